//! The embedded font: DejaVu Sans (its licence, a free one, in
//! `plot/fonts/DejaVuSans-LICENSE.txt`), registered with plotters once, so
//! no figure depends on the fonts installed on the machine.

use std::sync::Once;

use plotters::style::{FontDesc, FontFamily, FontStyle, RGBColor, TextStyle};

/// The font file, DejaVu Sans 2.37 (Debian's fonts-dejavu-core).
static DEJAVU_SANS: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// The family name the font is registered under (also the SVG's font-family).
const FAMILY: &str = "sans-serif";

/// Registers the embedded font with plotters (the first call only).
pub(crate) fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a font file checked in with the crate; a failure here is a
        // build defect, which `text_style`'s users would see as missing text.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, DEJAVU_SANS);
    });
}

/// plotters draws a font of size `s` as `s / 1.24` pixels (its points).
const PX_TO_SIZE: f64 = 1.24;

/// A text style of the embedded font: `size_px` pixels high (at scale 1,
/// times `scale`), in colour `color`.
pub(crate) fn text_style(size_px: f64, scale: f64, color: RGBColor) -> TextStyle<'static> {
    FontDesc::new(
        FontFamily::Name(FAMILY),
        size_px * scale * PX_TO_SIZE,
        FontStyle::Normal,
    )
    .color(&color)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_embedded_font_parses() {
        assert!(ab_glyph_parses(super::DEJAVU_SANS));
    }

    fn ab_glyph_parses(bytes: &'static [u8]) -> bool {
        plotters::style::register_font("test-font", plotters::style::FontStyle::Normal, bytes).is_ok()
    }
}

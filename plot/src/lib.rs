//! Small PNG line charts for leakwatch's figures.
//!
//! A [`Figure`] is a stack of [`Panel`]s sharing one x axis (time, usually).
//! Each panel has its own y axis, a legend, and any number of [`Series`]
//! (lines, dashed lines or points) and [`Marker`]s (vertical or horizontal
//! reference lines such as a leak onset or a threshold). Text is drawn with
//! an embedded 8x8 bitmap font, so nothing depends on the fonts installed on
//! the machine. Non-finite values break a line instead of being drawn.
//!
//! ```no_run
//! use plot::{Figure, Panel, Series, Style};
//! let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.01).collect();
//! let y: Vec<f64> = t.iter().map(|t| t.sin()).collect();
//! let mut fig = Figure::new("demo", "t [s]");
//! fig.panels.push(Panel::new("sine", "y [-]").with_series(Series::line("sin", &t, &y)));
//! plot::render_png(&fig, std::path::Path::new("demo.png")).unwrap();
//! ```

use std::fmt;
use std::path::{Path, PathBuf};

use font8x8::UnicodeFonts;

/// Width of a rendered figure in pixels.
pub const FIGURE_WIDTH_PX: usize = 1400;
/// Height of one panel in pixels (plot area plus its title and tick labels).
pub const PANEL_HEIGHT_PX: usize = 280;
/// Height of the figure's title band and of the x-axis label band, in pixels.
const TITLE_BAND_PX: usize = 40;
const XLABEL_BAND_PX: usize = 40;
const LEFT_MARGIN_PX: usize = 110;
const RIGHT_MARGIN_PX: usize = 30;
const PANEL_TOP_PAD_PX: usize = 26;
const PANEL_BOTTOM_PAD_PX: usize = 24;

/// An RGB colour.
pub type Rgb = [u8; 3];

/// The colours series get in order, unless they set their own.
pub const PALETTE: [Rgb; 8] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [23, 190, 207],
];

const WHITE: Rgb = [255, 255, 255];
const BLACK: Rgb = [0, 0, 0];
const GRID: Rgb = [225, 225, 225];
const MARKER: Rgb = [90, 90, 90];

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// A solid line through the points.
    Line,
    /// A dashed line through the points.
    Dashed,
    /// A small square at each point.
    Points,
}

/// One data series: y against x, in the units of its panel's axes.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Abscissae (same units as the figure's x label).
    pub x: Vec<f64>,
    /// Ordinates (same units as the panel's y label); non-finite values break the line.
    pub y: Vec<f64>,
    /// How to draw it.
    pub style: Style,
    /// Colour; `None` takes the next colour of [`PALETTE`].
    pub color: Option<Rgb>,
}

impl Series {
    /// A solid line series.
    pub fn line(label: &str, x: &[f64], y: &[f64]) -> Self {
        Series {
            label: label.to_string(),
            x: x.to_vec(),
            y: y.to_vec(),
            style: Style::Line,
            color: None,
        }
    }

    /// The same series drawn in another style.
    pub fn styled(mut self, style: Style) -> Self {
        self.style = style;
        self
    }

    /// The same series in a fixed colour.
    pub fn colored(mut self, color: Rgb) -> Self {
        self.color = Some(color);
        self
    }
}

/// A reference line across a panel.
#[derive(Debug, Clone, PartialEq)]
pub enum Marker {
    /// A vertical line at an x value (e.g. the leak onset time in s), with a label.
    Vertical {
        /// Position on the x axis.
        x: f64,
        /// Text drawn beside the line.
        label: String,
    },
    /// A horizontal line at a y value (e.g. a detection threshold), with a label.
    Horizontal {
        /// Position on the panel's y axis.
        y: f64,
        /// Text drawn beside the line.
        label: String,
    },
}

/// One panel: a y axis with its series.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Title drawn above the panel.
    pub title: String,
    /// y-axis label, with its unit (e.g. `p [MPa]`).
    pub y_label: String,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Reference lines.
    pub markers: Vec<Marker>,
}

impl Panel {
    /// An empty panel.
    pub fn new(title: &str, y_label: &str) -> Self {
        Panel {
            title: title.to_string(),
            y_label: y_label.to_string(),
            series: Vec::new(),
            markers: Vec::new(),
        }
    }

    /// The panel with one more series.
    pub fn with_series(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// The panel with one more reference line.
    pub fn with_marker(mut self, marker: Marker) -> Self {
        self.markers.push(marker);
        self
    }
}

/// A figure: panels stacked vertically on a shared x axis.
#[derive(Debug, Clone)]
pub struct Figure {
    /// Title at the top.
    pub title: String,
    /// Label of the shared x axis, with its unit (e.g. `t [s]`).
    pub x_label: String,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

impl Figure {
    /// An empty figure.
    pub fn new(title: &str, x_label: &str) -> Self {
        Figure {
            title: title.to_string(),
            x_label: x_label.to_string(),
            panels: Vec::new(),
        }
    }
}

/// Why a figure could not be drawn or written.
#[derive(Debug)]
pub enum PlotError {
    /// The figure has no panels, or no finite data at all.
    NothingToPlot,
    /// A series has different numbers of x and y values.
    LengthMismatch {
        /// The series' label.
        label: String,
        /// Number of x values.
        x_len: usize,
        /// Number of y values.
        y_len: usize,
    },
    /// The output file could not be written.
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The PNG encoder failed.
    Encode(String),
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlotError::NothingToPlot => write!(f, "nothing to plot: no panel holds finite data"),
            PlotError::LengthMismatch { label, x_len, y_len } => {
                write!(f, "series '{label}' has {x_len} x values but {y_len} y values")
            }
            PlotError::Io { path, source } => write!(f, "cannot write {}: {source}", path.display()),
            PlotError::Encode(e) => write!(f, "PNG encoding failed: {e}"),
        }
    }
}

impl std::error::Error for PlotError {}

/// An RGB raster image, row-major, 3 bytes per pixel.
#[derive(Debug, Clone)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, `3 * width * height` bytes.
    pub pixels: Vec<u8>,
}

impl Image {
    fn new(width: usize, height: usize) -> Self {
        Image {
            width,
            height,
            pixels: vec![255; 3 * width * height],
        }
    }

    /// The colour at pixel (x, y), `None` outside the image.
    pub fn pixel(&self, x: usize, y: usize) -> Option<Rgb> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 3 * (y * self.width + x);
        Some([self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]])
    }

    fn put(&mut self, x: i64, y: i64, c: Rgb) {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return;
        }
        let i = 3 * (y as usize * self.width + x as usize);
        self.pixels[i..i + 3].copy_from_slice(&c);
    }

    fn fill_rect(&mut self, x0: i64, y0: i64, w: i64, h: i64, c: Rgb) {
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                self.put(x, y, c);
            }
        }
    }

    /// Bresenham line, `thick` pixels wide, skipping pixels outside `clip`.
    fn line(&mut self, a: (i64, i64), b: (i64, i64), c: Rgb, thick: i64, clip: Rect, dash: Option<&mut u32>) {
        let (mut x0, mut y0) = a;
        let (x1, y1) = b;
        let dx = (x1 - x0).abs();
        let dy = -(y1 - y0).abs();
        let sx = if x0 < x1 { 1 } else { -1 };
        let sy = if y0 < y1 { 1 } else { -1 };
        let mut err = dx + dy;
        let mut dash = dash;
        loop {
            let on = match dash.as_deref_mut() {
                Some(n) => {
                    *n += 1;
                    (*n / 8) % 2 == 0
                }
                None => true,
            };
            if on {
                for ox in 0..thick {
                    for oy in 0..thick {
                        let (px, py) = (x0 + ox - thick / 2, y0 + oy - thick / 2);
                        if clip.contains(px, py) {
                            self.put(px, py, c);
                        }
                    }
                }
            }
            if x0 == x1 && y0 == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x0 += sx;
            }
            if e2 <= dx {
                err += dx;
                y0 += sy;
            }
        }
    }

    /// Draws text with its top-left corner at (x, y), `scale` pixels per font pixel.
    fn text(&mut self, x: i64, y: i64, s: &str, c: Rgb, scale: i64) {
        let mut cx = x;
        for ch in s.chars() {
            let glyph = font8x8::BASIC_FONTS
                .get(ch)
                .or_else(|| font8x8::LATIN_FONTS.get(ch))
                .unwrap_or([0; 8]);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits & (1 << col) != 0 {
                        self.fill_rect(cx + col * scale, y + row as i64 * scale, scale, scale, c);
                    }
                }
            }
            cx += 8 * scale;
        }
    }

    /// Draws text rotated 90° counter-clockwise, reading bottom to top, starting at (x, y) (bottom-left).
    fn text_vertical(&mut self, x: i64, y: i64, s: &str, c: Rgb) {
        let mut cy = y;
        for ch in s.chars() {
            let glyph = font8x8::BASIC_FONTS
                .get(ch)
                .or_else(|| font8x8::LATIN_FONTS.get(ch))
                .unwrap_or([0; 8]);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits & (1 << col) != 0 {
                        self.put(x + row as i64, cy - col, c);
                    }
                }
            }
            cy -= 8;
        }
    }
}

/// Width in pixels of `s` drawn at `scale`.
fn text_width(s: &str, scale: i64) -> i64 {
    s.chars().count() as i64 * 8 * scale
}

#[derive(Debug, Clone, Copy)]
struct Rect {
    x: i64,
    y: i64,
    w: i64,
    h: i64,
}

impl Rect {
    fn contains(&self, px: i64, py: i64) -> bool {
        px >= self.x && px < self.x + self.w && py >= self.y && py < self.y + self.h
    }
}

/// Round tick positions covering `[lo, hi]`: steps of 1, 2 or 5 times a power of ten,
/// about `target` of them.
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo || target == 0 {
        return Vec::new();
    }
    let raw = (hi - lo) / target as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Formats a tick value compactly for the given tick step.
fn format_tick(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    format!("{v:.decimals$}")
}

/// The finite range of a set of values, padded by 5 %; a flat range is widened.
fn padded_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return None;
    }
    if hi - lo <= 1e-12 * (lo.abs() + hi.abs()).max(1e-300) {
        let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return Some((lo - pad, hi + pad));
    }
    let pad = 0.05 * (hi - lo);
    Some((lo - pad, hi + pad))
}

/// Renders a figure to an RGB image.
pub fn render(fig: &Figure) -> Result<Image, PlotError> {
    for p in &fig.panels {
        for s in &p.series {
            if s.x.len() != s.y.len() {
                return Err(PlotError::LengthMismatch {
                    label: s.label.clone(),
                    x_len: s.x.len(),
                    y_len: s.y.len(),
                });
            }
        }
    }
    let xs = fig
        .panels
        .iter()
        .flat_map(|p| p.series.iter().flat_map(|s| s.x.iter().copied()));
    let (x_lo, x_hi) = match padded_range(xs) {
        Some((lo, hi)) => {
            // No padding on a time axis: use the exact data range.
            let pad = (hi - lo) / 1.1 * 0.05;
            (lo + pad, hi - pad)
        }
        None => return Err(PlotError::NothingToPlot),
    };
    let n = fig.panels.len();
    let width = FIGURE_WIDTH_PX;
    let height = TITLE_BAND_PX + n * PANEL_HEIGHT_PX + XLABEL_BAND_PX;
    let mut img = Image::new(width, height);
    let title_x = (width as i64 - text_width(&fig.title, 2)) / 2;
    img.text(title_x.max(4), 10, &fig.title, BLACK, 2);

    let plot_w = (width - LEFT_MARGIN_PX - RIGHT_MARGIN_PX) as i64;
    let x_ticks = nice_ticks(x_lo, x_hi, 10);
    let x_step = if x_ticks.len() > 1 {
        x_ticks[1] - x_ticks[0]
    } else {
        1.0
    };
    let to_px = |x: f64| LEFT_MARGIN_PX as f64 + (x - x_lo) / (x_hi - x_lo) * plot_w as f64;

    for (k, panel) in fig.panels.iter().enumerate() {
        let top = (TITLE_BAND_PX + k * PANEL_HEIGHT_PX + PANEL_TOP_PAD_PX) as i64;
        let plot_h = (PANEL_HEIGHT_PX - PANEL_TOP_PAD_PX - PANEL_BOTTOM_PAD_PX) as i64;
        let area = Rect {
            x: LEFT_MARGIN_PX as i64,
            y: top,
            w: plot_w,
            h: plot_h,
        };
        img.text(area.x, top - 18, &panel.title, BLACK, 1);
        let ys =
            panel
                .series
                .iter()
                .flat_map(|s| s.y.iter().copied())
                .chain(panel.markers.iter().filter_map(|m| match m {
                    Marker::Horizontal { y, .. } => Some(*y),
                    Marker::Vertical { .. } => None,
                }));
        let (y_lo, y_hi) = padded_range(ys).unwrap_or((0.0, 1.0));
        let to_py = |y: f64| (top + plot_h) as f64 - (y - y_lo) / (y_hi - y_lo) * plot_h as f64;
        // Grid and ticks.
        let y_ticks = nice_ticks(y_lo, y_hi, 5);
        let y_step = if y_ticks.len() > 1 {
            y_ticks[1] - y_ticks[0]
        } else {
            1.0
        };
        for &t in &y_ticks {
            let py = to_py(t).round() as i64;
            img.line((area.x, py), (area.x + area.w - 1, py), GRID, 1, area, None);
            let label = format_tick(t, y_step);
            img.text(area.x - 8 - text_width(&label, 1), py - 4, &label, BLACK, 1);
        }
        for &t in &x_ticks {
            let px = to_px(t).round() as i64;
            img.line((px, area.y), (px, area.y + area.h - 1), GRID, 1, area, None);
            let label = format_tick(t, x_step);
            img.text(
                px - text_width(&label, 1) / 2,
                area.y + area.h + 6,
                &label,
                BLACK,
                1,
            );
        }
        // y label, vertical, centred on the panel.
        let label_len = text_width(&panel.y_label, 1);
        img.text_vertical(8, area.y + area.h / 2 + label_len / 2, &panel.y_label, BLACK);
        // Frame.
        let frame = Rect {
            x: area.x - 1,
            y: area.y - 1,
            w: area.w + 2,
            h: area.h + 2,
        };
        let (l, r, t, b) = (frame.x, frame.x + frame.w - 1, frame.y, frame.y + frame.h - 1);
        for (a, z) in [
            ((l, t), (r, t)),
            ((l, b), (r, b)),
            ((l, t), (l, b)),
            ((r, t), (r, b)),
        ] {
            img.line(a, z, BLACK, 1, frame, None);
        }
        // Markers.
        for (mi, m) in panel.markers.iter().enumerate() {
            let label_dy = 12 * (mi as i64 % 4);
            let mut dash = 0u32;
            match m {
                Marker::Vertical { x, label } => {
                    let px = to_px(*x).round() as i64;
                    img.line(
                        (px, area.y),
                        (px, area.y + area.h - 1),
                        MARKER,
                        2,
                        area,
                        Some(&mut dash),
                    );
                    img.text(px + 4, area.y + 4 + label_dy, label, MARKER, 1);
                }
                Marker::Horizontal { y, label } => {
                    let py = to_py(*y).round() as i64;
                    img.line(
                        (area.x, py),
                        (area.x + area.w - 1, py),
                        MARKER,
                        2,
                        area,
                        Some(&mut dash),
                    );
                    img.text(area.x + 4, py - 11, label, MARKER, 1);
                }
            }
        }
        // Series.
        for (i, s) in panel.series.iter().enumerate() {
            let color = s.color.unwrap_or(PALETTE[i % PALETTE.len()]);
            let mut dash = 0u32;
            let mut prev: Option<(i64, i64)> = None;
            for (&x, &y) in s.x.iter().zip(&s.y) {
                if !(x.is_finite() && y.is_finite()) {
                    prev = None;
                    continue;
                }
                let p = (to_px(x).round() as i64, to_py(y).round() as i64);
                match s.style {
                    Style::Points => img.fill_rect(p.0 - 1, p.1 - 1, 3, 3, color),
                    Style::Line | Style::Dashed => {
                        if let Some(q) = prev {
                            if q != p {
                                let d = if s.style == Style::Dashed {
                                    Some(&mut dash)
                                } else {
                                    None
                                };
                                img.line(q, p, color, 2, area, d);
                            }
                        } else {
                            img.line(p, p, color, 2, area, None);
                        }
                    }
                }
                prev = Some(p);
            }
        }
        // Legend, top right.
        let legend_w = panel
            .series
            .iter()
            .map(|s| text_width(&s.label, 1))
            .max()
            .unwrap_or(0)
            + 34;
        let lx = area.x + area.w - legend_w - 8;
        if !panel.series.is_empty() {
            img.fill_rect(
                lx - 4,
                area.y + 4,
                legend_w + 4,
                14 * panel.series.len() as i64 + 6,
                WHITE,
            );
        }
        for (i, s) in panel.series.iter().enumerate() {
            let color = s.color.unwrap_or(PALETTE[i % PALETTE.len()]);
            let ly = area.y + 10 + 14 * i as i64;
            img.fill_rect(lx, ly + 2, 22, 3, color);
            img.text(lx + 28, ly, &s.label, BLACK, 1);
        }
    }
    let xl = &fig.x_label;
    let last_panel_bottom = (TITLE_BAND_PX + n * PANEL_HEIGHT_PX) as i64;
    img.text(
        LEFT_MARGIN_PX as i64 + (plot_w - text_width(xl, 1)) / 2,
        last_panel_bottom + 14,
        xl,
        BLACK,
        1,
    );
    Ok(img)
}

/// Encodes an image as PNG bytes.
pub fn encode_png(img: &Image) -> Result<Vec<u8>, PlotError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, img.width as u32, img.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(|e| PlotError::Encode(e.to_string()))?;
        w.write_image_data(&img.pixels)
            .map_err(|e| PlotError::Encode(e.to_string()))?;
    }
    Ok(out)
}

/// Renders a figure and writes it as a PNG file.
pub fn render_png(fig: &Figure, path: &Path) -> Result<(), PlotError> {
    let bytes = encode_png(&render(fig)?)?;
    std::fs::write(path, bytes).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn demo() -> Figure {
        let t: Vec<f64> = (0..=1000).map(|i| i as f64 * 0.01).collect();
        let y: Vec<f64> = t.iter().map(|t| (t * 2.0).sin()).collect();
        let mut fig = Figure::new("demo", "t [s]");
        fig.panels
            .push(Panel::new("a", "y [-]").with_series(Series::line("sin", &t, &y)));
        fig.panels.push(
            Panel::new("b", "z [-]")
                .with_series(Series::line("flat", &t, &vec![2.0; t.len()]).colored([0, 200, 0]))
                .with_marker(Marker::Vertical {
                    x: 5.0,
                    label: "onset".into(),
                }),
        );
        fig
    }

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        let t = nice_ticks(0.0, 1.0, 5);
        let want = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0];
        assert_eq!(t.len(), want.len());
        assert!(t.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12), "{t:?}");
        // 50.3 / 10 = 5.03 per tick rounds up to a step of 10.
        assert_eq!(nice_ticks(-3.3, 47.0, 10), vec![0.0, 10.0, 20.0, 30.0, 40.0]);
        assert_eq!(
            nice_ticks(-3.3, 47.0, 20),
            vec![0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0]
        );
        assert!(nice_ticks(1.0, 1.0, 5).is_empty());
        assert!(nice_ticks(f64::NAN, 1.0, 5).is_empty());
    }

    #[test]
    fn image_has_the_documented_size_and_draws_the_series() {
        let img = render(&demo()).unwrap();
        assert_eq!(img.width, FIGURE_WIDTH_PX);
        assert_eq!(img.height, TITLE_BAND_PX + 2 * PANEL_HEIGHT_PX + XLABEL_BAND_PX);
        // The flat green line of panel 2 sits mid-height of its plot area.
        let top = TITLE_BAND_PX + PANEL_HEIGHT_PX + PANEL_TOP_PAD_PX;
        let plot_h = PANEL_HEIGHT_PX - PANEL_TOP_PAD_PX - PANEL_BOTTOM_PAD_PX;
        let mid = top + plot_h / 2;
        let x = LEFT_MARGIN_PX + 50;
        let hits = (mid - 2..=mid + 2)
            .filter(|&y| img.pixel(x, y) == Some([0, 200, 0]))
            .count();
        assert!(hits >= 1, "flat line not found near row {mid}");
    }

    #[test]
    fn png_round_trips_through_the_decoder() {
        let img = render(&demo()).unwrap();
        let bytes = encode_png(&img).unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(
            (info.width as usize, info.height as usize),
            (img.width, img.height)
        );
        assert_eq!(&buf[..info.buffer_size()], &img.pixels[..]);
    }

    #[test]
    fn bad_figures_are_reported() {
        assert!(matches!(
            render(&Figure::new("x", "t")),
            Err(PlotError::NothingToPlot)
        ));
        let mut fig = Figure::new("x", "t");
        fig.panels
            .push(Panel::new("p", "y").with_series(Series::line("s", &[1.0, 2.0], &[1.0])));
        let e = render(&fig).unwrap_err();
        assert!(e.to_string().contains("'s' has 2 x values but 1 y values"), "{e}");
        let mut fig = Figure::new("x", "t");
        fig.panels.push(Panel::new("p", "y").with_series(Series::line(
            "s",
            &[1.0, 2.0],
            &[f64::NAN, f64::NAN],
        )));
        assert!(render(&fig).is_ok(), "all-NaN y still draws the axes");
    }
}

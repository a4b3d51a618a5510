//! Drawing a [`Figure`] onto an [`Image`]: the layout of the panels, the axes
//! and their ticks, the series, markers and legends.

use crate::raster::{text_width, Rect};
use crate::{
    Figure, Image, Marker, PlotError, Style, BLACK, FIGURE_WIDTH_PX, GRID, LEFT_MARGIN_PX, MARKER, PALETTE,
    PANEL_BOTTOM_PAD_PX, PANEL_HEIGHT_PX, PANEL_TOP_PAD_PX, RIGHT_MARGIN_PX, TITLE_BAND_PX, WHITE,
    XLABEL_BAND_PX,
};

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

//! Drawing a [`Figure`] onto an [`Image`]: the layout of the panels, the axes
//! and their ticks, the series, markers and legends.

use crate::raster::{text_width, Rect};
use crate::{
    Figure, Image, Marker, Panel, PlotError, Rgb, Series, Style, BLACK, FIGURE_WIDTH_PX, GRID,
    LEFT_MARGIN_PX, MARKER, PALETTE, PANEL_BOTTOM_PAD_PX, PANEL_HEIGHT_PX, PANEL_TOP_PAD_PX, RIGHT_MARGIN_PX,
    TITLE_BAND_PX, WHITE, XLABEL_BAND_PX,
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

/// The distance between the first two ticks, or 1 when there are fewer than two.
fn tick_step(ticks: &[f64]) -> f64 {
    if ticks.len() > 1 {
        ticks[1] - ticks[0]
    } else {
        1.0
    }
}

/// The x axis all panels share: its range, its ticks and the plot areas' width.
struct XAxis {
    /// Left end of the range (the data's first x).
    lo: f64,
    /// Right end of the range (the data's last x).
    hi: f64,
    /// Tick positions.
    ticks: Vec<f64>,
    /// Distance between ticks (for their labels' decimals).
    step: f64,
    /// Width of a plot area in pixels.
    plot_w: i64,
}

impl XAxis {
    /// The pixel column of `x` (unrounded).
    fn px(&self, x: f64) -> f64 {
        LEFT_MARGIN_PX as f64 + (x - self.lo) / (self.hi - self.lo) * self.plot_w as f64
    }
}

/// A panel's plot area and its y range: where its values land.
struct PanelArea {
    /// The plot area, inside the frame.
    area: Rect,
    /// Bottom of the y range.
    y_lo: f64,
    /// Top of the y range.
    y_hi: f64,
}

impl PanelArea {
    /// The pixel row of `y` (unrounded).
    fn py(&self, y: f64) -> f64 {
        (self.area.y + self.area.h) as f64 - (y - self.y_lo) / (self.y_hi - self.y_lo) * self.area.h as f64
    }
}

/// Renders a figure to an RGB image.
pub fn render(fig: &Figure) -> Result<Image, PlotError> {
    check_lengths(fig)?;
    let x = x_axis(fig)?;
    let n = fig.panels.len();
    let mut img = Image::new(
        FIGURE_WIDTH_PX,
        TITLE_BAND_PX + n * PANEL_HEIGHT_PX + XLABEL_BAND_PX,
    );
    draw_title(&mut img, &fig.title);
    for (k, panel) in fig.panels.iter().enumerate() {
        draw_panel(&mut img, panel, k, &x);
    }
    draw_x_label(&mut img, &fig.x_label, n, x.plot_w);
    Ok(img)
}

/// The first series, in panel order, whose x and y differ in length, as an error.
fn check_lengths(fig: &Figure) -> Result<(), PlotError> {
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
    Ok(())
}

/// The shared x axis: the exact range of all series' x, and its ticks.
fn x_axis(fig: &Figure) -> Result<XAxis, PlotError> {
    let xs = fig
        .panels
        .iter()
        .flat_map(|p| p.series.iter().flat_map(|s| s.x.iter().copied()));
    let (lo, hi) = match padded_range(xs) {
        Some((lo, hi)) => {
            // No padding on a time axis: use the exact data range.
            let pad = (hi - lo) / 1.1 * 0.05;
            (lo + pad, hi - pad)
        }
        None => return Err(PlotError::NothingToPlot),
    };
    let ticks = nice_ticks(lo, hi, 10);
    Ok(XAxis {
        lo,
        hi,
        step: tick_step(&ticks),
        ticks,
        plot_w: (FIGURE_WIDTH_PX - LEFT_MARGIN_PX - RIGHT_MARGIN_PX) as i64,
    })
}

/// The figure's title, centred in the title band.
fn draw_title(img: &mut Image, title: &str) {
    let title_x = (FIGURE_WIDTH_PX as i64 - text_width(title, 2)) / 2;
    img.text(title_x.max(4), 10, title, BLACK, 2);
}

/// Panel `k`: its title, grid and ticks, y label, frame, markers, series and legend.
fn draw_panel(img: &mut Image, panel: &Panel, k: usize, x: &XAxis) {
    let pa = panel_area(panel, k, x.plot_w);
    img.text(pa.area.x, pa.area.y - 18, &panel.title, BLACK, 1);
    draw_grid(img, &pa, x);
    draw_y_label(img, pa.area, &panel.y_label);
    draw_frame(img, pa.area);
    draw_markers(img, &panel.markers, &pa, x);
    for (i, s) in panel.series.iter().enumerate() {
        match s.style {
            Style::Points => draw_points(img, s, series_color(i, s), &pa, x),
            Style::Line | Style::Dashed => draw_line(img, s, series_color(i, s), &pa, x),
        }
    }
    draw_legend(img, &panel.series, pa.area);
}

/// Panel `k`'s plot area, and its y range: its series' y and its horizontal
/// markers, padded (0 to 1 when it has none).
fn panel_area(panel: &Panel, k: usize, plot_w: i64) -> PanelArea {
    let area = Rect {
        x: LEFT_MARGIN_PX as i64,
        y: (TITLE_BAND_PX + k * PANEL_HEIGHT_PX + PANEL_TOP_PAD_PX) as i64,
        w: plot_w,
        h: (PANEL_HEIGHT_PX - PANEL_TOP_PAD_PX - PANEL_BOTTOM_PAD_PX) as i64,
    };
    let ys = panel
        .series
        .iter()
        .flat_map(|s| s.y.iter().copied())
        .chain(panel.markers.iter().filter_map(|m| match m {
            Marker::Horizontal { y, .. } => Some(*y),
            Marker::Vertical { .. } => None,
        }));
    let (y_lo, y_hi) = padded_range(ys).unwrap_or((0.0, 1.0));
    PanelArea { area, y_lo, y_hi }
}

/// The grid lines and tick labels: the y ticks' on the left, then the x ticks' below.
fn draw_grid(img: &mut Image, pa: &PanelArea, x: &XAxis) {
    let area = pa.area;
    let y_ticks = nice_ticks(pa.y_lo, pa.y_hi, 5);
    let y_step = tick_step(&y_ticks);
    for &t in &y_ticks {
        let py = pa.py(t).round() as i64;
        img.line((area.x, py), (area.x + area.w - 1, py), GRID, 1, area, None);
        let label = format_tick(t, y_step);
        img.text(area.x - 8 - text_width(&label, 1), py - 4, &label, BLACK, 1);
    }
    for &t in &x.ticks {
        let px = x.px(t).round() as i64;
        img.line((px, area.y), (px, area.y + area.h - 1), GRID, 1, area, None);
        let label = format_tick(t, x.step);
        img.text(
            px - text_width(&label, 1) / 2,
            area.y + area.h + 6,
            &label,
            BLACK,
            1,
        );
    }
}

/// The y label, vertical, centred on the panel.
fn draw_y_label(img: &mut Image, area: Rect, label: &str) {
    let label_len = text_width(label, 1);
    img.text_vertical(8, area.y + area.h / 2 + label_len / 2, label, BLACK);
}

/// The frame: a black line one pixel outside each side of the plot area.
fn draw_frame(img: &mut Image, area: Rect) {
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
}

/// The markers: dashed vertical or horizontal lines, each with its label.
fn draw_markers(img: &mut Image, markers: &[Marker], pa: &PanelArea, x: &XAxis) {
    let area = pa.area;
    for (mi, m) in markers.iter().enumerate() {
        let label_dy = 12 * (mi as i64 % 4);
        let mut dash = 0u32;
        match m {
            Marker::Vertical { x: mx, label } => {
                let px = x.px(*mx).round() as i64;
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
                let py = pa.py(*y).round() as i64;
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
}

/// The colour of series `i` of a panel: its own, else the palette's `i`-th.
fn series_color(i: usize, s: &Series) -> Rgb {
    s.color.unwrap_or(PALETTE[i % PALETTE.len()])
}

/// A series' points in pixels, in order; `None` for a point with a value that is not finite.
fn pixels<'a>(
    s: &'a Series,
    pa: &'a PanelArea,
    x: &'a XAxis,
) -> impl Iterator<Item = Option<(i64, i64)>> + 'a {
    s.x.iter().zip(&s.y).map(|(&px, &py)| {
        (px.is_finite() && py.is_finite()).then(|| (x.px(px).round() as i64, pa.py(py).round() as i64))
    })
}

/// A `Style::Points` series: a 3×3 square per finite point.
fn draw_points(img: &mut Image, s: &Series, color: Rgb, pa: &PanelArea, x: &XAxis) {
    for p in pixels(s, pa, x).flatten() {
        img.fill_rect(p.0 - 1, p.1 - 1, 3, 3, color);
    }
}

/// A `Style::Line` or `Style::Dashed` series: segments between consecutive finite
/// points (a dot where a run starts), broken where a value is not finite.
fn draw_line(img: &mut Image, s: &Series, color: Rgb, pa: &PanelArea, x: &XAxis) {
    let mut dash = 0u32;
    let mut prev: Option<(i64, i64)> = None;
    for p in pixels(s, pa, x) {
        let Some(p) = p else {
            prev = None;
            continue;
        };
        if let Some(q) = prev {
            if q != p {
                let d = if s.style == Style::Dashed {
                    Some(&mut dash)
                } else {
                    None
                };
                img.line(q, p, color, 2, pa.area, d);
            }
        } else {
            img.line(p, p, color, 2, pa.area, None);
        }
        prev = Some(p);
    }
}

/// The legend, top right: a white box with each series' colour and label.
fn draw_legend(img: &mut Image, series: &[Series], area: Rect) {
    let legend_w = series.iter().map(|s| text_width(&s.label, 1)).max().unwrap_or(0) + 34;
    let lx = area.x + area.w - legend_w - 8;
    if !series.is_empty() {
        img.fill_rect(
            lx - 4,
            area.y + 4,
            legend_w + 4,
            14 * series.len() as i64 + 6,
            WHITE,
        );
    }
    for (i, s) in series.iter().enumerate() {
        let ly = area.y + 10 + 14 * i as i64;
        img.fill_rect(lx, ly + 2, 22, 3, series_color(i, s));
        img.text(lx + 28, ly, &s.label, BLACK, 1);
    }
}

/// The x label, centred under the last panel.
fn draw_x_label(img: &mut Image, label: &str, n: usize, plot_w: i64) {
    let last_panel_bottom = (TITLE_BAND_PX + n * PANEL_HEIGHT_PX) as i64;
    img.text(
        LEFT_MARGIN_PX as i64 + (plot_w - text_width(label, 1)) / 2,
        last_panel_bottom + 14,
        label,
        BLACK,
        1,
    );
}

//! Drawing a [`Figure`] with plotters on any of its backends (bitmap, SVG):
//! the title, one chart per panel (axes, ticks, grid), the series (long ones
//! as per-pixel-column envelopes), the markers and shaded spans with labels
//! that never overlap, and each panel's legend in a column beside it.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::font::text_style;
use crate::layout::{self, Anchor, LabelBox, Piece};
use crate::{
    Figure, Marker, Panel, PlotError, Rgb, Series, Style, FIGURE_WIDTH_PX, LEFT_MARGIN_PX, LEGEND_WIDTH_PX,
    PALETTE, PANEL_HEIGHT_PX, TITLE_BAND_PX, Y_DESC_PAD_PX,
};

type Area<DB> = DrawingArea<DB, Shift>;
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

const GRID: RGBColor = RGBColor(225, 225, 225);
const MARKER: RGBColor = RGBColor(70, 70, 70);
const SPAN: RGBColor = RGBColor(150, 150, 150);

/// A drawing error as a [`PlotError`].
fn err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// `v` pixels at scale 1 in pixels at scale `s`.
fn px(s: f64, v: f64) -> i32 {
    (v * s).round() as i32
}

fn rgb(c: Rgb) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Draws `fig` on `root`, whose size is the figure's at scale `s` (2 for a
/// bitmap drawn twice as large and reduced, 1 for SVG).
pub(crate) fn draw<DB: DrawingBackend>(fig: &Figure, root: &Area<DB>, s: f64) -> Result<(), PlotError> {
    crate::font::register();
    let x = layout::x_range(fig)?;
    root.fill(&WHITE).map_err(err)?;
    let (title, rest) = root.split_vertically(px(s, TITLE_BAND_PX as f64));
    let n = fig.panels.len();
    let (panels, x_label) = rest.split_vertically(px(s, (n * PANEL_HEIGHT_PX) as f64));
    centred_text(&title, &fig.title, 20.0, s)?;
    for (panel, area) in fig.panels.iter().zip(panels.split_evenly((n, 1))) {
        draw_panel(panel, &area, x, s)?;
    }
    let x_label = x_label.margin(0, 0, px(s, LEFT_MARGIN_PX as f64), px(s, LEGEND_WIDTH_PX as f64));
    centred_text(&x_label, &fig.x_label, 15.0, s)
}

/// `text` centred on `area`, `size` pixels high at scale 1.
fn centred_text<DB: DrawingBackend>(area: &Area<DB>, text: &str, size: f64, s: f64) -> Result<(), PlotError> {
    let (w, h) = area.dim_in_pixel();
    let style = text_style(size, s, BLACK).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new(text.to_string(), (w as i32 / 2, h as i32 / 2), style))
        .map_err(err)
}

/// One panel: its chart (title, axes, grid, y label), spans, markers, series,
/// the markers' labels, and its legend to the right.
fn draw_panel<DB: DrawingBackend>(
    panel: &Panel,
    area: &Area<DB>,
    (x_lo, x_hi): (f64, f64),
    s: f64,
) -> Result<(), PlotError> {
    let (y_lo, y_hi) = layout::y_range(panel);
    let (plot, legend) = area.split_horizontally(px(s, (FIGURE_WIDTH_PX - LEGEND_WIDTH_PX) as f64));
    let mut chart = ChartBuilder::on(&plot)
        .caption(&panel.title, text_style(15.0, s, BLACK))
        .margin_top(px(s, 2.0))
        .margin_left(px(s, Y_DESC_PAD_PX as f64))
        .margin_right(px(s, 8.0))
        .x_label_area_size(px(s, 24.0))
        .y_label_area_size(px(s, LEFT_MARGIN_PX as f64))
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)
        .map_err(err)?;
    chart
        .configure_mesh()
        .bold_line_style(GRID.stroke_width(px(s, 1.0) as u32))
        .light_line_style(TRANSPARENT)
        .axis_style(BLACK.stroke_width(px(s, 1.0) as u32))
        .x_labels(10)
        .y_labels(6)
        .label_style(text_style(13.0, s, BLACK))
        .axis_desc_style(text_style(14.0, s, BLACK))
        .y_desc(&panel.y_label)
        .draw()
        .map_err(err)?;
    draw_spans_and_lines(&mut chart, panel, s)?;
    let columns = chart.plotting_area().dim_in_pixel().0 as usize;
    let columns = (columns as f64 / s).round().max(1.0) as usize;
    for (i, series) in panel.series.iter().enumerate() {
        draw_series(
            &mut chart,
            series,
            series_color(i, series),
            columns,
            (x_lo, x_hi),
            s,
        )?;
    }
    draw_labels(&chart, panel, s)?;
    let top = chart.plotting_area().get_pixel_range().1.start - area.get_pixel_range().1.start;
    draw_legend(&legend, &panel.series, top, s)
}

/// The colour of series `i` of a panel: its own, else the palette's `i`-th.
fn series_color(i: usize, s: &Series) -> RGBColor {
    rgb(s.color.unwrap_or(PALETTE[i % PALETTE.len()]))
}

/// The shaded spans, then the markers' dashed lines (their labels come last).
fn draw_spans_and_lines<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    panel: &Panel,
    s: f64,
) -> Result<(), PlotError> {
    let (x_r, y_r) = (chart.x_range(), chart.y_range());
    let dash = |a: (f64, f64), b: (f64, f64)| {
        DashedLineSeries::new(
            [a, b],
            px(s, 6.0),
            px(s, 4.0),
            MARKER.stroke_width(px(s, 1.5) as u32),
        )
    };
    for m in &panel.markers {
        if let Marker::Span { x_from, x_to, .. } = m {
            let r = Rectangle::new([(*x_from, y_r.start), (*x_to, y_r.end)], SPAN.mix(0.22).filled());
            chart.plotting_area().draw(&r).map_err(err)?;
        }
    }
    for m in &panel.markers {
        match m {
            Marker::Vertical { x, .. } => chart
                .draw_series(dash((*x, y_r.start), (*x, y_r.end)))
                .map_err(err)?,
            Marker::Horizontal { y, .. } => chart
                .draw_series(dash((x_r.start, *y), (x_r.end, *y)))
                .map_err(err)?,
            Marker::Span { .. } => continue,
        };
    }
    Ok(())
}

/// A series: its runs as lines (solid or dashed) or points, its dense stretches
/// as envelopes (the per-column min..max shaded, the mean drawn as its line).
fn draw_series<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    series: &Series,
    color: RGBColor,
    columns: usize,
    (lo, hi): (f64, f64),
    s: f64,
) -> Result<(), PlotError> {
    let line = color.stroke_width(px(s, 1.5).max(1) as u32);
    for piece in layout::pieces(&series.x, &series.y, lo, hi, columns) {
        let points = match piece {
            Piece::Run(points) => points,
            Piece::Envelope(cols) => {
                let outline: Vec<(f64, f64)> = cols
                    .iter()
                    .map(|c| (c.x, c.max))
                    .chain(cols.iter().rev().map(|c| (c.x, c.min)))
                    .collect();
                chart
                    .plotting_area()
                    .draw(&Polygon::new(outline, color.mix(0.3).filled()))
                    .map_err(err)?;
                if series.style == Style::Points {
                    continue;
                }
                cols.iter().map(|c| (c.x, c.mean)).collect()
            }
        };
        match series.style {
            Style::Line => chart.draw_series(LineSeries::new(points, line)).map(|_| ()),
            Style::Dashed => chart
                .draw_series(DashedLineSeries::new(points, px(s, 7.0), px(s, 5.0), line))
                .map(|_| ()),
            Style::Points => chart
                .draw_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, px(s, 2.0), color.filled())),
                )
                .map(|_| ()),
        }
        .map_err(err)?;
    }
    Ok(())
}

/// The markers' and spans' labels, each placed where it overlaps no other,
/// on a white box so that no curve hides it.
fn draw_labels<DB: DrawingBackend>(chart: &Chart<DB>, panel: &Panel, s: f64) -> Result<(), PlotError> {
    let area = chart.plotting_area();
    let (w, h) = area.dim_in_pixel();
    let (base_x, base_y) = (area.get_pixel_range().0.start, area.get_pixel_range().1.start);
    let style = text_style(12.0, s, MARKER);
    let mut placed: Vec<LabelBox> = Vec::new();
    let (x_r, y_r) = (chart.x_range(), chart.y_range());
    for m in &panel.markers {
        let (anchor, label) = match m {
            Marker::Vertical { x, label } => (
                Anchor::Vertical(chart.backend_coord(&(*x, y_r.start)).0 - base_x),
                label,
            ),
            Marker::Span { x_from, label, .. } => (
                Anchor::Vertical(chart.backend_coord(&(*x_from, y_r.start)).0 - base_x),
                label,
            ),
            Marker::Horizontal { y, label } => (
                Anchor::Horizontal(chart.backend_coord(&(x_r.start, *y)).1 - base_y),
                label,
            ),
        };
        if label.is_empty() {
            continue;
        }
        let (tw, th) = area.estimate_text_size(label, &style).map_err(err)?;
        let b = layout::place(
            anchor,
            (tw as i32 + px(s, 6.0), th as i32 + px(s, 4.0)),
            &placed,
            (w as i32, h as i32),
            px(s, 3.0),
        );
        placed.push(b);
        let at = EmptyElement::at((x_r.start, y_r.end))
            + Rectangle::new([(b.x, b.y), (b.x + b.w, b.y + b.h)], WHITE.mix(0.85).filled())
            + Text::new(label.clone(), (b.x + px(s, 3.0), b.y + px(s, 2.0)), style.clone());
        area.draw(&at).map_err(err)?;
    }
    Ok(())
}

/// The legend in the column right of the plot: each labelled series' line
/// (or dot) and its label, from `top` pixels below the panel's top.
fn draw_legend<DB: DrawingBackend>(
    area: &Area<DB>,
    series: &[Series],
    top: i32,
    s: f64,
) -> Result<(), PlotError> {
    let style = text_style(13.0, s, BLACK).pos(Pos::new(HPos::Left, VPos::Center));
    let row = px(s, 19.0);
    let mut y = top + px(s, 8.0);
    for (i, ser) in series.iter().enumerate().filter(|(_, ser)| !ser.label.is_empty()) {
        let color = series_color(i, ser);
        let (a, b) = ((px(s, 4.0), y), (px(s, 28.0), y));
        let line = color.stroke_width(px(s, 2.0) as u32);
        match ser.style {
            Style::Line => area.draw(&PathElement::new(vec![a, b], line)),
            Style::Dashed => area.draw(&DashedPathElement::new(vec![a, b], px(s, 6.0), px(s, 3.0), line)),
            Style::Points => area.draw(&Circle::new((px(s, 16.0), y), px(s, 3.0), color.filled())),
        }
        .map_err(err)?;
        area.draw(&Text::new(ser.label.clone(), (px(s, 34.0), y), style.clone()))
            .map_err(err)?;
        y += row;
    }
    Ok(())
}

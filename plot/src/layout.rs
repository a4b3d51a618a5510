//! The geometry of a figure, apart from drawing: the axes' ranges, the
//! decimation of long series into per-pixel-column envelopes, and the
//! placement of marker labels so that no two overlap.

use crate::{Figure, Marker, Panel, PlotError};

/// The finite range of a set of values, padded by 5 %; a flat range is widened.
pub(crate) fn padded_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = finite_range(values)?;
    if hi - lo <= 1e-12 * (lo.abs() + hi.abs()).max(1e-300) {
        let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return Some((lo - pad, hi + pad));
    }
    let pad = 0.05 * (hi - lo);
    Some((lo - pad, hi + pad))
}

/// The smallest and largest finite value, `None` when there is none.
fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    lo.is_finite().then_some((lo, hi))
}

/// The shared x range: the exact range of all series' finite x (a single
/// value widened by 1 either side), or [`PlotError::NothingToPlot`].
pub(crate) fn x_range(fig: &Figure) -> Result<(f64, f64), PlotError> {
    let xs = fig
        .panels
        .iter()
        .flat_map(|p| p.series.iter().flat_map(|s| s.x.iter().copied()));
    match finite_range(xs) {
        Some((lo, hi)) if hi > lo => Ok((lo, hi)),
        Some((lo, _)) => Ok((lo - 1.0, lo + 1.0)),
        None => Err(PlotError::NothingToPlot),
    }
}

/// A panel's y range: its series' y and its horizontal markers, padded by 5 %
/// (0 to 1 when it has none).
pub(crate) fn y_range(panel: &Panel) -> (f64, f64) {
    let ys = panel
        .series
        .iter()
        .flat_map(|s| s.y.iter().copied())
        .chain(panel.markers.iter().filter_map(|m| match m {
            Marker::Horizontal { y, .. } => Some(*y),
            _ => None,
        }));
    padded_range(ys).unwrap_or((0.0, 1.0))
}

/// What a series becomes on a plot area of a given width.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Piece {
    /// A run of consecutive finite points, drawn as they are.
    Run(Vec<(f64, f64)>),
    /// A run of pixel columns holding more points than can be seen: each
    /// column's x (its centre) with its smallest, mean and largest y.
    Envelope(Vec<Column>),
}

/// One pixel column of an [`Piece::Envelope`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Column {
    /// The column's centre on the x axis.
    pub x: f64,
    /// The smallest y in the column.
    pub min: f64,
    /// The mean y in the column.
    pub mean: f64,
    /// The largest y in the column.
    pub max: f64,
}

/// A series cut into pieces for a plot area `columns` pixels wide showing x in
/// `[lo, hi]`: runs of finite points as they are when the series has at most
/// two finite points per column, else per-column min/mean/max envelopes (runs
/// of columns that hold points; an empty column breaks the run).
pub(crate) fn pieces(x: &[f64], y: &[f64], lo: f64, hi: f64, columns: usize) -> Vec<Piece> {
    let finite = |i: usize| x[i].is_finite() && y[i].is_finite();
    let n = (0..x.len().min(y.len())).filter(|&i| finite(i)).count();
    if n <= 2 * columns.max(1) || hi <= lo {
        let mut out = Vec::new();
        let mut run = Vec::new();
        for i in 0..x.len().min(y.len()) {
            if finite(i) {
                run.push((x[i], y[i]));
            } else if !run.is_empty() {
                out.push(Piece::Run(std::mem::take(&mut run)));
            }
        }
        if !run.is_empty() {
            out.push(Piece::Run(run));
        }
        return out;
    }
    let width = (hi - lo) / columns as f64;
    // (min, sum, max, count) per column
    let mut acc = vec![(f64::INFINITY, 0.0, f64::NEG_INFINITY, 0usize); columns];
    for i in (0..x.len().min(y.len())).filter(|&i| finite(i)) {
        let c = (((x[i] - lo) / width).floor().max(0.0) as usize).min(columns - 1);
        let a = &mut acc[c];
        *a = (a.0.min(y[i]), a.1 + y[i], a.2.max(y[i]), a.3 + 1);
    }
    let mut out = Vec::new();
    let mut run = Vec::new();
    for (c, &(min, sum, max, count)) in acc.iter().enumerate() {
        if count == 0 {
            if !run.is_empty() {
                out.push(Piece::Envelope(std::mem::take(&mut run)));
            }
            continue;
        }
        run.push(Column {
            x: lo + (c as f64 + 0.5) * width,
            min,
            mean: sum / count as f64,
            max,
        });
    }
    if !run.is_empty() {
        out.push(Piece::Envelope(run));
    }
    out
}

/// A label's box in pixels, from the plot area's top-left corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LabelBox {
    /// Left edge.
    pub x: i32,
    /// Top edge.
    pub y: i32,
    /// Width.
    pub w: i32,
    /// Height.
    pub h: i32,
}

impl LabelBox {
    /// Whether two boxes come closer than `gap` pixels.
    fn overlaps(&self, o: &LabelBox, gap: i32) -> bool {
        self.x < o.x + o.w + gap
            && o.x < self.x + self.w + gap
            && self.y < o.y + o.h + gap
            && o.y < self.y + self.h + gap
    }
}

/// Where a label belongs: beside a vertical line at pixel column `x`, or above
/// a horizontal line at pixel row `y`.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Anchor {
    /// Beside a vertical line (stacked downwards from the top).
    Vertical(i32),
    /// Above (or else below) a horizontal line (moved rightwards).
    Horizontal(i32),
}

/// The box of a `w`×`h` label for `anchor` on a `area_w`×`area_h` plot area that
/// overlaps none of `placed` (kept `pad` pixels apart): the first free row
/// beside a vertical line (right of it, or left when it would leave the area),
/// the first free place along a horizontal line.
pub(crate) fn place(
    anchor: Anchor,
    (w, h): (i32, i32),
    placed: &[LabelBox],
    (area_w, area_h): (i32, i32),
    pad: i32,
) -> LabelBox {
    let free = |b: &LabelBox| !placed.iter().any(|p| p.overlaps(b, pad));
    let step = (h + pad).max(1);
    match anchor {
        Anchor::Vertical(px) => {
            let x = if px + pad + w <= area_w {
                px + pad
            } else {
                (px - pad - w).max(0)
            };
            (0..)
                .map(|row| LabelBox {
                    x,
                    y: pad + row * step,
                    w,
                    h,
                })
                .find(|b| free(b) || b.y > area_h.max(0) * 4)
                .unwrap_or(LabelBox { x, y: pad, w, h })
        }
        Anchor::Horizontal(py) => {
            let rows = [py - pad - h, py + pad];
            let xs = (0..)
                .map(|k| pad + k * step)
                .take_while(|x| *x + w <= area_w.max(w + pad));
            let candidates: Vec<LabelBox> = rows
                .iter()
                .flat_map(|&y| xs.clone().map(move |x| LabelBox { x, y, w, h }))
                .collect();
            candidates.iter().copied().find(|b| free(b)).unwrap_or_else(|| {
                // everything along the line taken: stack below the lowest label
                let below = placed.iter().map(|p| p.y + p.h).max().unwrap_or(0) + pad;
                LabelBox {
                    x: pad,
                    y: below,
                    w,
                    h,
                }
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sparse_series_stays_as_it_is_and_breaks_at_nan() {
        let x = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [1.0, 2.0, f64::NAN, 4.0, 5.0];
        let p = pieces(&x, &y, 0.0, 4.0, 100);
        assert_eq!(
            p,
            vec![
                Piece::Run(vec![(0.0, 1.0), (1.0, 2.0)]),
                Piece::Run(vec![(3.0, 4.0), (4.0, 5.0)])
            ]
        );
    }

    #[test]
    fn a_dense_series_becomes_each_columns_min_mean_max() {
        // 1000 points over 10 columns: column c holds x in [c, c+1), y = ±1 alternating plus c
        let x: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
        let y: Vec<f64> = (0..1000)
            .map(|i| (i / 100) as f64 + if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let p = pieces(&x, &y, 0.0, 10.0, 10);
        let Piece::Envelope(cols) = &p[0] else {
            panic!("{p:?}")
        };
        assert_eq!(p.len(), 1);
        assert_eq!(cols.len(), 10);
        for (c, col) in cols.iter().enumerate() {
            assert!((col.x - (c as f64 + 0.5)).abs() < 1e-12);
            assert_eq!((col.min, col.max), (c as f64 - 1.0, c as f64 + 1.0));
            assert!((col.mean - c as f64).abs() < 1e-12, "{col:?}");
        }
    }

    #[test]
    fn labels_at_nearby_lines_are_stacked_not_overlapped() {
        let mut placed = Vec::new();
        for px in [100, 104, 110, 300, 990] {
            let b = place(Anchor::Vertical(px), (150, 14), &placed, (1000, 200), 3);
            placed.push(b);
        }
        for (i, a) in placed.iter().enumerate() {
            for b in &placed[i + 1..] {
                assert!(!a.overlaps(b, 0), "{a:?} overlaps {b:?}");
            }
        }
        // the first three stack in rows of 17 px; the one at 300 px has row 0 free
        assert_eq!(
            placed.iter().map(|b| b.y).collect::<Vec<_>>(),
            vec![3, 20, 37, 3, 3]
        );
        // the last would leave the area on the right: it sits left of its line
        assert_eq!(placed[4].x, 990 - 3 - 150);
        let h = place(Anchor::Horizontal(10), (150, 14), &placed, (1000, 200), 3);
        assert!(placed.iter().all(|p| !p.overlaps(&h, 0)), "{h:?}");
    }

    #[test]
    fn ranges_are_padded_and_flat_ones_widened() {
        assert_eq!(padded_range([0.0, 10.0].into_iter()), Some((-0.5, 10.5)));
        assert_eq!(padded_range([2.0, 2.0].into_iter()), Some((1.8, 2.2)));
        assert_eq!(padded_range([f64::NAN].into_iter()), None);
    }
}

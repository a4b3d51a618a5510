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

#![forbid(unsafe_code)]

use std::fmt;
use std::path::{Path, PathBuf};

mod raster;
mod render;

pub use raster::Image;
pub use render::{nice_ticks, render};

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

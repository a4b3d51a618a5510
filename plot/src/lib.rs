//! leakwatch's figures, drawn with plotters: PNG and SVG.
//!
//! A [`Figure`] is a stack of [`Panel`]s sharing one x axis (time, usually).
//! Each panel has its own y axis, a legend in a column to its right, and any
//! number of [`Series`] (lines, dashed lines or points) and [`Marker`]s
//! (vertical or horizontal reference lines such as a leak onset or a
//! threshold, and shaded spans such as a stretch the detector was blind).
//! Text is drawn in an embedded font (DejaVu Sans), so nothing depends on the
//! fonts installed on the machine; a PNG is drawn at twice its size and
//! reduced, so lines and text are antialiased. A series with more points than
//! its plot area has pixel columns is drawn as each column's min..max
//! (shaded) and mean (its line): an envelope. Marker labels never overlap:
//! they are stacked. Non-finite values break a line instead of being drawn.
//!
//! ```no_run
//! use plot::{Figure, Panel, Series, Style};
//! let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.01).collect();
//! let y: Vec<f64> = t.iter().map(|t| t.sin()).collect();
//! let mut fig = Figure::new("demo", "t [s]");
//! fig.panels.push(Panel::new("sine", "y [-]").with_series(Series::line("sin", &t, &y)));
//! plot::render_png(&fig, std::path::Path::new("demo.png")).unwrap();
//! plot::write_svg(&fig, std::path::Path::new("demo.svg")).unwrap();
//! ```

#![forbid(unsafe_code)]

use std::fmt;
use std::path::{Path, PathBuf};

use plotters::prelude::{BitMapBackend, IntoDrawingArea, SVGBackend};

mod draw;
mod font;
mod image;
mod layout;

pub use image::Image;

/// Width of a rendered figure in pixels (PNG) or user units (SVG).
pub const FIGURE_WIDTH_PX: usize = 1400;
/// Height of one panel in pixels (plot area plus its title and tick labels).
pub const PANEL_HEIGHT_PX: usize = 280;
/// Height of the figure's title band and of the x-axis label band, in pixels.
const TITLE_BAND_PX: usize = 40;
const XLABEL_BAND_PX: usize = 34;
/// Width of the y axis' tick labels and label, left of each plot area, in pixels.
const LEFT_MARGIN_PX: usize = 90;
/// Room left of the y-axis label (its text is centred on the plot area's left edge), in pixels.
const Y_DESC_PAD_PX: usize = 16;
/// Width of the legend column right of each plot area, in pixels.
const LEGEND_WIDTH_PX: usize = 190;
/// A PNG is drawn this many times larger and reduced (antialiasing).
const SUPERSAMPLE: usize = 2;

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
    /// A shaded stretch of the x axis (e.g. where the detector was blind), with a label.
    Span {
        /// Where it starts on the x axis.
        x_from: f64,
        /// Where it ends on the x axis.
        x_to: f64,
        /// Text drawn at its start (empty: none).
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
    /// The plotting library could not draw the figure.
    Draw(String),
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
            PlotError::Draw(e) => write!(f, "cannot draw the figure: {e}"),
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

/// The size of a figure in pixels: width and height.
fn size(fig: &Figure) -> (usize, usize) {
    (
        FIGURE_WIDTH_PX,
        TITLE_BAND_PX + fig.panels.len() * PANEL_HEIGHT_PX + XLABEL_BAND_PX,
    )
}

/// The first series, in panel order, whose x and y differ in length, as an
/// error; [`PlotError::NothingToPlot`] for a figure without panels.
fn check(fig: &Figure) -> Result<(), PlotError> {
    if fig.panels.is_empty() {
        return Err(PlotError::NothingToPlot);
    }
    for s in fig.panels.iter().flat_map(|p| &p.series) {
        if s.x.len() != s.y.len() {
            return Err(PlotError::LengthMismatch {
                label: s.label.clone(),
                x_len: s.x.len(),
                y_len: s.y.len(),
            });
        }
    }
    Ok(())
}

/// Renders a figure to an RGB image, [`FIGURE_WIDTH_PX`] wide and
/// [`PANEL_HEIGHT_PX`] per panel (plus the title and x-label bands) high.
pub fn render(fig: &Figure) -> Result<Image, PlotError> {
    check(fig)?;
    let (w, h) = size(fig);
    let (bw, bh) = (w * SUPERSAMPLE, h * SUPERSAMPLE);
    let mut big = vec![255u8; 3 * bw * bh];
    {
        let root = BitMapBackend::with_buffer(&mut big, (bw as u32, bh as u32)).into_drawing_area();
        draw::draw(fig, &root, SUPERSAMPLE as f64)?;
        root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
    }
    Ok(Image::reduced(&big, bw, bh, SUPERSAMPLE))
}

/// Renders a figure as an SVG document (the same layout as [`render`], in user
/// units equal to its pixels; text in the `sans-serif` family).
pub fn render_svg(fig: &Figure) -> Result<String, PlotError> {
    check(fig)?;
    let (w, h) = size(fig);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (w as u32, h as u32)).into_drawing_area();
        draw::draw(fig, &root, 1.0)?;
        root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
    }
    Ok(out)
}

/// Writes `bytes` to `path`.
fn write(path: &Path, bytes: &[u8]) -> Result<(), PlotError> {
    std::fs::write(path, bytes).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Renders a figure and writes it as a PNG file.
pub fn render_png(fig: &Figure, path: &Path) -> Result<(), PlotError> {
    write(path, &encode_png(&render(fig)?)?)
}

/// Renders a figure and writes it as an SVG file.
pub fn write_svg(fig: &Figure, path: &Path) -> Result<(), PlotError> {
    write(path, render_svg(fig)?.as_bytes())
}

#[cfg(test)]
mod tests;

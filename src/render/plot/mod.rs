//! Line plots: series of `(x, y)` points on linear or log10 axes, horizontal reference lines,
//! ticks, axis labels, a title and a legend, drawn with tiny-skia and the embedded font
//! (e.g. radial profiles, or objective, grid mass and `C` against iteration).
//!
//! Points with a NaN or infinite coordinate, or a non-positive one on a log axis, are skipped
//! and the line breaks there. Lines are clipped to the plot area. Screen pixels grow right and
//! down; the data range maps onto the plot area as [`PlotFrame`] describes.

use serde::{Deserialize, Serialize};
use tiny_skia::{Color, Pixmap};

use super::RenderError;

mod annotate;
mod draw;
mod layout;
mod legend;
mod scale;

pub use scale::PlotFrame;

/// Okabe–Ito colours (distinguishable with the common colour-vision deficiencies), ordered
/// for use on white: blue, vermillion, bluish green, orange, reddish purple, sky blue, black,
/// yellow.
pub const PALETTE: [[u8; 3]; 8] = [
    [0, 114, 178],
    [213, 94, 0],
    [0, 158, 115],
    [230, 159, 0],
    [204, 121, 167],
    [86, 180, 233],
    [0, 0, 0],
    [240, 228, 66],
];

/// Smallest and largest accepted side of a plot, in pixels.
pub const PLOT_SIDE_PX: (u32, u32) = (64, 4096);
/// Largest accepted series line width, in pixels.
pub const MAX_LINE_WIDTH_PX: f32 = 50.0;

/// How data values map onto an axis.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisScale {
    #[default]
    Linear,
    /// Position proportional to `log10(value)`; non-positive values are not drawn.
    Log,
}

/// Dash pattern of a line.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LineStyle {
    #[default]
    Solid,
    Dashed,
    Dotted,
    DashDot,
}

/// One line of a plot, drawn through its points in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    /// Legend text; an empty label keeps the series out of the legend.
    pub label: String,
    /// Data points `(x, y)` in the units of the axes.
    pub points: Vec<(f64, f64)>,
    /// sRGB colour.
    pub color: [u8; 3],
    pub style: LineStyle,
    /// Line width in pixels, `0 < width <= MAX_LINE_WIDTH_PX`.
    pub width: f32,
    /// Also draw a filled circle at each point.
    pub markers: bool,
}

impl Series {
    /// A solid 2-pixel line without markers.
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>, color: [u8; 3]) -> Self {
        Self {
            label: label.into(),
            points,
            color,
            style: LineStyle::Solid,
            width: 2.0,
            markers: false,
        }
    }
}

/// One axis: its title, scale and data range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// Axis title (units in brackets, e.g. "r \[arcsec\]"); empty for none.
    pub label: String,
    pub scale: AxisScale,
    /// Shown range `(lo, hi)`, `lo < hi` (both positive on a log axis). None: the range of
    /// the drawable data (and of the reference values, on y) widened by 5 % on each side
    /// (of `log10` on a log axis).
    pub range: Option<(f64, f64)>,
}

impl Axis {
    /// A linear axis with its range from the data.
    pub fn linear(label: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            scale: AxisScale::Linear,
            range: None,
        }
    }

    /// A log10 axis with its range from the data.
    pub fn log(label: impl Into<String>) -> Self {
        Self {
            scale: AxisScale::Log,
            ..Self::linear(label)
        }
    }
}

/// A horizontal line across the plot at `y = value` (e.g. a true value), dashed, with its
/// label written next to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    pub value: f64,
    pub label: String,
    /// sRGB colour of the line and its label.
    pub color: [u8; 3],
}

/// A complete line plot; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinePlot {
    /// Title above the plot; empty for none.
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    pub references: Vec<Reference>,
    /// Size of the whole image in pixels, each `PLOT_SIDE_PX.0..=PLOT_SIDE_PX.1`; the text
    /// scale grows with the smaller side (one font unit per 200 pixels).
    pub width_px: u32,
    pub height_px: u32,
}

impl Default for LinePlot {
    /// An empty 800 x 500 plot with linear axes.
    fn default() -> Self {
        Self {
            title: String::new(),
            x: Axis::linear(""),
            y: Axis::linear(""),
            series: Vec::new(),
            references: Vec::new(),
            width_px: 800,
            height_px: 500,
        }
    }
}

impl LinePlot {
    /// Checks sizes and series widths (ranges are checked when the frame is built).
    pub fn validate(&self) -> Result<(), RenderError> {
        for (name, v) in [("width_px", self.width_px), ("height_px", self.height_px)] {
            if !(PLOT_SIDE_PX.0..=PLOT_SIDE_PX.1).contains(&v) {
                return Err(RenderError::BadOption {
                    name,
                    value: v.to_string(),
                    reason: "must be 64 to 4096 pixels",
                });
            }
        }
        for (k, s) in self.series.iter().enumerate() {
            if !(s.width > 0.0 && s.width <= MAX_LINE_WIDTH_PX) {
                return Err(RenderError::BadOption {
                    name: "series.width",
                    value: format!("series {k} ({:?}): {}", s.label, s.width),
                    reason: "must be above 0 and at most 50 pixels",
                });
            }
        }
        Ok(())
    }

    /// The same plot drawn `k` times larger: image size and line widths times `k` (sizes
    /// rounded to whole pixels, widths capped at [`MAX_LINE_WIDTH_PX`]); the text grows with
    /// the image, so a `k = 2` plot is the `k = 1` one at twice the resolution, e.g. for print.
    pub fn scaled(&self, k: f32) -> LinePlot {
        let side = |v: u32| (v as f32 * k).round().clamp(0.0, u32::MAX as f32) as u32;
        let mut out = self.clone();
        out.width_px = side(self.width_px);
        out.height_px = side(self.height_px);
        for s in &mut out.series {
            s.width = (s.width * k).min(MAX_LINE_WIDTH_PX);
        }
        out
    }

    /// Where the plot area lies in the image and how data map onto it, for the image that
    /// [`Self::render_pixmap`] draws.
    pub fn frame(&self) -> Result<PlotFrame, RenderError> {
        Ok(layout::plan(self)?.frame)
    }

    /// Draws the plot on a white image of `width_px` x `height_px` pixels.
    pub fn render_pixmap(&self) -> Result<Pixmap, RenderError> {
        let plan = layout::plan(self)?;
        let f = &plan.frame;
        let mut pm = Pixmap::new(f.width, f.height).ok_or_else(|| {
            RenderError::Png(format!("cannot allocate {} x {}", f.width, f.height))
        })?;
        pm.fill(Color::WHITE);
        draw::grid_and_axes(&mut pm, &plan, self);
        draw::all_series(&mut pm, f, &self.series);
        let samples = annotate::series_samples(f, &self.series);
        let taken = annotate::references(&mut pm, &plan, &self.references, &samples);
        let refs = &self.references;
        legend::draw(&mut pm, &plan, &self.series, refs, &samples, &taken);
        draw::frame_and_title(&mut pm, &plan, self);
        Ok(pm)
    }

    /// [`Self::render_pixmap`] encoded as PNG.
    pub fn render_png(&self) -> Result<Vec<u8>, RenderError> {
        self.render_pixmap()?
            .encode_png()
            .map_err(|e| RenderError::Png(e.to_string()))
    }
}

//! Figures of maps with tiny-skia: the convergence map colour-mapped, with axes in arcsec, a
//! colour bar, critical curves, point overlays and a legend ([method §6]).
//!
//! Orientation: pixel `i` of the map (+x, West for HFF maps with `CDELT1 < 0`) grows to the
//! right and row `j` (+y, North) grows upward, as DS9 shows the FITS file; so East is to the
//! left, as on the sky. Rendering is deterministic: no system fonts, the text is drawn from an
//! embedded font (DejaVu Sans, `src/render/fonts/`) at a size that follows the figure's.
//!
//! [method §6]: crate::method#6-products

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::curves::CriticalCurves;
use crate::map::Map;

mod axes;
mod colormap;
mod colormap_tables;
mod compose;
mod figure;
mod font;
mod layout;
mod overlay;
mod paint;
mod plot;

pub use colormap::{
    color_limits, render_colormap_rgba, value_rgb, ColorScale, Colormap, LOG_RANGE, NO_DATA_RGB,
};
pub use compose::{
    compose_grid, compose_png_grid, grid_offsets, GridLayout, MAX_COMPOSED_PIXELS,
    MAX_COMPOSED_SIDE_PX,
};
pub use figure::{kappa_figure_frame, kappa_figure_frame_for, render_kappa_png, FigureFrame};
pub use overlay::{CAUSTIC_RGB, RADIAL_RGB, TANGENTIAL_RGB};
pub use plot::{
    Axis, AxisScale, LinePlot, LineStyle, PlotFrame, Reference, Series, MAX_LINE_WIDTH_PX, PALETTE,
    PLOT_SIDE_PX,
};

/// What prevents a figure from being drawn.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RenderError {
    #[error("render option {name} = {value}: {reason}")]
    BadOption {
        name: &'static str,
        value: String,
        reason: &'static str,
    },
    #[error("the map has {len} values but its geometry needs {pixels} x {pixels}")]
    BadMap { len: usize, pixels: usize },
    #[error("the map has no finite values to set the colour scale from")]
    NoFiniteValues,
    #[error("log10 colour scale: the map has no positive values; give vmin and vmax")]
    NoPositiveValues,
    #[error("PNG encoding failed: {0}")]
    Png(String),
}

/// Checks that the map's data fill its geometry and the geometry is usable.
pub(crate) fn check_map(map: &Map) -> Result<(), RenderError> {
    let n = map.geometry.pixels;
    let size = map.geometry.size_arcsec;
    if n == 0 || map.data.len() != n * n {
        return Err(RenderError::BadMap {
            len: map.data.len(),
            pixels: n,
        });
    }
    if !(size.is_finite() && size > 0.0 && map.geometry.center.is_finite()) {
        let value = format!("{size} arcsec at {}", map.geometry.center);
        return Err(RenderError::BadOption {
            name: "geometry",
            value,
            reason: "size must be positive and finite",
        });
    }
    Ok(())
}

/// Marker drawn at each position of an [`OverlayPoints`] set.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Marker {
    #[default]
    Circle,
    Cross,
    Plus,
    Square,
    /// A filled, semi-transparent ([`PIXEL_ALPHA`]) square of side `side_mas` milliarcsec
    /// centred on the position (at least [`MIN_PIXEL_SIDE_PX`] screen pixels), e.g. one
    /// constraint pixel of an arc; overlapping squares of one set do not darken each other.
    Pixel {
        side_mas: u32,
    },
    /// A wide circle around the position (three times a marker's radius, drawn thick) that
    /// singles it out, e.g. the worst systems of a verdict.
    Ring,
}

/// Opacity of [`Marker::Pixel`] squares.
pub const PIXEL_ALPHA: f32 = 0.7;
/// Smallest side of a [`Marker::Pixel`] square on screen, in pixels.
pub const MIN_PIXEL_SIDE_PX: f32 = 2.0;

/// Where the legend of [`render_kappa_png`] goes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LegendPlace {
    /// A box in the top-right corner of the map (covers part of it).
    #[default]
    InsideTopRight,
    /// Rows under the x-axis title, outside the map (the figure grows downwards).
    Below,
}

/// A labelled set of positions (arcsec, frame of [method §1]), e.g. observed images.
/// A set with an empty `label` is drawn but has no legend entry.
///
/// [method §1]: crate::method#1-frames-and-units
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OverlayPoints {
    pub label: String,
    /// sRGB colour.
    pub color: [u8; 3],
    pub positions_arcsec: Vec<DVec2>,
    pub marker: Marker,
}

/// Labelled polylines (arcsec, frame of [method §1]) drawn over the map, e.g. the
/// critical curves of another lens. A set with an empty `label` has no legend entry.
///
/// [method §1]: crate::method#1-frames-and-units
#[derive(Debug, Clone, PartialEq)]
pub struct OverlayLines {
    pub label: String,
    /// sRGB colour.
    pub color: [u8; 3],
    pub dashed: bool,
    pub lines: Vec<Vec<DVec2>>,
}

/// What is drawn over the map: critical curves (tangential red, radial cyan; the caustics
/// white and dashed if [`KappaPlotOptions::show_caustics`]), other lines and point sets,
/// clipped to the map.
#[derive(Debug, Clone, Default)]
pub struct Overlay<'a> {
    pub curves: Option<&'a CriticalCurves>,
    pub lines: Vec<OverlayLines>,
    pub points: Vec<OverlayPoints>,
    /// Texts on the map, drawn last (e.g. the ids of the systems a ring marks).
    pub labels: Vec<OverlayLabel>,
}

/// A text on the map: starts just right of `position_arcsec` (beside a [`Marker::Ring`]
/// there), in `color` over a dark halo; left of it when it would leave the map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OverlayLabel {
    pub text: String,
    pub position_arcsec: DVec2,
    /// sRGB colour.
    pub color: [u8; 3],
}

/// Options of [`render_kappa_png`]; `Default` gives a 512-pixel viridis map, linear scale,
/// limits from the data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct KappaPlotOptions {
    pub scale: ColorScale,
    /// Lower colour limit in data units (None: from the data, see [`color_limits`]).
    pub vmin: Option<f64>,
    /// Upper colour limit in data units (None: the data maximum).
    pub vmax: Option<f64>,
    pub colormap: Colormap,
    /// Side of the map on screen in pixels, 64 to 4096 (default 512). Text scales with it.
    pub map_pixels_on_screen: u32,
    /// Title above the map.
    pub title: Option<String>,
    /// Colour-bar label (`_{...}` and `^{...}` set sub- and superscripts); default "κ" or
    /// "log₁₀ κ".
    pub colorbar_label: Option<String>,
    /// Also draw the caustics of [`Overlay::curves`] (default false).
    pub show_caustics: bool,
    /// Where the legend goes (default: inside the map's top-right corner).
    pub legend: LegendPlace,
}

impl Default for KappaPlotOptions {
    fn default() -> Self {
        Self {
            scale: ColorScale::Linear,
            vmin: None,
            vmax: None,
            colormap: Colormap::Viridis,
            map_pixels_on_screen: 512,
            title: None,
            colorbar_label: None,
            show_caustics: false,
            legend: LegendPlace::InsideTopRight,
        }
    }
}

impl KappaPlotOptions {
    /// Checks the screen size (the colour limits are checked by [`color_limits`]).
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(64..=4096).contains(&self.map_pixels_on_screen) {
            return Err(RenderError::BadOption {
                name: "map_pixels_on_screen",
                value: self.map_pixels_on_screen.to_string(),
                reason: "must be 64 to 4096",
            });
        }
        Ok(())
    }
}

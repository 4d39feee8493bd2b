//! Where the parts of the convergence figure go on screen (map, axes, colour bar, legend),
//! shared by the figure and the overlays drawn on it.

use glam::DVec2;

use super::font::CAP;
use crate::map::MapGeometry;

/// Map pixels per font unit of text scale.
const MAP_PX_PER_SCALE: f32 = 256.0;
/// Tick length, gap between parts and padding at the figure's edge, in font units: every
/// length of the figure is a multiple of the text scale, so a figure drawn twice as large is
/// the same figure at twice the resolution.
pub(super) const TICK: f32 = 4.0;
pub(super) const GAP: f32 = 3.0;
pub(super) const PAD: f32 = 6.0;
/// Smallest text scale (cap height 7 pixels, about 10-pixel type).
pub(super) const MIN_TEXT_SCALE: f32 = 1.0;

/// The text scale of a figure whose map is `m` pixels a side: proportional to `m` (one font
/// unit per 256 pixels, so a 512-pixel map has 14-pixel capitals), at least
/// [`MIN_TEXT_SCALE`].
pub(super) fn text_scale(m: u32) -> f32 {
    (m as f32 / MAP_PX_PER_SCALE).max(MIN_TEXT_SCALE)
}

/// Pixel positions of the parts of the figure.
pub(super) struct Layout {
    /// Text scale: pixels per font unit ([`text_scale`]).
    pub(super) s: f32,
    /// Map side on screen.
    pub(super) m: f32,
    pub(super) left: f32,
    pub(super) top: f32,
    pub(super) cb_x: f32,
    pub(super) cb_w: f32,
    pub(super) width: u32,
    pub(super) height: u32,
    /// Top of the legend under the map (when it goes there).
    pub(super) legend_top: f32,
}

impl Layout {
    /// The layout of a map `m` pixels a side, with or without a title, with room for y tick
    /// labels `y_label_w` and colour-bar tick labels `cb_label_w` pixels wide.
    pub(super) fn new(m: u32, title: bool, y_label_w: f32, cb_label_w: f32) -> Self {
        let s = text_scale(m);
        let (ch, tick, gap, pad) = (CAP * s, TICK * s, GAP * s, PAD * s);
        let m = m as f32;
        let top = (if title {
            pad + ch + 3.0 * gap
        } else {
            pad + ch / 2.0
        })
        .round();
        let left = (pad + ch + 2.0 * gap + y_label_w + gap + tick).round();
        let bottom = tick + gap + ch + 3.0 * gap + ch + pad;
        let legend_top = (top + m + bottom - pad + 2.0 * gap).round();
        let cb_x = (left + m + 8.0 * s).round();
        let cb_w = (m / 24.0).round().max(10.0);
        let right_edge = cb_x + cb_w + tick + gap + cb_label_w + 2.0 * gap + ch + pad;
        Self {
            s,
            m,
            left,
            top,
            cb_x,
            cb_w,
            width: right_edge.ceil() as u32,
            height: (top + m + bottom).ceil() as u32,
            legend_top,
        }
    }

    /// Width available to a row of the legend under the map (from the map's left edge).
    pub(super) fn legend_avail(&self) -> f32 {
        self.width as f32 - self.left - self.pad()
    }

    pub(super) fn ch(&self) -> f32 {
        CAP * self.s
    }
    pub(super) fn tick(&self) -> f32 {
        TICK * self.s
    }
    pub(super) fn gap(&self) -> f32 {
        GAP * self.s
    }
    pub(super) fn pad(&self) -> f32 {
        PAD * self.s
    }
    /// Width of ticks and frames: half a font unit, whole pixels, at least one.
    pub(super) fn line(&self) -> f32 {
        (self.s / 2.0).floor().max(1.0)
    }

    /// Screen position of `p` (arcsec) on a map of geometry `g`.
    pub(super) fn screen(&self, g: &MapGeometry, p: DVec2) -> (f32, f32) {
        let half = g.size_arcsec / 2.0;
        let u = (p.x - (g.center.x - half)) / g.size_arcsec;
        let v = ((g.center.y + half) - p.y) / g.size_arcsec;
        (
            self.left + (u * self.m as f64) as f32,
            self.top + (v * self.m as f64) as f32,
        )
    }
}

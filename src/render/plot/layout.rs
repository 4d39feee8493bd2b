//! Margins, text scale and ticks of a line plot.

use super::scale::{axis_values, fraction, resolve_range, PlotFrame, Ticks};
use super::{AxisScale, LinePlot};
use crate::render::font::{minus_signs, text_width, ADVANCE, CAP};
use crate::render::RenderError;

/// Smallest plot area side in pixels left after the margins.
const MIN_AREA_PX: f32 = 24.0;
/// Image pixels per font unit of text scale (the smaller image side / this).
const PX_PER_SCALE: f32 = 200.0;
/// Smallest text scale (cap height 7 pixels, about 10-pixel type).
const MIN_TEXT_SCALE: f32 = 1.0;

/// Everything the drawing needs besides the plot itself.
pub(super) struct Plan {
    pub(super) frame: PlotFrame,
    /// Text scale: pixels per font unit, proportional to the smaller image side.
    pub(super) s: f32,
    pub(super) x_ticks: Ticks,
    pub(super) y_ticks: Ticks,
}

impl Plan {
    /// Cap height of text.
    pub(super) fn ch(&self) -> f32 {
        CAP * self.s
    }
    /// Depth of descenders below the cap height.
    pub(super) fn desc(&self) -> f32 {
        2.0 * self.s
    }
    pub(super) fn gap(&self) -> f32 {
        3.0 * self.s
    }
    pub(super) fn pad(&self) -> f32 {
        6.0 * self.s
    }
    pub(super) fn tick(&self) -> f32 {
        4.0 * self.s
    }
    /// Width of ticks and frames: half a font unit, whole pixels, at least one.
    pub(super) fn line(&self) -> f32 {
        (self.s / 2.0).floor().max(1.0)
    }
}

/// [`super::scale::ticks`] with the labels' hyphens printed as minus signs.
fn ticks(scale: AxisScale, range: (f64, f64), target: usize) -> Ticks {
    let mut t = super::scale::ticks(scale, range, target);
    for (_, label) in &mut t.major {
        *label = minus_signs(label);
    }
    t
}

fn widest(t: &[(f64, String)], s: f32) -> f32 {
    t.iter().map(|(_, l)| text_width(l, s)).fold(0.0, f32::max)
}

/// Tick sets for `target` from 10 down to 2 until `fits` accepts one (at 2 it is taken).
fn choose(scale: AxisScale, range: (f64, f64), fits: impl Fn(&Ticks) -> bool) -> Ticks {
    let mut t = ticks(scale, range, 2);
    for target in (2..=10).rev() {
        let candidate = ticks(scale, range, target);
        if fits(&candidate) {
            t = candidate;
            break;
        }
    }
    t
}

fn too_small(name: &'static str, v: u32) -> RenderError {
    RenderError::BadOption {
        name,
        value: v.to_string(),
        reason: "too small for the plot's labels",
    }
}

/// Resolves the axis ranges, the text scale, the margins and the ticks of `plot`.
pub(super) fn plan(plot: &LinePlot) -> Result<Plan, RenderError> {
    plot.validate()?;
    let x_range = resolve_range("x.range", &plot.x, axis_values(plot, false).into_iter())?;
    let y_range = resolve_range("y.range", &plot.y, axis_values(plot, true).into_iter())?;
    let (w, h) = (plot.width_px as f32, plot.height_px as f32);
    let s = (plot.width_px.min(plot.height_px) as f32 / PX_PER_SCALE).max(MIN_TEXT_SCALE);
    let sf = s;
    let mut plan = Plan {
        frame: PlotFrame {
            width: plot.width_px,
            height: plot.height_px,
            left: 0.0,
            top: 0.0,
            plot_width: 0.0,
            plot_height: 0.0,
            x_scale: plot.x.scale,
            y_scale: plot.y.scale,
            x_range,
            y_range,
        },
        s,
        x_ticks: ticks(plot.x.scale, x_range, 2),
        y_ticks: ticks(plot.y.scale, y_range, 2),
    };
    let (ch, desc, gap, pad, tk) = (plan.ch(), plan.desc(), plan.gap(), plan.pad(), plan.tick());
    let top = pad
        + if plot.title.is_empty() {
            ch / 2.0
        } else {
            ch + desc + 2.0 * gap
        };
    let x_title = if plot.x.label.is_empty() {
        desc
    } else {
        2.0 * gap + ch + desc
    };
    let bottom = tk + gap + ch + x_title + pad;
    let plot_h = (h - top - bottom).floor();
    if plot_h < MIN_AREA_PX {
        return Err(too_small("height_px", plot.height_px));
    }
    // y ticks: at least a line of text and two gaps apart.
    let y_step = |t: &Ticks| {
        let span = plot_h as f64 / t.major.len().max(1) as f64;
        span >= (ch + 2.0 * gap) as f64 * 1.5
    };
    let y_ticks = choose(plot.y.scale, y_range, y_step);
    let y_title = if plot.y.label.is_empty() {
        0.0
    } else {
        ch + desc + 2.0 * gap
    };
    let left = (pad + y_title + widest(&y_ticks.major, s) + gap + tk).round();
    // x ticks: labels at least three characters apart.
    let x_fits = |plot_w: f32| {
        move |t: &Ticks| {
            let pos: Vec<(f64, f32)> = t
                .major
                .iter()
                .filter_map(|(v, l)| {
                    let f = fraction(plot.x.scale, x_range, *v)?;
                    Some((f * plot_w as f64, text_width(l, s)))
                })
                .collect();
            pos.windows(2)
                .all(|p| (p[1].0 - p[0].0) as f32 >= (p[0].1 + p[1].1) / 2.0 + 3.0 * ADVANCE * sf)
        }
    };
    let mut right = pad + 3.0 * ADVANCE * sf;
    let mut x_ticks = choose(plot.x.scale, x_range, x_fits(w - left - right));
    right = right.max(pad + widest(&x_ticks.major, s) / 2.0).round();
    let plot_w = (w - left - right).floor();
    if plot_w < MIN_AREA_PX {
        return Err(too_small("width_px", plot.width_px));
    }
    if !x_fits(plot_w)(&x_ticks) {
        x_ticks = choose(plot.x.scale, x_range, x_fits(plot_w));
    }
    plan.frame.left = left;
    plan.frame.top = top.round();
    plan.frame.plot_width = plot_w;
    plan.frame.plot_height = plot_h;
    plan.x_ticks = x_ticks;
    plan.y_ticks = y_ticks;
    Ok(plan)
}

//! Axis ranges from the data, data-to-screen mapping and tick positions and labels.

use super::{Axis, AxisScale, LinePlot};
use crate::render::axes::nice_ticks;
use crate::render::RenderError;

/// Fraction of the data span added on each side of an automatic range.
const MARGIN: f64 = 0.05;

/// Where the plot area lies in the image of [`LinePlot::render_pixmap`] and how data map onto
/// it (pixels, origin top-left, +y down). The data range `x_range.0..x_range.1` spans screen
/// `left..left + plot_width` linearly in `x` (linear axis) or in `log10 x` (log axis); the
/// y range spans `top + plot_height..top` (upward).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotFrame {
    /// Image size in pixels.
    pub width: u32,
    pub height: u32,
    /// Left and top edges of the plot area and its size, in pixels.
    pub left: f32,
    pub top: f32,
    pub plot_width: f32,
    pub plot_height: f32,
    pub x_scale: AxisScale,
    pub y_scale: AxisScale,
    /// Shown data ranges `(lo, hi)`, in data units.
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
}

/// Position of `v` along an axis as a fraction of its length, 0 at `lo` and 1 at `hi`:
/// `(v - lo) / (hi - lo)` or `(log10 v - log10 lo) / (log10 hi - log10 lo)`. None if `v` is
/// not finite, not positive on a log axis, or the result overflows.
pub(super) fn fraction(scale: AxisScale, (lo, hi): (f64, f64), v: f64) -> Option<f64> {
    let t = match scale {
        AxisScale::Linear => (v - lo) / (hi - lo),
        AxisScale::Log if v > 0.0 => (v.log10() - lo.log10()) / (hi.log10() - lo.log10()),
        AxisScale::Log => return None,
    };
    t.is_finite().then_some(t)
}

/// Data value at fraction `t` of an axis; the inverse of [`fraction`].
fn value_at(scale: AxisScale, (lo, hi): (f64, f64), t: f64) -> f64 {
    match scale {
        AxisScale::Linear => lo + t * (hi - lo),
        AxisScale::Log => 10f64.powf(lo.log10() + t * (hi.log10() - lo.log10())),
    }
}

impl PlotFrame {
    /// Screen `x` of data `x` in f64 (None where the point is not drawn).
    pub(super) fn sx(&self, x: f64) -> Option<f64> {
        fraction(self.x_scale, self.x_range, x)
            .map(|t| self.left as f64 + t * self.plot_width as f64)
    }

    /// Screen `y` of data `y` in f64 (None where the point is not drawn).
    pub(super) fn sy(&self, y: f64) -> Option<f64> {
        fraction(self.y_scale, self.y_range, y)
            .map(|t| (self.top + self.plot_height) as f64 - t * self.plot_height as f64)
    }

    /// Screen position (pixels) of the data point `(x, y)`: `left + t_x plot_width`,
    /// `top + (1 - t_y) plot_height` with `t` the fraction along each axis (module docs).
    /// None for a point that is not drawn (non-finite, or non-positive on a log axis).
    pub fn data_to_screen(&self, x: f64, y: f64) -> Option<(f32, f32)> {
        let (a, b) = (self.sx(x)? as f32, self.sy(y)? as f32);
        (a.is_finite() && b.is_finite()).then_some((a, b))
    }

    /// Data coordinates under the screen point `(px, py)` pixels; the inverse of
    /// [`Self::data_to_screen`] (also outside the plot area).
    pub fn screen_to_data(&self, px: f32, py: f32) -> (f64, f64) {
        let tx = (px - self.left) as f64 / self.plot_width as f64;
        let ty = (self.top + self.plot_height - py) as f64 / self.plot_height as f64;
        (
            value_at(self.x_scale, self.x_range, tx),
            value_at(self.y_scale, self.y_range, ty),
        )
    }

    /// Whether the screen point `(px, py)` lies inside the plot area.
    pub fn contains(&self, px: f32, py: f32) -> bool {
        px >= self.left
            && px <= self.left + self.plot_width
            && py >= self.top
            && py <= self.top + self.plot_height
    }
}

fn bad_range(name: &'static str, value: String, reason: &'static str) -> RenderError {
    RenderError::BadOption {
        name,
        value,
        reason,
    }
}

/// The shown range of an axis: the given one (checked), or the drawable data values
/// `values` widened by [`MARGIN`] on each side (in `log10` on a log axis). With no values at
/// all the range is `(0, 1)` or `(1, 10)`.
pub(super) fn resolve_range(
    name: &'static str,
    axis: &Axis,
    values: impl Iterator<Item = f64>,
) -> Result<(f64, f64), RenderError> {
    let log = axis.scale == AxisScale::Log;
    if let Some((lo, hi)) = axis.range {
        let text = format!("({lo}, {hi})");
        if !(lo.is_finite() && hi.is_finite() && lo < hi && (hi - lo).is_finite()) {
            return Err(bad_range(name, text, "must be finite with lo < hi"));
        }
        if log && lo <= 0.0 {
            return Err(bad_range(name, text, "a log axis needs lo > 0"));
        }
        return Ok((lo, hi));
    }
    let (mut lo, mut hi, mut any, mut any_positive) =
        (f64::INFINITY, f64::NEG_INFINITY, false, false);
    for v in values.filter(|v| v.is_finite()) {
        any = true;
        if log && v <= 0.0 {
            continue;
        }
        any_positive = true;
        let v = if log { v.log10() } else { v };
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !any {
        return Ok(if log { (1.0, 10.0) } else { (0.0, 1.0) });
    }
    if !any_positive {
        let reason = "log axis: the data have no positive value; give a range";
        return Err(bad_range(name, "no positive value".into(), reason));
    }
    let span = hi - lo;
    let pad = if span > 1e-12 * lo.abs().max(hi.abs()) {
        MARGIN * span
    } else if log {
        0.5
    } else if lo == 0.0 {
        1.0
    } else {
        0.1 * lo.abs()
    };
    let (lo, hi) = (lo - pad, hi + pad);
    let (lo, hi) = if log {
        // The margin must not leave the positive finite numbers.
        let (a, b) = (f64::MIN_POSITIVE.log10(), f64::MAX.log10());
        (10f64.powf(lo.clamp(a, b)), 10f64.powf(hi.clamp(a, b)))
    } else {
        (lo, hi)
    };
    if !(lo.is_finite() && hi.is_finite() && lo < hi && (hi - lo).is_finite()) {
        let text = format!("({lo:e}, {hi:e})");
        return Err(bad_range(
            name,
            text,
            "the data span too wide a range; give one",
        ));
    }
    Ok((lo, hi))
}

/// Values of the axis that the resolved range is built from, from `plot`: the coordinates of
/// the points whose both coordinates are drawable (plus, on y, the reference values).
pub(super) fn axis_values(plot: &LinePlot, y: bool) -> Vec<f64> {
    let ok = |v: f64, s: AxisScale| v.is_finite() && (s == AxisScale::Linear || v > 0.0);
    let mut out: Vec<f64> = plot
        .series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|&&(x, yv)| ok(x, plot.x.scale) && ok(yv, plot.y.scale))
        .map(|&(x, yv)| if y { yv } else { x })
        .collect();
    // If no point is drawable on both axes, let each axis see its own finite values so that
    // the log-axis error names the axis at fault.
    if out.is_empty() {
        out = plot
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .map(|&(x, yv)| if y { yv } else { x })
            .filter(|v| v.is_finite())
            .collect();
    }
    if y {
        out.extend(plot.references.iter().map(|r| r.value));
    }
    out
}

/// Labelled (major) ticks and unlabelled minor ticks of an axis.
pub(super) struct Ticks {
    pub(super) major: Vec<(f64, String)>,
    pub(super) minor: Vec<f64>,
}

/// About `target` ticks over `range`: [`nice_ticks`] on a linear axis (labels in compact
/// scientific notation for very large or small values), decades on a log axis.
pub(super) fn ticks(scale: AxisScale, range: (f64, f64), target: usize) -> Ticks {
    match scale {
        AxisScale::Linear => Ticks {
            major: linear_ticks(range, target),
            minor: Vec::new(),
        },
        AxisScale::Log => log_ticks(range, target),
    }
}

fn linear_ticks((lo, hi): (f64, f64), target: usize) -> Vec<(f64, String)> {
    let t = nice_ticks(lo, hi, target);
    let biggest = t.iter().map(|(v, _)| v.abs()).fold(0.0, f64::max);
    if t.len() < 2 || (1e-3..1e5).contains(&biggest) || biggest == 0.0 {
        return t;
    }
    // One exponent for all labels, mantissa decimals as the step needs: "1.2e14".
    let e = biggest.log10().floor() as i32;
    let step = t[1].0 - t[0].0;
    let decimals = (e - step.log10().floor() as i32).clamp(0, 12) as usize;
    t.into_iter()
        .map(|(v, label)| {
            if label
                .trim_matches(|c| c == '0' || c == '.' || c == '-')
                .is_empty()
            {
                (v, "0".to_string())
            } else {
                (v, format!("{:.decimals$}e{e}", v / 10f64.powi(e)))
            }
        })
        .collect()
}

/// Whether the decades `k0..=k1` are all labelled as plain decimals (`10^-3 ..= 10^4`).
fn plain_decades(k0: i32, k1: i32) -> bool {
    k0 >= -3 && k1 <= 4
}

/// `m * 10^k` written compactly: plain decimals ("0.02", "500") or "{m}e{k}" ("2e-5").
pub(super) fn decade_label(m: u32, k: i32, plain: bool) -> String {
    if plain {
        let decimals = (-k).max(0) as usize;
        format!("{:.decimals$}", m as f64 * 10f64.powi(k))
    } else {
        format!("{m}e{k}")
    }
}

fn log_ticks((lo, hi): (f64, f64), target: usize) -> Ticks {
    let (a, b) = (lo.log10(), hi.log10());
    let (k0, k1) = ((a - 1e-9).ceil() as i32, (b + 1e-9).floor() as i32);
    let inside = |v: f64| v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9);
    let decades = (k1 - k0 + 1).max(0) as usize;
    // One notation for the whole axis: plain if every decade shown can be.
    let plain = plain_decades(k0 - 1, k1);
    let all = |ms: &[u32]| -> Vec<(u32, i32)> {
        (k0 - 1..=k1)
            .flat_map(|k| ms.iter().map(move |&m| (m, k)))
            .filter(|&(m, k)| inside(m as f64 * 10f64.powi(k)))
            .collect()
    };
    let every: Vec<u32> = (1..=9).collect();
    if decades >= 2 {
        let step = decades.div_ceil(target.max(2)).max(1) as i32;
        let major = (k0..=k1)
            .filter(|k| k.rem_euclid(step) == 0)
            .map(|k| (10f64.powi(k), decade_label(1, k, plain)))
            .collect();
        let minor = if step == 1 {
            all(&every[1..])
                .iter()
                .map(|&(m, k)| m as f64 * 10f64.powi(k))
                .collect()
        } else {
            (k0..=k1)
                .filter(|k| k.rem_euclid(step) != 0)
                .map(|k| 10f64.powi(k))
                .collect()
        };
        return Ticks { major, minor };
    }
    // Within about a decade: the first mantissa set giving three ticks (at most target + 1),
    // else the densest giving two, else linear ticks.
    let sets: [&[u32]; 4] = [&[1], &[1, 2, 5], &[1, 2, 3, 5], &every];
    let counts: Vec<Vec<(u32, i32)>> = sets.iter().map(|m| all(m)).collect();
    let picked = counts
        .iter()
        .find(|c| c.len() >= 3 && c.len() <= target.max(2) + 1)
        .or_else(|| {
            counts
                .iter()
                .rev()
                .find(|c| (2..=target.max(2) + 1).contains(&c.len()))
        })
        .cloned()
        .unwrap_or_default();
    let major: Vec<(f64, String)> = if picked.len() >= 2 {
        picked
            .iter()
            .map(|&(m, k)| (m as f64 * 10f64.powi(k), decade_label(m, k, plain)))
            .collect()
    } else {
        linear_ticks((lo, hi), target)
    };
    let minor = all(&every)
        .iter()
        .map(|&(m, k)| m as f64 * 10f64.powi(k))
        .filter(|v| !major.iter().any(|(t, _)| (t - v).abs() <= 1e-9 * v))
        .collect();
    Ticks { major, minor }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(t: &Ticks) -> Vec<&str> {
        t.major.iter().map(|(_, l)| l.as_str()).collect()
    }

    #[test]
    fn log_ticks_are_decades() {
        let t = log_ticks((0.8, 1200.0), 6);
        assert_eq!(labels(&t), ["1", "10", "100", "1000"]);
        assert_eq!(t.minor.len(), 2 + 8 * 3); // 0.8, 0.9, then 2..9 in three decades
        let t = log_ticks((1e-8, 1e4), 5);
        assert_eq!(labels(&t), ["1e-6", "1e-3", "1e0", "1e3"]);
        let t = log_ticks((3.0, 30.0), 5);
        assert_eq!(labels(&t), ["5", "10", "20"]);
        let t = log_ticks((0.21, 1.5), 5);
        assert_eq!(labels(&t), ["0.3", "0.5", "1"]);
        let t = log_ticks((1.1, 1.9), 5);
        assert!(t.major.len() >= 2, "{:?}", labels(&t));
    }

    #[test]
    fn big_linear_labels_are_compact() {
        let t = linear_ticks((1.0e14, 1.5e14), 5);
        assert_eq!(t[0].1, "1.0e14");
        assert!(t.iter().all(|(_, l)| l.len() <= 6), "{t:?}");
    }
}

//! Perceptual colour maps and the value-to-colour scale.

use serde::{Deserialize, Serialize};

use super::colormap_tables::{MAGMA, VIRIDIS};
use super::RenderError;
use crate::map::Map;

/// A 256-entry perceptually uniform colour map (matplotlib's tables).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Colormap {
    #[default]
    Viridis,
    Magma,
    /// Blue through white to red, white in the middle: for differences about zero with
    /// symmetric limits.
    Diverging,
}

impl Colormap {
    /// The 256 sRGB entries, index 0 for the lowest value.
    pub fn table(self) -> &'static [[u8; 3]; 256] {
        match self {
            Colormap::Viridis => &VIRIDIS,
            Colormap::Magma => &MAGMA,
            Colormap::Diverging => &DIVERGING,
        }
    }

    /// Colour of `t` in `[0, 1]` (clamped; NaN gives the lowest colour): entry `floor(256 t)`.
    pub fn rgb(self, t: f64) -> [u8; 3] {
        let k = if t.is_nan() {
            0.0
        } else {
            (t * 256.0).floor().clamp(0.0, 255.0)
        };
        self.table()[k as usize]
    }
}

/// [`Colormap::Diverging`]: linear in sRGB from blue (33, 102, 172) through near-white
/// (247, 247, 247) to red (178, 24, 43), the ends of ColorBrewer's RdBu.
static DIVERGING: [[u8; 3]; 256] = diverging_table();

const fn diverging_table() -> [[u8; 3]; 256] {
    const LOW: [f64; 3] = [33.0, 102.0, 172.0];
    const MID: [f64; 3] = [247.0, 247.0, 247.0];
    const HIGH: [f64; 3] = [178.0, 24.0, 43.0];
    let mut out = [[0u8; 3]; 256];
    let mut k = 0;
    while k < 256 {
        let t = k as f64 / 255.0;
        let (a, b, u) = if t < 0.5 {
            (LOW, MID, 2.0 * t)
        } else {
            (MID, HIGH, 2.0 * t - 1.0)
        };
        let mut c = 0;
        while c < 3 {
            out[k][c] = (a[c] + (b[c] - a[c]) * u + 0.5) as u8;
            c += 1;
        }
        k += 1;
    }
    out
}

/// How values map to colour: linearly, or by `log10(value)` (values at or below the lower
/// limit get the lowest colour).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColorScale {
    #[default]
    Linear,
    /// `log10` of the values.
    Log,
}

/// Default dynamic range of the log10 scale: the lower limit is at least `max / LOG_RANGE`.
pub const LOG_RANGE: f64 = 1e3;

impl ColorScale {
    /// The displayed quantity: `v`, or `log10(v)` (`-inf` for `v <= 0`).
    pub fn apply(self, v: f64) -> f64 {
        match self {
            ColorScale::Linear => v,
            ColorScale::Log if v > 0.0 => v.log10(),
            ColorScale::Log => f64::NEG_INFINITY,
        }
    }
}

/// The colour limits in displayed units (`log10` of the values for [`ColorScale::Log`]).
/// Given `vmin`/`vmax` (in data units) are used as they are; missing ones come from the finite
/// values of the map: min and max (linear), or max and `max(smallest positive, max / 1e3)`
/// (log10). Equal limits are widened by 0.5 either side.
pub fn color_limits(
    map: &Map,
    scale: ColorScale,
    vmin: Option<f64>,
    vmax: Option<f64>,
) -> Result<(f64, f64), RenderError> {
    for (name, v) in [("vmin", vmin), ("vmax", vmax)] {
        match v {
            Some(x) if !x.is_finite() || (scale == ColorScale::Log && x <= 0.0) => {
                let reason = "must be finite (and positive on a log10 scale)";
                return Err(RenderError::BadOption {
                    name,
                    value: x.to_string(),
                    reason,
                });
            }
            _ => {}
        }
    }
    let (lo, hi) = match scale {
        ColorScale::Linear => {
            let (lo, hi) = map.min_max();
            if lo > hi && (vmin.is_none() || vmax.is_none()) {
                return Err(RenderError::NoFiniteValues);
            }
            (vmin.unwrap_or(lo), vmax.unwrap_or(hi))
        }
        ColorScale::Log => {
            let positive = map.data.iter().filter(|v| v.is_finite() && **v > 0.0);
            let (lo, hi) = positive.fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
            if hi <= 0.0 && (vmin.is_none() || vmax.is_none()) {
                return Err(RenderError::NoPositiveValues);
            }
            let hi = vmax.unwrap_or(hi);
            let lo = vmin.unwrap_or(lo.max(hi / LOG_RANGE));
            (lo.log10(), hi.log10())
        }
    };
    if lo > hi {
        let value = format!("{} > vmax", vmin.unwrap_or(lo));
        return Err(RenderError::BadOption {
            name: "vmin",
            value,
            reason: "vmin must not exceed vmax",
        });
    }
    Ok(if lo == hi {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    })
}

/// Non-finite pixels are drawn in this grey.
pub const NO_DATA_RGB: [u8; 3] = [200, 200, 200];

/// Colour of one value, with limits in displayed units from [`color_limits`].
pub fn value_rgb(v: f64, scale: ColorScale, limits: (f64, f64), cmap: Colormap) -> [u8; 3] {
    if !v.is_finite() {
        return NO_DATA_RGB;
    }
    let d = scale.apply(v);
    cmap.rgb((d - limits.0) / (limits.1 - limits.0))
}

/// Raw RGBA (4 bytes a pixel, opaque) of `map` at its own resolution, for the browser to draw:
/// `n` rows of `n` pixels, the first row North (top), pixel `i` growing to the right (West),
/// i.e. the orientation of [`super::render_kappa_png`]. Limits as in [`color_limits`].
pub fn render_colormap_rgba(
    map: &Map,
    scale: ColorScale,
    vmin: Option<f64>,
    vmax: Option<f64>,
    cmap: Colormap,
) -> Result<Vec<u8>, RenderError> {
    super::check_map(map)?;
    let limits = color_limits(map, scale, vmin, vmax)?;
    let n = map.geometry.pixels;
    let mut out = Vec::with_capacity(n * n * 4);
    for row in 0..n {
        let j = n - 1 - row;
        for i in 0..n {
            let [r, g, b] = value_rgb(
                map.data.get(j * n + i).copied().unwrap_or(f64::NAN),
                scale,
                limits,
                cmap,
            );
            out.extend_from_slice(&[r, g, b, 255]);
        }
    }
    Ok(out)
}

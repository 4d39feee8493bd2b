//! Azimuthally averaged convergence and enclosed projected mass about a centre
//! ([method §6], "Radial profile").
//!
//! Each pixel is a square of constant `kappa` (its centre value). Its weight in an annulus is
//! the exact area of the square inside the annulus (disc-rectangle intersection in closed form),
//! so thin bins and bins smaller than a pixel are averaged correctly.
//!
//! [method §6]: crate::method#6-products

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::cosmology::LensPlane;
use crate::map::Map;

/// Most bins a profile may have (guards against absurd allocations from user input).
pub const MAX_RADIAL_BINS: usize = 100_000;

/// How to choose the radial bins, radii in arcsec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RadialBins {
    /// `count` bins of equal width from `r_min_arcsec >= 0` to `r_max_arcsec`; centres are the
    /// bin midpoints.
    Linear {
        r_min_arcsec: f64,
        r_max_arcsec: f64,
        count: usize,
    },
    /// `count` bins of equal width in `ln r` from `r_min_arcsec > 0` to `r_max_arcsec`; centres
    /// are the geometric means of the bin edges.
    Log {
        r_min_arcsec: f64,
        r_max_arcsec: f64,
        count: usize,
    },
    /// Explicit edges in arcsec: at least two, the first `>= 0`, strictly increasing; centres are
    /// the midpoints.
    Edges(Vec<f64>),
}

/// The profile: one entry per bin, and the enclosed mass at every bin edge.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RadialProfile {
    /// Bin centres in arcsec (see [`RadialBins`]).
    pub r_arcsec: Vec<f64>,
    /// Area-weighted mean `kappa_ref` (`D_ls/D_s = 1`) in each annulus.
    pub kappa: Vec<f64>,
    /// Bin edges in arcsec (one more than bins).
    pub r_edges_arcsec: Vec<f64>,
    /// Projected mass inside each edge, `Sigma_cr_ref * integral of kappa dA`, in Msun.
    pub enclosed_mass_msun: Vec<f64>,
}

/// What can be wrong with a radial-profile request.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RadialError {
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error(
        "radial profile: the outer edge {r_max_arcsec} arcsec reaches beyond the map; about this \
         centre the map covers a full circle only out to {limit_arcsec} arcsec"
    )]
    BeyondMap {
        r_max_arcsec: f64,
        limit_arcsec: f64,
    },
    #[error("radial profile: the kappa map has no pixels")]
    EmptyMap,
    #[error("radial profile: the kappa map of {pixels} pixels a side holds {found} values")]
    WrongLength { pixels: usize, found: usize },
    #[error("radial profile: kappa at pixel (column {i}, row {j}) is {value}, not finite")]
    NotFinite { i: usize, j: usize, value: f64 },
}

impl RadialBins {
    /// The validated bin edges in arcsec.
    pub fn edges_arcsec(&self) -> Result<Vec<f64>, RadialError> {
        let bad = |field: &str, value, reason| {
            Err(
                crate::error::BadFieldValue::new(format!("radial_bins.{field}"), value, reason)
                    .into(),
            )
        };
        let edges = match *self {
            RadialBins::Linear {
                r_min_arcsec: lo,
                r_max_arcsec: hi,
                count,
            } => {
                check_range(lo, hi, count, false)?;
                (0..=count)
                    .map(|k| lo + (hi - lo) * k as f64 / count as f64)
                    .collect()
            }
            RadialBins::Log {
                r_min_arcsec: lo,
                r_max_arcsec: hi,
                count,
            } => {
                check_range(lo, hi, count, true)?;
                let ratio = (hi / lo).ln();
                (0..=count)
                    .map(|k| lo * (ratio * k as f64 / count as f64).exp())
                    .collect()
            }
            RadialBins::Edges(ref e) => e.clone(),
        };
        if edges.len() < 2 || edges.len() > MAX_RADIAL_BINS + 1 {
            return bad(
                "edges",
                edges.len() as f64,
                "need between 2 and 100001 edges",
            );
        }
        if !(edges[0].is_finite() && edges[0] >= 0.0) {
            return bad(
                "edges[0]",
                edges[0],
                "the first edge must be finite and >= 0",
            );
        }
        for w in edges.windows(2) {
            if !(w[1].is_finite() && w[1] > w[0]) {
                return bad(
                    "edges",
                    w[1],
                    "edges must be finite and strictly increasing",
                );
            }
        }
        Ok(edges)
    }

    /// Bin centres in arcsec for the given edges: geometric means for log bins, else midpoints.
    fn centres(&self, edges: &[f64]) -> Vec<f64> {
        let log = matches!(self, RadialBins::Log { .. });
        edges
            .windows(2)
            .map(|w| {
                if log {
                    (w[0] * w[1]).sqrt()
                } else {
                    0.5 * (w[0] + w[1])
                }
            })
            .collect()
    }
}

/// Checks `r_min` (`> 0` when `log`, else `>= 0`) `< r_max` and `1 <= count <= MAX_RADIAL_BINS`.
fn check_range(lo: f64, hi: f64, count: usize, log: bool) -> Result<(), RadialError> {
    let bad = |field: &str, value, reason| {
        Err(crate::error::BadFieldValue::new(format!("radial_bins.{field}"), value, reason).into())
    };
    if !(lo.is_finite() && (lo > 0.0 || (!log && lo == 0.0))) {
        return bad(
            "r_min_arcsec",
            lo,
            "must be finite and >= 0 (> 0 for log bins)",
        );
    }
    if !(hi.is_finite() && hi > lo) {
        return bad(
            "r_max_arcsec",
            hi,
            "must be finite and greater than r_min_arcsec",
        );
    }
    if count == 0 || count > MAX_RADIAL_BINS {
        return bad("count", count as f64, "need between 1 and 100000 bins");
    }
    Ok(())
}

/// The azimuthally averaged `kappa` about `center` (arcsec) in `bins`, and the enclosed mass
/// `M(<R) = Sigma_cr_ref * sum over pixels of kappa * (pixel area inside R)` in Msun at every bin
/// edge, with `Sigma_cr_ref` of `plane` (Msun/arcsec^2; `kappa` at `D_ls/D_s = 1`).
///
/// The outer edge must lie inside the map (the whole circle), so that no mass is missed.
pub fn radial_profile(
    kappa: &Map,
    center: DVec2,
    bins: &RadialBins,
    plane: &LensPlane,
) -> Result<RadialProfile, RadialError> {
    let edges = bins.edges_arcsec()?;
    let g = kappa.geometry;
    let n = g.pixels;
    if n == 0 {
        return Err(RadialError::EmptyMap);
    }
    if kappa.data.len() != n * n {
        return Err(RadialError::WrongLength {
            pixels: n,
            found: kappa.data.len(),
        });
    }
    let r_max = edges[edges.len() - 1];
    let half = 0.5 * g.size_arcsec;
    let d = center - g.center;
    let limit = (half - d.x.abs()).min(half - d.y.abs());
    if !(center.is_finite() && r_max <= limit * (1.0 + 1e-12)) {
        return Err(RadialError::BeyondMap {
            r_max_arcsec: r_max,
            limit_arcsec: limit.max(0.0),
        });
    }
    // Ring 0 is the disc inside edges[0], ring k the annulus edges[k-1]..edges[k].
    let mut mass = vec![0.0; edges.len()];
    let mut area = vec![0.0; edges.len()];
    let s = g.pixel_arcsec();
    let lo = g.arcsec_to_pixel(center - DVec2::splat(r_max + s));
    let hi = g.arcsec_to_pixel(center + DVec2::splat(r_max + s));
    let clamp = |v: f64| (v.max(0.0) as usize).min(n - 1);
    for j in clamp(lo.y)..=clamp(hi.y) {
        for i in clamp(lo.x)..=clamp(hi.x) {
            let p = g.pixel_center(i, j) - center;
            let (x0, x1, y0, y1) = (p.x - 0.5 * s, p.x + 0.5 * s, p.y - 0.5 * s, p.y + 0.5 * s);
            let near = DVec2::new(x0.max(0.0).min(x1), y0.max(0.0).min(y1)).length();
            if near >= r_max {
                continue;
            }
            let value = kappa.at(i, j);
            if !value.is_finite() {
                return Err(RadialError::NotFinite { i, j, value });
            }
            let far = DVec2::new(x0.abs().max(x1.abs()), y0.abs().max(y1.abs())).length();
            let ring_near = edges.partition_point(|&e| e <= near);
            let ring_far = edges.partition_point(|&e| e < far).min(edges.len() - 1);
            let mut inside_prev = 0.0;
            for (ring, &edge) in edges.iter().enumerate().take(ring_far + 1).skip(ring_near) {
                let inside = if ring == ring_far && far <= edge {
                    s * s
                } else {
                    rect_disc_area(x0, x1, y0, y1, edge)
                };
                area[ring] += inside - inside_prev;
                mass[ring] += value * (inside - inside_prev);
                inside_prev = inside;
            }
        }
    }
    let sigma_cr = plane.sigma_cr_ref_msun_per_arcsec2;
    let enclosed_mass_msun = mass
        .iter()
        .scan(0.0, |acc, m| {
            *acc += m;
            Some(*acc * sigma_cr)
        })
        .collect();
    let kappa_mean = (1..edges.len()).map(|k| mass[k] / area[k]).collect();
    Ok(RadialProfile {
        r_arcsec: bins.centres(&edges),
        kappa: kappa_mean,
        r_edges_arcsec: edges,
        enclosed_mass_msun,
    })
}

/// Area of the rectangle `[x0, x1] x [y0, y1]` inside the disc of radius `r` about the origin
/// (same units squared), by inclusion-exclusion of origin-anchored corner rectangles.
pub fn rect_disc_area(x0: f64, x1: f64, y0: f64, y1: f64, r: f64) -> f64 {
    let c = |x: f64, y: f64| x.signum() * y.signum() * quadrant_area(x.abs(), y.abs(), r);
    (c(x1, y1) - c(x0, y1) - c(x1, y0) + c(x0, y0)).max(0.0)
}

/// Area of `[0, x] x [0, y]` (x, y >= 0) inside the disc of radius `r` about the origin:
/// `y min(x, x_c) + integral from x_c to x of sqrt(r^2 - u^2) du`, `x_c = sqrt(r^2 - y^2)`.
fn quadrant_area(x: f64, y: f64, r: f64) -> f64 {
    let (x, y) = (x.min(r), y.min(r));
    if x * x + y * y <= r * r {
        return x * y;
    }
    let xc = (r * r - y * y).max(0.0).sqrt();
    let primitive = |u: f64| {
        0.5 * (u * (r * r - u * u).max(0.0).sqrt() + r * r * (u / r).clamp(-1.0, 1.0).asin())
    };
    y * xc + primitive(x) - primitive(xc)
}

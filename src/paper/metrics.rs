//! How a reconstruction of the simulated cluster is scored against the truth (the quantities of
//! the paper's figures, section 4 and 5 of Sendra et al.).
//!
//! All maps here share one geometry (the simulation field) and are at the reference
//! normalisation `D_ls/D_s = 1` unless a distance ratio `f` is passed.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::curves::CriticalCurves;
use crate::inversion::ConstraintSet;
use crate::map::LensMaps;
use crate::map::{Map, MapGeometry};
use crate::profiles::MassComponent;

/// The region that holds arcs: the disc around the field centre out to the outermost constraint
/// pixel (the lensing data constrain nothing beyond it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArcRegion {
    pub center_arcsec: DVec2,
    pub radius_arcsec: f64,
}

impl ArcRegion {
    /// The disc centred on `center` reaching the farthest of `pixels`.
    pub fn enclosing(center: DVec2, pixels: &[DVec2]) -> Self {
        let radius_arcsec = pixels
            .iter()
            .map(|p| p.distance(center))
            .fold(0.0, f64::max);
        Self {
            center_arcsec: center,
            radius_arcsec,
        }
    }

    /// Is `p` (arcsec) inside the region.
    pub fn contains(&self, p: DVec2) -> bool {
        p.distance(self.center_arcsec) <= self.radius_arcsec
    }
}

/// The deflection error of a reconstruction for a source at distance ratio `f`.
#[derive(Debug, Clone, PartialEq)]
pub struct DeflectionError {
    /// `|f (alpha_true - alpha_rec) - offset|` per map pixel, arcsec.
    pub map: Map,
    /// The constant deflection removed before measuring, arcsec: the mean difference inside the
    /// arc region. A uniform deflection only shifts every source (the free betas absorb it), so
    /// the data cannot see it.
    pub offset_arcsec: DVec2,
    /// Median and 90th percentile of the map inside the arc region, arcsec.
    pub median_arcsec: f64,
    pub p90_arcsec: f64,
}

/// `|f (alpha_true - alpha_rec) - offset|` on the common map geometry, with its median and 90th
/// percentile inside `region` (see [`DeflectionError::offset_arcsec`]).
pub fn deflection_error(
    truth: &LensMaps,
    rec: &LensMaps,
    f: f64,
    region: &ArcRegion,
) -> DeflectionError {
    let g = truth.geometry();
    let n = g.pixels;
    let diff: Vec<DVec2> = (0..n * n)
        .map(|k| {
            f * DVec2::new(
                truth.alpha_x.data[k] - rec.alpha_x.data[k],
                truth.alpha_y.data[k] - rec.alpha_y.data[k],
            )
        })
        .collect();
    let inside: Vec<usize> = (0..n * n)
        .filter(|&k| region.contains(g.pixel_center(k % n, k / n)))
        .collect();
    let offset_arcsec = if inside.is_empty() {
        DVec2::ZERO
    } else {
        inside.iter().map(|&k| diff[k]).sum::<DVec2>() / inside.len() as f64
    };
    let data: Vec<f64> = diff.iter().map(|d| (*d - offset_arcsec).length()).collect();
    let mut values: Vec<f64> = inside.iter().map(|&k| data[k]).collect();
    values.sort_by(f64::total_cmp);
    DeflectionError {
        map: Map { geometry: g, data },
        offset_arcsec,
        median_arcsec: quantile(&values, 0.5),
        p90_arcsec: quantile(&values, 0.9),
    }
}

pub use crate::stats::quantile;

/// Mean distance between two sets of curves, arcsec: for every point of each set the distance
/// to the nearest point of the other, averaged over both directions. `None` when either set is
/// empty.
pub fn curve_distance_arcsec(a: &[Vec<DVec2>], b: &[Vec<DVec2>]) -> Option<f64> {
    let pa: Vec<DVec2> = a.iter().flatten().copied().collect();
    let pb: Vec<DVec2> = b.iter().flatten().copied().collect();
    if pa.is_empty() || pb.is_empty() {
        return None;
    }
    let one_way = |from: &[DVec2], to: &[DVec2]| {
        from.iter()
            .map(|p| {
                to.iter()
                    .map(|q| p.distance_squared(*q))
                    .fold(f64::INFINITY, f64::min)
            })
            .map(f64::sqrt)
            .sum::<f64>()
            / from.len() as f64
    };
    Some(0.5 * (one_way(&pa, &pb) + one_way(&pb, &pa)))
}

/// Is a radial critical curve recovered: some recovered radial curve of at least
/// `min_points` points lies, on average, within `tolerance_arcsec` of the true radial curves.
pub fn radial_curve_found(
    truth: &CriticalCurves,
    rec: &CriticalCurves,
    min_points: usize,
    tolerance_arcsec: f64,
) -> bool {
    let truth_points: Vec<DVec2> = truth.radial.iter().flatten().copied().collect();
    if truth_points.is_empty() {
        return false;
    }
    rec.radial
        .iter()
        .filter(|c| c.len() >= min_points)
        .any(|c| {
            let mean = c
                .iter()
                .map(|p| {
                    truth_points
                        .iter()
                        .map(|q| p.distance(*q))
                        .fold(f64::INFINITY, f64::min)
                })
                .sum::<f64>()
                / c.len() as f64;
            mean <= tolerance_arcsec
        })
}

/// The paper's source-position error (eq. 8): `sum over systems of |beta_rec - beta_true|^2`,
/// arcsec^2, over the systems present in both (matched by id).
pub fn beta_error_arcsec2(recovered: &[(String, DVec2)], truth: &[(String, DVec2)]) -> f64 {
    recovered
        .iter()
        .filter_map(|(id, b)| {
            truth
                .iter()
                .find(|(t, _)| t == id)
                .map(|(_, bt)| b.distance_squared(*bt))
        })
        .sum()
}

/// Relative error `(rec - true) / true` per radial bin (NaN where the truth is 0).
pub fn relative_errors(rec: &[f64], truth: &[f64]) -> Vec<f64> {
    rec.iter()
        .zip(truth)
        .map(|(r, t)| if *t != 0.0 { (r - t) / t } else { f64::NAN })
        .collect()
}

/// The weighted squared residual of the lens equation that the inversion minimises,
/// `sum_i w_i |theta_i - f_s alpha(theta_i) - beta_s|^2` (both axes), for any `lens`, each
/// system's `beta_s` its best for that lens (the weighted mean of `theta_i - f_s alpha`).
/// For the reconstructed lens it is `2 phi + Theta^T W Theta` of the linear system.
pub fn lens_equation_chi2(
    constraints: &ConstraintSet,
    distance_ratios: &[f64],
    lens: &dyn MassComponent,
) -> f64 {
    let mut sums = vec![(DVec2::ZERO, 0.0); constraints.systems.len()];
    let residuals: Vec<(usize, DVec2, f64)> = constraints
        .pixels
        .iter()
        .map(|p| {
            let u = p.position - distance_ratios[p.system] * lens.deflection(p.position);
            sums[p.system].0 += p.weight * u;
            sums[p.system].1 += p.weight;
            (p.system, u, p.weight)
        })
        .collect();
    residuals
        .iter()
        .map(|&(s, u, w)| {
            let (sum, weight) = sums[s];
            w * (u - sum / weight).length_squared()
        })
        .sum()
}

/// Projected mass inside `region`, Msun: `Sigma_cr_ref * sum(kappa) * pixel area` over the map
/// pixels whose centres lie in the region.
pub fn region_mass_msun(
    kappa: &Map,
    sigma_cr_ref_msun_per_arcsec2: f64,
    region: &ArcRegion,
) -> f64 {
    let g: MapGeometry = kappa.geometry;
    let n = g.pixels;
    let sum: f64 = (0..n * n)
        .filter(|&k| region.contains(g.pixel_center(k % n, k / n)))
        .map(|k| kappa.data[k])
        .sum();
    sum * g.pixel_arcsec().powi(2) * sigma_cr_ref_msun_per_arcsec2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn region_mass_of_a_uniform_sheet_is_its_area() {
        let kappa = Map::from_fn(MapGeometry::centered(100.0, 200), |_| 0.5);
        let region = ArcRegion {
            center_arcsec: DVec2::ZERO,
            radius_arcsec: 30.0,
        };
        let m = region_mass_msun(&kappa, 2.0, &region);
        let expected = 0.5 * 2.0 * std::f64::consts::PI * 900.0;
        // Pixel-centre counting of a disc of 60 pixels across: ~1% area error.
        assert!((m / expected - 1.0).abs() < 0.01, "{m} vs {expected}");
    }

    #[test]
    fn quantiles_interpolate() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert!((quantile(&v, 0.9) - 4.6).abs() < 1e-12);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn curve_distance_of_concentric_circles_is_their_gap() {
        let circle = |r: f64| -> Vec<DVec2> {
            (0..720)
                .map(|k| {
                    let t = k as f64 * std::f64::consts::TAU / 720.0;
                    DVec2::new(r * t.cos(), r * t.sin())
                })
                .collect()
        };
        let d = curve_distance_arcsec(&[circle(40.0)], &[circle(43.0)]).unwrap();
        assert!((d - 3.0).abs() < 1e-3, "{d}");
        assert!(curve_distance_arcsec(&[], &[circle(1.0)]).is_none());
    }

    #[test]
    fn beta_error_sums_matched_systems_only() {
        let rec = vec![
            ("1".to_string(), DVec2::new(1.0, 0.0)),
            ("2".to_string(), DVec2::new(0.0, 2.0)),
            ("9".to_string(), DVec2::new(5.0, 5.0)),
        ];
        let truth = vec![
            ("1".to_string(), DVec2::ZERO),
            ("2".to_string(), DVec2::ZERO),
        ];
        assert_eq!(beta_error_arcsec2(&rec, &truth), 5.0);
    }
}

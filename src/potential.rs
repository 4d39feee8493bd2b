//! The lensing potential and arrival times ([method §6]).
//!
//! The potential `psi_ref` (arcsec^2, `D_ls/D_s = 1`) is defined by `alpha_ref = grad psi_ref`;
//! only its differences are observable, so every function here gives differences or fixes the
//! constant where it says so. No profile needs a formula of its own: a difference is the line
//! integral of the deflection, which every [`MassComponent`] already has,
//!
//! ```text
//! psi_ref(b) - psi_ref(a) = integral from a to b of alpha_ref . dl       (straight segment)
//! ```
//!
//! computed by adaptive Gauss-Legendre quadrature ([`potential_difference`]), and a map of it
//! is the cumulative integral of the deflection maps ([`potential_map`]), so the cells and the
//! galaxies of a reconstruction cost nothing beyond the maps already made by FFT.
//!
//! A source at `beta` seen at `theta` arrives after
//!
//! ```text
//! t(theta) = D_dt / c * phi(theta),   phi = |theta - beta|^2 / 2 - f psi_ref(theta)
//! D_dt = (1 + z_l) D_l D_s / D_ls                                    (time-delay distance)
//! ```
//!
//! with `phi` (the Fermat potential) in rad^2 and `f = D_ls/D_s`; [`arrival_time_days`]
//! converts. The delay between two images of the same source is the difference of their `t`.
//!
//! [method §6]: crate::method#6-products

use glam::DVec2;

use crate::cosmology::{CosmologyError, LensPlane};
use crate::map::{LensMaps, Map};
use crate::profiles::MassComponent;
use crate::units::{ARCSEC_PER_RAD, C_KM_S, MPC_M};

/// Seconds in a day.
const DAY_S: f64 = 86_400.0;

/// Abscissae and weights of 8-point Gauss-Legendre quadrature on `[-1, 1]` (half of them:
/// the rule is symmetric).
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// Relative accuracy of [`potential_difference`], against the scale `|b - a| max|alpha|`.
const LINE_RTOL: f64 = 1e-10;
/// Deepest bisection of a segment (a piece 2^-40 of the whole: far below any scale of a lens).
const LINE_MAX_DEPTH: u32 = 40;

/// `integral_a^b alpha . dl` on one piece by 8-point Gauss-Legendre.
fn gauss_piece(lens: &dyn MassComponent, a: DVec2, b: DVec2) -> (f64, f64) {
    let mid = (a + b) / 2.0;
    let half = (b - a) / 2.0;
    let mut sum = 0.0;
    let mut largest = 0.0_f64;
    for (x, w) in GL8 {
        for s in [-x, x] {
            let alpha = lens.deflection(mid + s * half);
            largest = largest.max(alpha.length());
            sum += w * alpha.dot(half);
        }
    }
    (sum, largest)
}

fn adaptive(
    lens: &dyn MassComponent,
    a: DVec2,
    b: DVec2,
    whole: f64,
    tolerance: f64,
    depth: u32,
) -> f64 {
    let m = (a + b) / 2.0;
    let (left, _) = gauss_piece(lens, a, m);
    let (right, _) = gauss_piece(lens, m, b);
    let halves = left + right;
    if (halves - whole).abs() <= tolerance || depth >= LINE_MAX_DEPTH {
        return halves;
    }
    adaptive(lens, a, m, left, tolerance / 2.0, depth + 1)
        + adaptive(lens, m, b, right, tolerance / 2.0, depth + 1)
}

/// `psi_ref(to) - psi_ref(from)` in arcsec^2 (`D_ls/D_s = 1`): the deflection integrated along
/// the straight segment, bisected until the halves agree with the whole to `1e-10` of
/// `|to - from| max|alpha|`. A segment through a singular centre (a point mass) still ends, at
/// the depth limit, with the value of the integrable part.
pub fn potential_difference(lens: &dyn MassComponent, from: DVec2, to: DVec2) -> f64 {
    if from == to {
        return 0.0;
    }
    let (whole, largest) = gauss_piece(lens, from, to);
    let tolerance = LINE_RTOL * (to - from).length() * largest.max(1e-12);
    adaptive(lens, from, to, whole, tolerance, 0)
}

/// `int_{k}^{k+1} g` from samples `g[k-1..=k+2]` a unit apart: the cubic through the four
/// (error `h^5 g''''`), or the trapezoid at the ends of the samples and next to a sample
/// without data (NaN).
fn step_integral(g: &[f64], k: usize) -> f64 {
    if k >= 1 && k + 2 < g.len() && g[k - 1].is_finite() && g[k + 2].is_finite() {
        (-g[k - 1] + 13.0 * g[k] + 13.0 * g[k + 1] - g[k + 2]) / 24.0
    } else {
        (g[k] + g[k + 1]) / 2.0
    }
}

/// Cumulative integral of `g` (unit spacing) from index `origin`: `out[origin] = 0`.
fn cumulative(g: &[f64], origin: usize) -> Vec<f64> {
    let mut out = vec![0.0; g.len()];
    for k in origin..g.len().saturating_sub(1) {
        out[k + 1] = out[k] + step_integral(g, k);
    }
    for k in (0..origin).rev() {
        out[k] = out[k + 1] - step_integral(g, k);
    }
    out
}

/// The potential `psi_ref` (arcsec^2, `D_ls/D_s = 1`) on the pixels of `maps`, zero at the
/// centre pixel `(n/2, n/2)`: the deflection maps integrated from there, along the centre row
/// and then up each column, and along the centre column and then along each row, averaged
/// (a deflection from a real potential gives the same along both; the average halves what
/// differs). Each step between pixel centres uses the cubic through four samples, so the error
/// is of order `h^4 alpha'''` per pixel `h` where the deflection is smooth. Pixels without data
/// (NaN deflection, e.g. the blank borders of published maps) stay NaN, and a pixel whose one
/// path crosses them takes the other path's value.
pub fn potential_map(maps: &LensMaps) -> Map {
    let g = maps.geometry();
    let n = g.pixels;
    let h = g.pixel_arcsec();
    let c = n / 2;
    let ax = &maps.alpha_x;
    let ay = &maps.alpha_y;
    let mut data = vec![0.0; n * n];
    if n == 0 {
        return Map { geometry: g, data };
    }
    // Row first: along the centre row in x, then up every column in y.
    let mut row_first = vec![0.0; n * n];
    let row: Vec<f64> = (0..n).map(|i| ax.at(i, c) * h).collect();
    let along_row = cumulative(&row, c);
    for (i, base) in along_row.iter().enumerate() {
        let column: Vec<f64> = (0..n).map(|j| ay.at(i, j) * h).collect();
        for (j, v) in cumulative(&column, c).into_iter().enumerate() {
            row_first[j * n + i] = base + v;
        }
    }
    // Column first: along the centre column in y, then along every row in x.
    let column: Vec<f64> = (0..n).map(|j| ay.at(c, j) * h).collect();
    let along_column = cumulative(&column, c);
    for (j, base) in along_column.iter().enumerate() {
        let row: Vec<f64> = (0..n).map(|i| ax.at(i, j) * h).collect();
        for (i, v) in cumulative(&row, c).into_iter().enumerate() {
            let k = j * n + i;
            let (a, b) = (row_first[k], base + v);
            data[k] = if !(ax.data[k].is_finite() && ay.data[k].is_finite()) {
                f64::NAN
            } else if a.is_finite() && b.is_finite() {
                0.5 * (a + b)
            } else if a.is_finite() {
                a
            } else {
                b
            };
        }
    }
    Map { geometry: g, data }
}

/// `psi_ref` at `p` (arcsec) from a map of it and the deflection maps it came from: the
/// nearest pixel centre's value plus the deflection integrated (trapezoid) to `p`, which is
/// far more accurate than interpolating `psi` itself (its curvature is `kappa`-sized). `None`
/// outside the map.
pub fn potential_at(psi: &Map, maps: &LensMaps, p: DVec2) -> Option<f64> {
    let g = psi.geometry;
    let n = g.pixels as f64;
    let q = g.arcsec_to_pixel(p);
    if !(q.x >= -0.5 && q.x <= n - 0.5 && q.y >= -0.5 && q.y <= n - 0.5) {
        return None;
    }
    let q = q.round().clamp(DVec2::ZERO, DVec2::splat(n - 1.0));
    let (i, j) = (q.x as usize, q.y as usize);
    let centre = g.pixel_center(i, j);
    let alpha = |r: DVec2| DVec2::new(maps.alpha_x.sample_cubic(r), maps.alpha_y.sample_cubic(r));
    Some(psi.at(i, j) + (p - centre).dot(alpha(centre) + alpha(p)) / 2.0)
}

/// The time-delay distance `D_dt = (1 + z_l) D_l D_s / D_ls` in Mpc for a source at `z_s`.
pub fn time_delay_distance_mpc(plane: &LensPlane, z_source: f64) -> Result<f64, CosmologyError> {
    let f = plane.distance_ratio(z_source)?;
    Ok((1.0 + plane.z_lens) * plane.d_l_mpc / f)
}

/// The arrival time in days of a ray seen at `theta` from a source at `beta` (both arcsec),
/// given `psi_ref(theta)` (arcsec^2, from any fixed origin: the same for every image compared),
/// for a source at `z_s`. Only differences between images of one source mean anything.
pub fn arrival_time_days(
    plane: &LensPlane,
    z_source: f64,
    theta: DVec2,
    beta: DVec2,
    psi_ref: f64,
) -> Result<f64, CosmologyError> {
    let f = plane.distance_ratio(z_source)?;
    let d_dt_m = time_delay_distance_mpc(plane, z_source)? * MPC_M;
    let fermat_arcsec2 = (theta - beta).length_squared() / 2.0 - f * psi_ref;
    let fermat_rad2 = fermat_arcsec2 / (ARCSEC_PER_RAD * ARCSEC_PER_RAD);
    Ok(d_dt_m / (C_KM_S * 1e3) * fermat_rad2 / DAY_S)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::MapGeometry;
    use crate::profiles::{PointMass, Sis};

    #[test]
    fn sis_potential_is_theta_e_times_radius() {
        // psi = theta_E |x| for an SIS.
        let sis = Sis::from_theta_e(DVec2::new(1.0, -2.0), 20.0).unwrap();
        let c = DVec2::new(1.0, -2.0);
        for (a, b) in [
            (DVec2::new(5.0, 3.0), DVec2::new(-17.0, 9.0)),
            // Through the centre, where alpha jumps.
            (DVec2::new(-9.0, -2.0), DVec2::new(14.0, -2.0)),
        ] {
            let want = 20.0 * ((b - c).length() - (a - c).length());
            let got = potential_difference(&sis, a, b);
            assert!(
                (got - want).abs() < 1e-8 * want.abs().max(1.0),
                "{got} {want}"
            );
        }
    }

    #[test]
    fn point_mass_potential_is_logarithmic() {
        // psi = theta_E^2 ln |x|.
        let pm = PointMass::from_theta_e(DVec2::ZERO, 3.0).unwrap();
        let (a, b) = (DVec2::new(0.5, 0.2), DVec2::new(-4.0, 7.0));
        let want = 9.0 * (b.length() / a.length()).ln();
        let got = potential_difference(&pm, a, b);
        assert!((got - want).abs() < 1e-9 * want.abs(), "{got} {want}");
    }

    #[test]
    fn map_agrees_with_line_integrals() {
        let sis = Sis::from_theta_e(DVec2::new(0.3, -0.2), 10.0).unwrap();
        let g = MapGeometry::centered(60.0, 240);
        let maps = LensMaps::from_lens(&sis, g);
        let psi = potential_map(&maps);
        let origin = g.pixel_center(120, 120);
        for p in [DVec2::new(17.3, -8.1), DVec2::new(-25.0, 22.0)] {
            let want = potential_difference(&sis, origin, p);
            let got = potential_at(&psi, &maps, p).unwrap();
            // The cusp at the centre is smoothed by the pixels: a few 1e-3 of the difference.
            assert!((got - want).abs() < 2e-3 * want.abs(), "{got} {want}");
        }
        assert_eq!(potential_at(&psi, &maps, DVec2::new(31.0, 0.0)), None);
    }
}

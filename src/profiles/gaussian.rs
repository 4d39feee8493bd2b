//! Circular Gaussian of mass: the WSLAP grid cell ([method §2]).
//!
//! With `b^2 = K m / D_l` (arcsec^2, `K` = [`point_mass_deflection_arcsec2`]), width `s` (arcsec),
//! `d = theta - theta_0`, `r = |d|` and `u = r^2 / (2 s^2)`:
//! `kappa = m / (2 pi s^2 Sigma_cr_ref) e^-u = b^2 / (2 s^2) e^-u`,
//! `alpha = b^2 (1 - e^-u) d / r^2`, which tends to `b^2 d / (2 s^2)` at `r = 0`.
//! The plain `gaussian_unit_*` functions are for `b^2 = 1` and are what a grid solver calls.
//!
//! [method §2]: crate::method#2-mass-components

use glam::DVec2;

use super::error::{require_finite_center, require_positive, ProfileError};
use super::MassComponent;
use crate::cosmology::LensPlane;
use crate::units::point_mass_deflection_arcsec2;

/// Below this `u = r^2/(2 s^2)` the radial factors are summed as power series: the closed forms
/// lose digits to cancellation there, the series converge to machine precision in
/// [`SERIES_TERMS`] terms.
const SERIES_MAX_U: f64 = 0.5;
/// Number of series terms: `0.5^16 / 16!` is far below 1e-16.
const SERIES_TERMS: i32 = 16;

/// A Gaussian of mass at `center` (arcsec).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gaussian {
    center: DVec2,
    mass_msun: f64,
    sigma_arcsec: f64,
    /// `K m / D_l` in arcsec^2.
    b2_arcsec2: f64,
}

impl Gaussian {
    /// A Gaussian of total mass `mass_msun` (Msun) and width `sigma_arcsec` (arcsec) on `plane`.
    pub fn new(
        center: DVec2,
        mass_msun: f64,
        sigma_arcsec: f64,
        plane: &LensPlane,
    ) -> Result<Self, ProfileError> {
        Ok(Self {
            center: require_finite_center("gaussian", center)?,
            mass_msun: require_positive("gaussian", "mass", mass_msun)?,
            sigma_arcsec: require_positive("gaussian", "sigma", sigma_arcsec)?,
            b2_arcsec2: point_mass_deflection_arcsec2() * mass_msun / plane.d_l_mpc,
        })
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }

    /// Total mass in Msun.
    pub fn mass_msun(&self) -> f64 {
        self.mass_msun
    }

    /// Width (standard deviation) in arcsec.
    pub fn sigma_arcsec(&self) -> f64 {
        self.sigma_arcsec
    }

    /// Squared reference Einstein radius of the whole mass, `K m / D_l`, in arcsec^2.
    pub fn b2_arcsec2(&self) -> f64 {
        self.b2_arcsec2
    }
}

/// Beyond this `u`, `e^-u` is below the smallest f64 and the Gaussian acts as a point mass.
const POINT_LIKE_U: f64 = 1.0e3;

/// `(1 - e^-u) / u`, accurate for all `u >= 0` (1 at `u = 0`).
fn one_minus_exp_over_u(u: f64) -> f64 {
    if u < SERIES_MAX_U {
        // sum_{n>=0} (-u)^n / (n+1)!
        let mut term = 1.0;
        let mut sum = 1.0;
        for n in 1..SERIES_TERMS {
            term *= -u / f64::from(n + 1);
            sum += term;
        }
        sum
    } else {
        -(-u).exp_m1() / u
    }
}

/// `(1 - (1 + u) e^-u) / u`, accurate for all `u >= 0` (0 at `u = 0`, `u/2` for small `u`).
fn one_minus_one_plus_u_exp_over_u(u: f64) -> f64 {
    if u < SERIES_MAX_U {
        // sum_{n>=2} (-1)^n (n-1) u^(n-1) / n!
        let mut pow_over_fact = 0.5 * u; // u^(n-1) / n! for n = 2
        let mut sum = pow_over_fact;
        for n in 3..SERIES_TERMS + 2 {
            pow_over_fact *= u / f64::from(n);
            let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
            sum += sign * f64::from(n - 1) * pow_over_fact;
        }
        sum
    } else if u < POINT_LIKE_U {
        (1.0 - (1.0 + u) * (-u).exp()) / u
    } else {
        1.0 / u
    }
}

/// `r` and `u = r^2 / (2 s^2)` without overflow for any finite offset.
fn radius_and_u(dx: f64, dy: f64, sigma_arcsec: f64) -> (f64, f64) {
    let r = dx.hypot(dy);
    let t = r / sigma_arcsec;
    (r, 0.5 * t * t)
}

/// Convergence of a unit Gaussian (`b^2 = K m / D_l = 1` arcsec^2) at offset `(dx, dy)`
/// arcsec: `e^-u / (2 s^2)` with `u = r^2 / (2 s^2)`, in 1/arcsec^2.
pub fn gaussian_unit_kappa(dx: f64, dy: f64, sigma_arcsec: f64) -> f64 {
    let (_, u) = radius_and_u(dx, dy, sigma_arcsec);
    (-u).exp() / (2.0 * sigma_arcsec * sigma_arcsec)
}

/// Deflection of a unit Gaussian (`b^2 = 1` arcsec^2) at offset `(dx, dy)` arcsec:
/// `(1 - e^-u) (dx, dy) / r^2` in 1/arcsec, equal to `(dx, dy) / (2 s^2)` at `r = 0`.
/// Multiply by `K m / D_l` for a mass `m` ([method §2]).
///
/// [method §2]: crate::method#2-mass-components
pub fn gaussian_unit_deflection(dx: f64, dy: f64, sigma_arcsec: f64) -> (f64, f64) {
    let (r, u) = radius_and_u(dx, dy, sigma_arcsec);
    if u < SERIES_MAX_U {
        // (1 - e^-u) / r^2 = ((1 - e^-u) / u) / (2 s^2), finite at r = 0.
        let g = one_minus_exp_over_u(u) / (2.0 * sigma_arcsec * sigma_arcsec);
        (g * dx, g * dy)
    } else {
        let a = -(-u).exp_m1() / r;
        (a * (dx / r), a * (dy / r))
    }
}

/// Beyond this `u = r^2 / (2 s^2)`, `1 - e^-u` rounds to 1 in double precision
/// (`e^-40 = 4e-18`): the cell deflects as a point mass.
const CELL_POINT_LIKE_U: f64 = 40.0;

/// Deflection of a unit Gaussian cell (`K m / D_l = 1` arcsec^2) at offset `(dx, dy)` arcsec,
/// given `inv_2s2 = 1 / (2 s^2)` in 1/arcsec^2: `(1 - e^-u) (dx, dy) / r^2`, `u = r^2 inv_2s2`,
/// equal to `(dx, dy) inv_2s2` at `r = 0` ([method §2]). The same function as
/// [`gaussian_unit_deflection`] (to ~1e-15 relative), written for the inner loops of the
/// linear system and the grid's maps: one `exp_m1` near the cell, none far from it.
///
/// [method §2]: crate::method#2-mass-components
#[inline]
pub fn cell_unit_deflection(dx: f64, dy: f64, inv_2s2: f64) -> (f64, f64) {
    let r2 = dx * dx + dy * dy;
    let u = r2 * inv_2s2;
    let g = if u > CELL_POINT_LIKE_U {
        1.0 / r2
    } else if u > 0.0 {
        -(-u).exp_m1() / r2
    } else {
        inv_2s2
    };
    (g * dx, g * dy)
}

/// Hessian `[psi_xx, psi_xy, psi_yy]` of a unit Gaussian (`b^2 = 1` arcsec^2) at offset
/// `(dx, dy)` arcsec, in 1/arcsec^2. With `G(t) = (1 - e^-u)/t`, `t = r^2`:
/// `psi_ij = G delta_ij + 2 G'(t) d_i d_j`, `2 G'(t) r^2 = -2 (1 - (1 + u) e^-u) / u / (2 s^2)`;
/// `[1, 0, 1] / (2 s^2)` at `r = 0`.
pub fn gaussian_unit_hessian(dx: f64, dy: f64, sigma_arcsec: f64) -> [f64; 3] {
    let two_s2 = 2.0 * sigma_arcsec * sigma_arcsec;
    let (r, u) = radius_and_u(dx, dy, sigma_arcsec);
    let g = one_minus_exp_over_u(u) / two_s2;
    if r == 0.0 {
        return [g, 0.0, g];
    }
    let (ux, uy) = (dx / r, dy / r);
    let c = -2.0 * one_minus_one_plus_u_exp_over_u(u) / two_s2;
    [g + c * ux * ux, c * ux * uy, g + c * uy * uy]
}

impl MassComponent for Gaussian {
    fn kappa(&self, p: DVec2) -> f64 {
        let d = p - self.center;
        self.b2_arcsec2 * gaussian_unit_kappa(d.x, d.y, self.sigma_arcsec)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        let d = p - self.center;
        let (ax, ay) = gaussian_unit_deflection(d.x, d.y, self.sigma_arcsec);
        DVec2::new(ax, ay) * self.b2_arcsec2
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        let d = p - self.center;
        gaussian_unit_hessian(d.x, d.y, self.sigma_arcsec).map(|h| h * self.b2_arcsec2)
    }
}

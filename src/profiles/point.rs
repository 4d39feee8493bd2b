//! Point mass ([method §1] and [§2]).
//!
//! With `b^2 = K m / D_l` (`K` = [`point_mass_deflection_arcsec2`], the squared Einstein radius
//! for `D_ls/D_s = 1`) and `d = theta - theta_0`, `r = |d|`:
//! `psi = b^2 ln r`, `alpha = b^2 d / r^2`, `kappa = 0` for `r > 0`.
//!
//! Inside the tiny radius [`POINT_CORE_ARCSEC`] the mass is spread uniformly over the disk:
//! `kappa = b^2 / r_c^2`, `alpha = b^2 d / r_c^2`, so every field is finite (deflection 0 at
//! `r = 0`) and the deflection outside the core is exact.
//!
//! [method §1]: crate::method#1-frames-and-units
//! [§2]: crate::method#2-mass-components

use glam::DVec2;

use super::error::{require_finite_center, require_positive, ProfileError};
use super::MassComponent;
use crate::cosmology::LensPlane;
use crate::units::point_mass_deflection_arcsec2;

/// Radius in arcsec of the uniform disk that stands in for the point at its centre (1e-8 arcsec,
/// far below any pixel; `1/r^4` stays finite).
pub const POINT_CORE_ARCSEC: f64 = 1.0e-8;

/// A point mass at `center` (arcsec).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    center: DVec2,
    /// Squared reference Einstein radius `K m / D_l` in arcsec^2.
    theta_e2_ref_arcsec2: f64,
}

impl PointMass {
    /// A point of `mass_msun` (Msun) on `plane`: `theta_E,ref^2 = K m / D_l` ([method §1]).
    ///
    /// [method §1]: crate::method#1-frames-and-units
    pub fn new(center: DVec2, mass_msun: f64, plane: &LensPlane) -> Result<Self, ProfileError> {
        let mass_msun = require_positive("point", "mass", mass_msun)?;
        let theta_e2 = point_mass_deflection_arcsec2() * mass_msun / plane.d_l_mpc;
        Self::from_theta_e(center, theta_e2.sqrt())
    }

    /// A point mass with reference Einstein radius `theta_e_ref_arcsec` (arcsec).
    pub fn from_theta_e(center: DVec2, theta_e_ref_arcsec: f64) -> Result<Self, ProfileError> {
        let theta_e = require_positive("point", "theta_e", theta_e_ref_arcsec)?;
        Ok(Self {
            center: require_finite_center("point", center)?,
            theta_e2_ref_arcsec2: theta_e * theta_e,
        })
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }

    /// Einstein radius for `D_ls/D_s = 1`, in arcsec.
    pub fn theta_e_ref_arcsec(&self) -> f64 {
        self.theta_e2_ref_arcsec2.sqrt()
    }
}

/// Point-mass convergence at offset `d` (arcsec): 0 outside the core, `b^2 / r_c^2` inside
/// (`b^2` in arcsec^2).
pub fn point_kappa(d: DVec2, theta_e2_arcsec2: f64) -> f64 {
    if d.x.hypot(d.y) < POINT_CORE_ARCSEC {
        theta_e2_arcsec2 / (POINT_CORE_ARCSEC * POINT_CORE_ARCSEC)
    } else {
        0.0
    }
}

/// Point-mass deflection `b^2 d / r^2` in arcsec at offset `d` (arcsec); `b^2 d / r_c^2` inside
/// the core.
pub fn point_deflection(d: DVec2, theta_e2_arcsec2: f64) -> DVec2 {
    let r = d.x.hypot(d.y);
    if r < POINT_CORE_ARCSEC {
        d * (theta_e2_arcsec2 / (POINT_CORE_ARCSEC * POINT_CORE_ARCSEC))
    } else {
        (d / r) * (theta_e2_arcsec2 / r)
    }
}

/// Point-mass Hessian `[psi_xx, psi_xy, psi_yy] = b^2 / r^4 [dy^2 - dx^2, -2 dx dy, dx^2 - dy^2]`
/// at offset `d` (arcsec); `[b^2 / r_c^2, 0, b^2 / r_c^2]` inside the core.
pub fn point_hessian(d: DVec2, theta_e2_arcsec2: f64) -> [f64; 3] {
    let r = d.x.hypot(d.y);
    if r < POINT_CORE_ARCSEC {
        let k = theta_e2_arcsec2 / (POINT_CORE_ARCSEC * POINT_CORE_ARCSEC);
        return [k, 0.0, k];
    }
    // Unit vector first, so that nothing overflows for any finite offset.
    let (ux, uy, a) = (d.x / r, d.y / r, theta_e2_arcsec2 / r / r);
    let diff = ux * ux - uy * uy;
    [-a * diff, -2.0 * a * ux * uy, a * diff]
}

impl MassComponent for PointMass {
    fn kappa(&self, p: DVec2) -> f64 {
        point_kappa(p - self.center, self.theta_e2_ref_arcsec2)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        point_deflection(p - self.center, self.theta_e2_ref_arcsec2)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        point_hessian(p - self.center, self.theta_e2_ref_arcsec2)
    }
}

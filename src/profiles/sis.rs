//! Singular isothermal sphere ([method §2]).
//!
//! With `theta_E = 4 pi (sigma_v / c)^2` (radians, `D_ls/D_s = 1`) and `r = |theta - theta_0|`:
//! `psi = theta_E r`, `kappa = theta_E / (2 r)`, `alpha = theta_E (theta - theta_0) / r`.
//!
//! At the centre the SIS is singular. Inside the tiny radius [`SIS_CORE_ARCSEC`] the mass that
//! the SIS holds there (`pi theta_E r_c Sigma_cr`) is spread uniformly over the disk instead:
//! `kappa = theta_E / r_c`, `alpha = theta_E (theta - theta_0) / r_c`, so every field is finite
//! (deflection 0 at `r = 0`, a large finite kappa) and the enclosed mass is unchanged for
//! `r >= r_c`.
//!
//! [method §2]: crate::method#2-mass-components

use glam::DVec2;

use super::error::{require_finite_center, require_positive, require_sigma_v, ProfileError};
use super::MassComponent;
use crate::units::{ARCSEC_PER_RAD, C_KM_S};

/// Radius in arcsec inside which the SIS is replaced by a uniform disk of the same mass;
/// far below any pixel (1e-8 arcsec), large enough that `1/r^3` stays finite.
pub const SIS_CORE_ARCSEC: f64 = 1.0e-8;

/// A singular isothermal sphere centred on `center` (arcsec).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sis {
    center: DVec2,
    theta_e_ref_arcsec: f64,
}

impl Sis {
    /// An SIS with 1-D velocity dispersion `sigma_v_km_s` [km/s]:
    /// `theta_E,ref = 4 pi (sigma_v / c)^2` rad (for `D_ls/D_s = 1`).
    pub fn new(center: DVec2, sigma_v_km_s: f64) -> Result<Self, ProfileError> {
        let sigma_v_km_s = require_sigma_v("sis", sigma_v_km_s)?;
        Self::from_theta_e(center, sis_theta_e_arcsec(sigma_v_km_s))
    }

    /// An SIS with reference Einstein radius `theta_e_ref_arcsec` (arcsec, `D_ls/D_s = 1`).
    pub fn from_theta_e(center: DVec2, theta_e_ref_arcsec: f64) -> Result<Self, ProfileError> {
        Ok(Self {
            center: require_finite_center("sis", center)?,
            theta_e_ref_arcsec: require_positive("sis", "theta_e", theta_e_ref_arcsec)?,
        })
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }

    /// Einstein radius for `D_ls/D_s = 1`, in arcsec.
    pub fn theta_e_ref_arcsec(&self) -> f64 {
        self.theta_e_ref_arcsec
    }
}

/// SIS Einstein radius `4 pi (sigma_v / c)^2` in arcsec for `D_ls/D_s = 1`
/// (`sigma_v` in km/s; 1000 km/s gives about 28.8 arcsec).
pub fn sis_theta_e_arcsec(sigma_v_km_s: f64) -> f64 {
    let beta = sigma_v_km_s / C_KM_S;
    4.0 * std::f64::consts::PI * beta * beta * ARCSEC_PER_RAD
}

/// SIS convergence `theta_E / (2 r)` at offset `d` (arcsec) from the centre; `theta_E / r_c`
/// inside the core `r < r_c` ([`SIS_CORE_ARCSEC`]).
pub fn sis_kappa(d: DVec2, theta_e_arcsec: f64) -> f64 {
    let r = d.x.hypot(d.y);
    if r < SIS_CORE_ARCSEC {
        theta_e_arcsec / SIS_CORE_ARCSEC
    } else {
        0.5 * theta_e_arcsec / r
    }
}

/// SIS deflection `theta_E d / r` in arcsec at offset `d` (arcsec); `theta_E d / r_c` in the core.
pub fn sis_deflection(d: DVec2, theta_e_arcsec: f64) -> DVec2 {
    let r = d.x.hypot(d.y);
    if r < SIS_CORE_ARCSEC {
        d * (theta_e_arcsec / SIS_CORE_ARCSEC)
    } else {
        (d / r) * theta_e_arcsec
    }
}

/// SIS Hessian `[psi_xx, psi_xy, psi_yy] = theta_E / r^3 [dy^2, -dx dy, dx^2]` at offset `d`
/// (arcsec); `[theta_E / r_c, 0, theta_E / r_c]` in the core.
pub fn sis_hessian(d: DVec2, theta_e_arcsec: f64) -> [f64; 3] {
    let r = d.x.hypot(d.y);
    if r < SIS_CORE_ARCSEC {
        let k = theta_e_arcsec / SIS_CORE_ARCSEC;
        return [k, 0.0, k];
    }
    // Unit vector first, so that nothing overflows for any finite offset.
    let (ux, uy, a) = (d.x / r, d.y / r, theta_e_arcsec / r);
    [a * uy * uy, -a * ux * uy, a * ux * ux]
}

impl MassComponent for Sis {
    fn kappa(&self, p: DVec2) -> f64 {
        sis_kappa(p - self.center, self.theta_e_ref_arcsec)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        sis_deflection(p - self.center, self.theta_e_ref_arcsec)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        sis_hessian(p - self.center, self.theta_e_ref_arcsec)
    }
}

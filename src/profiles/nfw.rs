//! Spherical NFW halo (Navarro, Frenk & White 1997; lensing: Bartelmann 1996), [method §2],
//! normalised by M200 and c200 as lenstronomy's `LensCosmo.nfw_physical2angle`.
//!
//! With `x = R / r_s` and `kappa_s = rho_s r_s / Sigma_cr_ref` (`D_ls/D_s = 1`):
//! `kappa = 2 kappa_s G(x)`, mean convergence inside `R` `= 4 kappa_s h(x) / x^2`,
//! `alpha = 4 kappa_s r_s h(x) / x` along `d / R`, `M_2D(R) = 4 pi kappa_s Sigma_cr r_s^2 h(x)`
//! (`G`, `h` in [`nfw_terms`]). The Hessian uses `gamma_t = mean kappa - kappa`.
//! The convergence diverges like `ln(1/x)` at the centre: inside `x <` [`X_FLOOR`] it is held
//! at its value there; the deflection goes to zero and the shear tends to `kappa_s`.
//!
//! [method §2]: crate::method#2-mass-components

use glam::DVec2;

use super::error::{require_finite_center, ProfileError};
use super::nfw_math::{
    axisymmetric_deflection, axisymmetric_hessian, nfw_scales, nfw_terms, X_FLOOR,
};
use super::MassComponent;
use crate::cosmology::LensPlane;

/// A spherical NFW halo.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nfw {
    center: DVec2,
    r_s_arcsec: f64,
    kappa_s: f64,
    m200_msun: f64,
    c200: f64,
    r200_arcsec: f64,
    sigma_cr_ref_msun_per_arcsec2: f64,
}

impl Nfw {
    /// An NFW halo at `center` (arcsec) with `m200_msun` (Msun) inside `r200` (mean density
    /// 200 rho_crit(z_l)) and concentration `c200 = r200 / r_s`, on `plane`.
    /// Errors name the field: `x`/`y` not finite, `m200` not in (0, 1e18], `c200` not in
    /// [1e-3, 1e3] (or NaN).
    pub fn new(
        center: DVec2,
        m200_msun: f64,
        c200: f64,
        plane: &LensPlane,
    ) -> Result<Self, ProfileError> {
        let center = require_finite_center("nfw", center)?;
        let scales = nfw_scales("nfw", m200_msun, c200, plane)?;
        Ok(Self {
            center,
            r_s_arcsec: scales.r_s_arcsec,
            kappa_s: scales.kappa_s,
            m200_msun,
            c200,
            r200_arcsec: scales.r200_arcsec,
            sigma_cr_ref_msun_per_arcsec2: plane.sigma_cr_ref_msun_per_arcsec2,
        })
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }
    /// Scale radius `r_s = r200 / c200` in arcsec.
    pub fn r_s_arcsec(&self) -> f64 {
        self.r_s_arcsec
    }
    /// `kappa_s = rho_s r_s / Sigma_cr_ref` (dimensionless, `D_ls/D_s = 1`).
    pub fn kappa_s(&self) -> f64 {
        self.kappa_s
    }
    /// M200 in Msun.
    pub fn m200_msun(&self) -> f64 {
        self.m200_msun
    }
    /// Concentration `c200`.
    pub fn c200(&self) -> f64 {
        self.c200
    }
    /// `r200` in arcsec.
    pub fn r200_arcsec(&self) -> f64 {
        self.r200_arcsec
    }
    /// Deflection at `R = r_s` in arcsec, `4 kappa_s r_s (1 + ln 1/2)` (lenstronomy's
    /// `alpha_Rs` for `D_ls/D_s = 1`).
    pub fn alpha_rs_arcsec(&self) -> f64 {
        4.0 * self.kappa_s * self.r_s_arcsec * (1.0 - std::f64::consts::LN_2)
    }
    /// Convergence, deflection (arcsec) and Hessian `[xx, xy, yy]` at `p` (arcsec) from one
    /// evaluation of `F`, `G`, `h` (cheaper than the three trait calls).
    pub fn fields(&self, p: DVec2) -> (f64, DVec2, [f64; 3]) {
        let d = p - self.center;
        let r = d.length();
        let x = r / self.r_s_arcsec;
        let t = nfw_terms(x);
        let (kappa, mean) = (2.0 * self.kappa_s * t.g, mean_kappa(x, t.h, self.kappa_s));
        (
            kappa,
            axisymmetric_deflection(d, mean),
            axisymmetric_hessian(d, r, kappa, mean),
        )
    }
    /// Projected mass inside the cylinder of radius `r_arcsec` (arcsec) about the centre, in
    /// Msun: [`nfw_mass_cylinder_msun`].
    pub fn mass_cylinder_msun(&self, r_arcsec: f64) -> f64 {
        nfw_mass_cylinder_msun(
            r_arcsec,
            self.r_s_arcsec,
            self.kappa_s,
            self.sigma_cr_ref_msun_per_arcsec2,
        )
    }
}

/// NFW projected mass inside radius `r_arcsec` in Msun:
/// `M_2D = 4 pi kappa_s Sigma_cr_ref r_s^2 h(R / r_s)` (`r_s` in arcsec, `Sigma_cr_ref` in
/// Msun/arcsec^2), written as `pi R^2 Sigma_cr_ref mean_kappa` so that it is 0 at `R = 0`.
pub fn nfw_mass_cylinder_msun(
    r_arcsec: f64,
    r_s_arcsec: f64,
    kappa_s: f64,
    sigma_cr_ref_msun_per_arcsec2: f64,
) -> f64 {
    let x = r_arcsec.abs() / r_s_arcsec;
    std::f64::consts::PI
        * r_arcsec
        * r_arcsec
        * sigma_cr_ref_msun_per_arcsec2
        * mean_kappa(x, nfw_terms(x).h, kappa_s)
}

/// NFW convergence `2 kappa_s G(x)` at offset `d` (arcsec) from the centre, `x = |d| / r_s`.
pub fn nfw_kappa(d: DVec2, r_s_arcsec: f64, kappa_s: f64) -> f64 {
    2.0 * kappa_s * nfw_terms(d.length() / r_s_arcsec).g
}

/// Mean NFW convergence inside `x = R / r_s`: `4 kappa_s h(x) / x^2` (`x` floored at X_FLOOR).
#[inline]
fn mean_kappa(x: f64, h: f64, kappa_s: f64) -> f64 {
    let x = x.max(X_FLOOR);
    4.0 * kappa_s * h / (x * x)
}

/// NFW deflection in arcsec at offset `d` (arcsec): `4 kappa_s r_s h(x)/x` along `d/|d|`
/// (zero at the centre).
pub fn nfw_deflection(d: DVec2, r_s_arcsec: f64, kappa_s: f64) -> DVec2 {
    let x = d.length() / r_s_arcsec;
    axisymmetric_deflection(d, mean_kappa(x, nfw_terms(x).h, kappa_s))
}

/// NFW Hessian `[psi_xx, psi_xy, psi_yy]` at offset `d` (arcsec) from `kappa = 2 kappa_s G`
/// and `gamma_t = 4 kappa_s h/x^2 - kappa`.
pub fn nfw_hessian(d: DVec2, r_s_arcsec: f64, kappa_s: f64) -> [f64; 3] {
    let r = d.length();
    let x = r / r_s_arcsec;
    let t = nfw_terms(x);
    axisymmetric_hessian(d, r, 2.0 * kappa_s * t.g, mean_kappa(x, t.h, kappa_s))
}

impl MassComponent for Nfw {
    fn kappa(&self, p: DVec2) -> f64 {
        nfw_kappa(p - self.center, self.r_s_arcsec, self.kappa_s)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        nfw_deflection(p - self.center, self.r_s_arcsec, self.kappa_s)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        nfw_hessian(p - self.center, self.r_s_arcsec, self.kappa_s)
    }
    fn deflection_hessian(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        let (_, alpha, hessian) = self.fields(p);
        (alpha, hessian)
    }
}

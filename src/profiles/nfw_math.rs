//! Shared maths of the NFW family ([method §2]): the dimensionless functions of
//! `x = R / r_s`, the M200/c200 normalisation, and the axially symmetric field assembly.
//!
//! With `u = 1 - x^2`:
//! `F(x) = arctanh(sqrt(u))/sqrt(u)` (x < 1), `arctan(sqrt(-u))/sqrt(-u)` (x > 1), `F(1) = 1`;
//! `G(x) = (1 - F)/(x^2 - 1)` (so `kappa_NFW = 2 kappa_s G`), `G(1) = 1/3`;
//! `h(x) = ln(x/2) + F(x)` (so `alpha_NFW = 4 kappa_s r_s h / x`).
//! Near `x = 1` both `F = sum_n u^n/(2n+1)` and `G = sum_n u^n/(2n+3)` are summed as series;
//! for small `x` `h` is evaluated in a cancellation-free form. Below [`X_FLOOR`] every function
//! is evaluated at `X_FLOOR` (the convergence diverges like `ln(1/x)` at the centre).
//!
//! [method §2]: crate::method#2-mass-components

use glam::DVec2;

use super::error::{require_positive, ProfileError};
use crate::cosmology::LensPlane;
use crate::units::c2_over_4pi_g_msun_per_mpc;

/// Smallest `x = R / r_s` at which the profiles are evaluated: closer to the centre the
/// convergence (which diverges like `2 kappa_s ln(2/x)`) is held at its value at
/// `x = 1e-6` (about `27 kappa_s`), so that nothing is infinite at the centre.
pub const X_FLOOR: f64 = 1.0e-6;

/// `|1 - x^2|` below which `F` and `G` are summed as power series in `u = 1 - x^2`.
const SERIES_U: f64 = 0.01;
/// Terms of those series: `0.01^10 / 21` is far below double precision.
const SERIES_TERMS: usize = 10;
/// Below this `x` the function `h` uses the cancellation-free small-`x` form.
const SMALL_X: f64 = 0.1;

/// `F`, `G` and `h` of one `x` (see the module documentation), computed together.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NfwTerms {
    /// `F(x)`.
    pub f: f64,
    /// `G(x) = (1 - F)/(x^2 - 1)`; `kappa = 2 kappa_s G`.
    pub g: f64,
    /// `h(x) = ln(x/2) + F(x)`; mean convergence inside `x` is `4 kappa_s h / x^2`.
    pub h: f64,
}

/// `F`, `G`, `h` at `x = R / r_s` (dimensionless; `x` below [`X_FLOOR`] is raised to it).
pub fn nfw_terms(x: f64) -> NfwTerms {
    let x = x.max(X_FLOOR);
    let u = 1.0 - x * x;
    if u.abs() < SERIES_U {
        // F = sum u^n/(2n+1), G = (F - 1)/u = sum u^n/(2n+3), by Horner.
        let mut g = 0.0;
        for n in (0..SERIES_TERMS).rev() {
            g = g * u + 1.0 / (2 * n + 3) as f64;
        }
        let f = 1.0 + u * g;
        return NfwTerms {
            f,
            g,
            h: (0.5 * x).ln() + f,
        };
    }
    if u > 0.0 {
        // x < 1: F = ln((1 + s)/x)/s with s = sqrt(1 - x^2).
        let s = u.sqrt();
        let ln_x = x.ln();
        let f = ((1.0 + s).ln() - ln_x) / s;
        let h = if x < SMALL_X {
            // h = [(1 - s) ln(2/x) + ln(1 - (1 - s)/2)] / s, with 1 - s = x^2/(1 + s).
            let one_minus_s = x * x / (1.0 + s);
            (one_minus_s * (std::f64::consts::LN_2 - ln_x) + (-0.5 * one_minus_s).ln_1p()) / s
        } else {
            ln_x - std::f64::consts::LN_2 + f
        };
        NfwTerms {
            f,
            g: (f - 1.0) / u,
            h,
        }
    } else {
        // x > 1: F = arctan(t)/t with t = sqrt(x^2 - 1).
        let t = (-u).sqrt();
        let f = t.atan() / t;
        NfwTerms {
            f,
            g: (f - 1.0) / u,
            h: (0.5 * x).ln() + f,
        }
    }
}

/// Scale radius, `kappa_s` and `r200` of an NFW halo, from M200 and c200.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NfwScales {
    /// Scale radius `r_s = r200 / c200` in arcsec.
    pub r_s_arcsec: f64,
    /// `kappa_s = rho_s r_s / Sigma_cr_ref` (dimensionless, `D_ls/D_s = 1`).
    pub kappa_s: f64,
    /// `r200` in arcsec.
    pub r200_arcsec: f64,
    /// `rho_s` in Msun/Mpc^3.
    pub rho_s_msun_per_mpc3: f64,
}

/// Largest M200 accepted, in Msun (far above any cluster; keeps every derived number finite).
pub const M200_MAX_MSUN: f64 = 1.0e18;
/// Accepted concentrations: `C200_MIN <= c200 <= C200_MAX`.
pub const C200_MIN: f64 = 1.0e-3;
/// See [`C200_MIN`].
pub const C200_MAX: f64 = 1.0e3;

/// `mu(c) = ln(1 + c) - c/(1 + c)` (dimensionless), summed as a series for small `c`.
pub fn nfw_mu(c: f64) -> f64 {
    if c < 1.0e-2 {
        // sum_{n>=2} (-1)^n (n-1)/n c^n; 0.01^14 is far below double precision.
        let (mut sum, mut cn, mut sign) = (0.0, c, -1.0);
        for n in 2..14 {
            cn *= c;
            sign = -sign;
            sum += sign * (n - 1) as f64 / n as f64 * cn;
        }
        sum
    } else {
        c.ln_1p() - c / (1.0 + c)
    }
}

/// NFW scales for `m200_msun` (mass inside r200, where the mean density is 200 rho_crit(z_l))
/// and `c200 = r200 / r_s` (lenstronomy `LensCosmo.nfw_physical2angle`):
/// `r200 = (3 M200 / (800 pi rho_crit))^(1/3)`,
/// `rho_s = (200/3) rho_crit c^3 / mu(c)`, `kappa_s = rho_s r_s / Sigma_cr_ref`.
/// `component` names the caller in errors.
pub fn nfw_scales(
    component: &'static str,
    m200_msun: f64,
    c200: f64,
    plane: &LensPlane,
) -> Result<NfwScales, ProfileError> {
    let m200_msun = require_positive(component, "m200", m200_msun)?;
    if m200_msun > M200_MAX_MSUN {
        return Err(ProfileError::BadParameter {
            component,
            field: "m200",
            value: m200_msun,
            reason: "M200 in Msun must not exceed 1e18",
        });
    }
    let c200 = require_positive(component, "c200", c200)?;
    if !(C200_MIN..=C200_MAX).contains(&c200) {
        return Err(ProfileError::BadParameter {
            component,
            field: "c200",
            value: c200,
            reason: "the concentration must be in [1e-3, 1e3]",
        });
    }
    let rho_c = plane.rho_crit_msun_per_mpc3;
    let r200_mpc = (3.0 * m200_msun / (800.0 * std::f64::consts::PI * rho_c)).cbrt();
    let r_s_mpc = r200_mpc / c200;
    let rho_s = 200.0 / 3.0 * rho_c * c200 * c200 * c200 / nfw_mu(c200);
    let sigma_cr_ref_msun_per_mpc2 = c2_over_4pi_g_msun_per_mpc() / plane.d_l_mpc;
    Ok(NfwScales {
        r_s_arcsec: r_s_mpc / plane.mpc_per_arcsec,
        kappa_s: rho_s * r_s_mpc / sigma_cr_ref_msun_per_mpc2,
        r200_arcsec: r200_mpc / plane.mpc_per_arcsec,
        rho_s_msun_per_mpc3: rho_s,
    })
}

/// Deflection (arcsec) of an axially symmetric lens at offset `d` (arcsec) from its centre,
/// given `mean_kappa` = mean convergence inside `r = |d|`: `alpha = mean_kappa * d`
/// (i.e. `|alpha| = mean_kappa r`).
#[inline]
pub fn axisymmetric_deflection(d: DVec2, mean_kappa: f64) -> DVec2 {
    d * mean_kappa
}

/// Offsets shorter than this (arcsec) count as the exact centre, where the shear direction is
/// undefined; it keeps `1/r` finite.
pub const CENTER_EPS_ARCSEC: f64 = 1.0e-100;

/// Hessian `[psi_xx, psi_xy, psi_yy]` of an axially symmetric lens at offset `d` (arcsec, with
/// `r = |d|`) from its centre, from the local convergence `kappa` and the mean convergence
/// inside `r`: tangential shear `gamma_t = mean_kappa - kappa`, `gamma1 = -gamma_t cos 2phi`,
/// `gamma2 = -gamma_t sin 2phi`, `psi_xx = kappa + gamma1`, `psi_yy = kappa - gamma1`,
/// `psi_xy = gamma2`. At the centre (`r <` [`CENTER_EPS_ARCSEC`]) the shear is set to zero.
#[inline]
pub fn axisymmetric_hessian(d: DVec2, r: f64, kappa: f64, mean_kappa: f64) -> [f64; 3] {
    if r < CENTER_EPS_ARCSEC {
        return [kappa, 0.0, kappa];
    }
    let n = d * (1.0 / r);
    let gamma_t = mean_kappa - kappa;
    let gamma1 = -gamma_t * (n.x * n.x - n.y * n.y);
    let gamma2 = -gamma_t * 2.0 * n.x * n.y;
    [kappa + gamma1, gamma2, kappa - gamma1]
}

//! Singular isothermal ellipsoid (Kormann, Schneider & Bartelmann 1994; Keeton & Kochanek 1998).
//!
//! In the frame of the major axis (`x'` along `pa`, degrees counter-clockwise from +x), with
//! axis ratio `0 < q <= 1` and the product-averaged Einstein radius `theta_E` of the SIS with
//! the same `sigma_v` ([`super::sis_theta_e_arcsec`], lenstronomy's `SIE` convention):
//!
//! - `kappa = theta_E / (2 sqrt(q x'^2 + y'^2 / q))`;
//! - with `b = theta_E sqrt(q)`, `psi_q = sqrt(q^2 x'^2 + y'^2)` and `e' = sqrt(1 - q^2)`:
//!   `alpha_x' = b / e' atan(e' x' / psi_q)`, `alpha_y' = b / e' atanh(e' y' / psi_q)`;
//! - the potential is homogeneous of degree 1 in `theta`, so the Hessian is
//!   `2 kappa / r^2 [dy^2, -dx dy, dx^2]` in any frame (`gamma = kappa`, tangential).
//!
//! At `q = 1` it is the SIS. As for the SIS, inside [`SIE_CORE_ARCSEC`] of the centre the fields
//! are those at that radius scaled to stay finite (deflection 0 at the centre).

use glam::DVec2;

use super::error::{require_finite_center, require_positive, require_sigma_v, ProfileError};
use super::MassComponent;

/// Radius in arcsec inside which the SIE's singular fields are replaced by finite values
/// (1e-8 arcsec, far below any pixel).
pub const SIE_CORE_ARCSEC: f64 = 1.0e-8;

/// `1 - q` below which the SIE is evaluated as an SIS (the two agree to far better than 1e-12).
const ROUND_Q: f64 = 1.0e-12;

/// A singular isothermal ellipsoid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sie {
    center: DVec2,
    theta_e_ref_arcsec: f64,
    q: f64,
    pa_deg: f64,
    /// `(cos pa, sin pa)`.
    axis: DVec2,
}

impl Sie {
    /// An SIE with velocity dispersion `sigma_v_km_s` [km/s] (the SIS of that `sigma_v` gives
    /// `theta_E`), axis ratio `q` in `[0.01, 1]`, major axis at `pa_deg` [degrees CCW from +x].
    pub fn new(
        center: DVec2,
        sigma_v_km_s: f64,
        q: f64,
        pa_deg: f64,
    ) -> Result<Self, ProfileError> {
        let sigma_v_km_s = require_sigma_v("sie", sigma_v_km_s)?;
        Self::from_theta_e(center, super::sis_theta_e_arcsec(sigma_v_km_s), q, pa_deg)
    }

    /// An SIE with product-averaged Einstein radius `theta_e_ref_arcsec` (arcsec,
    /// `D_ls/D_s = 1`), axis ratio `q` and position angle `pa_deg` as in [`Self::new`].
    pub fn from_theta_e(
        center: DVec2,
        theta_e_ref_arcsec: f64,
        q: f64,
        pa_deg: f64,
    ) -> Result<Self, ProfileError> {
        let bad = |field, value, reason| ProfileError::BadParameter {
            component: "sie",
            field,
            value,
            reason,
        };
        // Below q = 0.01 the needle is not a galaxy and atanh loses precision.
        if !(q.is_finite() && (0.01..=1.0).contains(&q)) {
            return Err(bad("q", q, "the axis ratio must be in [0.01, 1]"));
        }
        if !pa_deg.is_finite() {
            return Err(bad(
                "pa",
                pa_deg,
                "the position angle in degrees must be finite",
            ));
        }
        let pa = pa_deg.to_radians();
        Ok(Self {
            center: require_finite_center("sie", center)?,
            theta_e_ref_arcsec: require_positive("sie", "theta_e", theta_e_ref_arcsec)?,
            q,
            pa_deg,
            axis: DVec2::new(pa.cos(), pa.sin()),
        })
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }
    /// Product-averaged Einstein radius for `D_ls/D_s = 1`, in arcsec.
    pub fn theta_e_ref_arcsec(&self) -> f64 {
        self.theta_e_ref_arcsec
    }
    /// Axis ratio `q = b/a`.
    pub fn q(&self) -> f64 {
        self.q
    }
    /// Major-axis position angle in degrees CCW from +x.
    pub fn pa_deg(&self) -> f64 {
        self.pa_deg
    }

    /// Offset `d` (arcsec) in the major-axis frame, pulled out to the core radius if inside it;
    /// also returns the factor `|d| / r_c` (1 outside the core) by which fields scale there.
    fn axis_offset(&self, p: DVec2) -> (DVec2, f64) {
        let d = p - self.center;
        let (c, s) = (self.axis.x, self.axis.y);
        let u = DVec2::new(c * d.x + s * d.y, -s * d.x + c * d.y);
        let r = u.length();
        if r >= SIE_CORE_ARCSEC {
            (u, 1.0)
        } else if r > 0.0 {
            (u * (SIE_CORE_ARCSEC / r), r / SIE_CORE_ARCSEC)
        } else {
            (DVec2::new(SIE_CORE_ARCSEC, 0.0), 0.0)
        }
    }
}

/// SIE convergence at `u` (arcsec, major-axis frame): `theta_E / (2 sqrt(q u_x^2 + u_y^2/q))`.
pub fn sie_kappa(u: DVec2, theta_e_arcsec: f64, q: f64) -> f64 {
    0.5 * theta_e_arcsec / (q * u.x * u.x + u.y * u.y / q).sqrt()
}

/// SIE deflection in arcsec at `u` (arcsec, major-axis frame), in that frame
/// (Keeton & Kochanek 1998, eq. 8 with zero core).
pub fn sie_deflection(u: DVec2, theta_e_arcsec: f64, q: f64) -> DVec2 {
    let psi = (q * q * u.x * u.x + u.y * u.y).sqrt();
    let b = theta_e_arcsec * q.sqrt();
    if 1.0 - q < ROUND_Q {
        return u * (b / psi);
    }
    let e = (1.0 - q * q).sqrt();
    DVec2::new(
        b / e * (e * u.x / psi).atan(),
        b / e * (e * u.y / psi).atanh(),
    )
}

impl MassComponent for Sie {
    fn kappa(&self, p: DVec2) -> f64 {
        let (u, _) = self.axis_offset(p);
        sie_kappa(u, self.theta_e_ref_arcsec, self.q)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        let (u, scale) = self.axis_offset(p);
        let a = sie_deflection(u, self.theta_e_ref_arcsec, self.q) * scale;
        let (c, s) = (self.axis.x, self.axis.y);
        DVec2::new(c * a.x - s * a.y, s * a.x + c * a.y)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        let (u, _) = self.axis_offset(p);
        let k = sie_kappa(u, self.theta_e_ref_arcsec, self.q);
        // Degree-1 potential: the Hessian is 2 kappa times the projector across the radius,
        // the same in every frame; `d` is the sky-frame direction of `u`.
        let (c, s) = (self.axis.x, self.axis.y);
        let d = DVec2::new(c * u.x - s * u.y, s * u.x + c * u.y);
        let w = 2.0 * k / d.length_squared();
        [w * d.y * d.y, -w * d.x * d.y, w * d.x * d.x]
    }
}

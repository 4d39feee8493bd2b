//! External shear (Lenstool profile 14): `psi = (gamma/2) (x'^2 - y'^2)` about `center`, with
//! `x'` along the angle `pa` (degrees counter-clockwise from +x). In the sky frame
//! `gamma1 = gamma cos 2pa`, `gamma2 = gamma sin 2pa`, `alpha = (gamma1 dx + gamma2 dy,
//! gamma2 dx - gamma1 dy)` and `kappa = 0`.
//!
//! This is Lenstool's `e_grad.c` (`g = (gamma x', -gamma y')`, rotated back by `angle_pos`),
//! with `gamma` read from the `gamma` keyword at the reference normalisation (Lenstool scales
//! every deflection by `D_ls/D_s`). It stands for the tidal field of mass outside the model: it
//! has no convergence and no finite mass, and its deflection grows without bound with
//! distance, but it changes the critical curves (it belongs in an Einstein-radius evaluation
//! of a model that was fitted with it).

use glam::DVec2;

use super::error::{require_finite_center, ProfileError};
use super::MassComponent;

/// A constant external shear.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExternalShear {
    center: DVec2,
    gamma1: f64,
    gamma2: f64,
}

impl ExternalShear {
    /// Shear of strength `gamma` (finite, `>= 0`, `D_ls/D_s = 1`) along `pa_deg` [degrees
    /// counter-clockwise from +x], about `center` (arcsec; only shifts the deflection by a
    /// constant).
    pub fn new(center: DVec2, gamma: f64, pa_deg: f64) -> Result<Self, ProfileError> {
        let bad = |field, value, reason| ProfileError::BadParameter {
            component: "shear",
            field,
            value,
            reason,
        };
        if !(gamma.is_finite() && gamma >= 0.0) {
            return Err(bad("gamma", gamma, "must be finite and >= 0"));
        }
        if !pa_deg.is_finite() {
            return Err(bad("pa", pa_deg, "the angle must be finite"));
        }
        let two_pa = 2.0 * pa_deg.to_radians();
        Ok(Self {
            center: require_finite_center("shear", center)?,
            gamma1: gamma * two_pa.cos(),
            gamma2: gamma * two_pa.sin(),
        })
    }

    /// Shear with sky-frame components `gamma1`, `gamma2` (finite, `D_ls/D_s = 1`; lenstronomy
    /// `SHEAR`) about `center` (arcsec).
    pub fn from_components(center: DVec2, gamma1: f64, gamma2: f64) -> Result<Self, ProfileError> {
        for (field, value) in [("gamma1", gamma1), ("gamma2", gamma2)] {
            if !value.is_finite() {
                return Err(ProfileError::BadParameter {
                    component: "shear",
                    field,
                    value,
                    reason: "must be finite",
                });
            }
        }
        Ok(Self {
            center: require_finite_center("shear", center)?,
            gamma1,
            gamma2,
        })
    }

    /// `(gamma1, gamma2)` in the sky frame.
    pub fn components(&self) -> (f64, f64) {
        (self.gamma1, self.gamma2)
    }
}

impl MassComponent for ExternalShear {
    /// Always 0: a shear has no convergence.
    fn kappa(&self, _p: DVec2) -> f64 {
        0.0
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        let d = p - self.center;
        DVec2::new(
            self.gamma1 * d.x + self.gamma2 * d.y,
            self.gamma2 * d.x - self.gamma1 * d.y,
        )
    }
    fn hessian(&self, _p: DVec2) -> [f64; 3] {
        [self.gamma1, self.gamma2, -self.gamma1]
    }
}

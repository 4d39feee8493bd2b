//! A uniform mass sheet: `kappa` everywhere, `psi = kappa r^2 / 2`, `alpha = kappa theta`,
//! Hessian `[kappa, 0, kappa]` (lenstronomy `CONVERGENCE`), about the frame origin.
//!
//! It stands for mass spread wider than the field (a sheet of `kappa` at `D_ls/D_s = 1`);
//! added to a lens as `(1 - lambda) + lambda kappa` it is the mass-sheet degeneracy.

use glam::DVec2;

use super::error::ProfileError;
use super::MassComponent;

/// A uniform sheet of convergence `kappa` (`D_ls/D_s = 1`) centred on the frame origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassSheet {
    kappa: f64,
}

impl MassSheet {
    /// A sheet of finite `kappa` (negative values are allowed: a sheet removed).
    pub fn new(kappa: f64) -> Result<Self, ProfileError> {
        if !kappa.is_finite() {
            return Err(ProfileError::BadParameter {
                component: "sheet",
                field: "kappa",
                value: kappa,
                reason: "must be finite",
            });
        }
        Ok(Self { kappa })
    }

    /// The sheet's convergence at `D_ls/D_s = 1`.
    pub fn kappa_value(&self) -> f64 {
        self.kappa
    }
}

impl MassComponent for MassSheet {
    fn kappa(&self, _p: DVec2) -> f64 {
        self.kappa
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        p * self.kappa
    }
    fn hessian(&self, _p: DVec2) -> [f64; 3] {
        [self.kappa, 0.0, self.kappa]
    }
}

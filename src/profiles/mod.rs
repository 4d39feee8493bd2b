//! Mass components: one file per profile, all implementing [`MassComponent`].
//!
//! Positions are arcsec in the frame of METHOD.md section 1. Every quantity is for the
//! reference normalisation `D_ls/D_s = 1`: multiply by `f(z_s)` for a source at `z_s`.

use glam::DVec2;

/// One lensing mass distribution on the lens plane.
pub trait MassComponent: Send + Sync + std::fmt::Debug {
    /// Convergence `kappa_ref = Sigma / Sigma_cr_ref` at `p` (arcsec).
    fn kappa(&self, p: DVec2) -> f64;
    /// Deflection `alpha_ref` at `p`, in arcsec.
    fn deflection(&self, p: DVec2) -> DVec2;
    /// Hessian of the lensing potential at `p`: `[psi_xx, psi_xy, psi_yy]` (dimensionless).
    /// `kappa = (psi_xx + psi_yy)/2`, `gamma1 = (psi_xx - psi_yy)/2`, `gamma2 = psi_xy`.
    fn hessian(&self, p: DVec2) -> [f64; 3];
}

/// A lens made of several components; its fields are the sums of theirs.
#[derive(Debug, Default)]
pub struct Lens {
    pub components: Vec<Box<dyn MassComponent>>,
}

impl Lens {
    pub fn new(components: Vec<Box<dyn MassComponent>>) -> Self {
        Self { components }
    }
}

impl MassComponent for Lens {
    fn kappa(&self, p: DVec2) -> f64 {
        self.components.iter().map(|c| c.kappa(p)).sum()
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        self.components.iter().map(|c| c.deflection(p)).sum()
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        self.components.iter().fold([0.0; 3], |acc, c| {
            let h = c.hessian(p);
            [acc[0] + h[0], acc[1] + h[1], acc[2] + h[2]]
        })
    }
}

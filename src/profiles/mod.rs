//! Mass components: one file per profile, all implementing [`MassComponent`].
//!
//! Positions are arcsec in the frame of [method §1]. Every quantity is for the
//! reference normalisation `D_ls/D_s = 1`: multiply by `f(z_s)` for a source at `z_s`.
//!
//! [method §1]: crate::method#1-frames-and-units

use glam::DVec2;

use crate::map::LensMaps;

mod dpie;
mod error;
mod gaussian;
mod maps;
mod nfw;
mod nfw_ellipse;
mod nfw_math;
mod point;
mod shear;
mod sheet;
mod sie;
mod sis;
mod tnfw;
mod tnfw_near;

pub use dpie::{
    dpie_b0_arcsec, kk_epsilon, Dpie, CIRCULAR_EPSILON as DPIE_CIRCULAR_EPSILON,
    DPIE_SINGULAR_CORE_ARCSEC,
};
pub(crate) use error::require_sigma_v;
pub use error::ProfileError;
pub use gaussian::{
    cell_unit_deflection, gaussian_unit_deflection, gaussian_unit_hessian, gaussian_unit_kappa,
    Gaussian,
};
pub use maps::add_pixelwise;
pub use nfw::{nfw_deflection, nfw_hessian, nfw_kappa, nfw_mass_cylinder_msun, Nfw};
pub use nfw_ellipse::{NfwEllipse, CSE_TERMS};
pub use nfw_math::{nfw_terms, NfwTerms, X_FLOOR as NFW_X_FLOOR};
pub use point::PointMass;
pub use shear::ExternalShear;
pub use sheet::MassSheet;
pub use sie::Sie;
pub use sis::{sis_theta_e_arcsec, Sis};
pub use tnfw::{
    far_field_coefficients as tnfw_far_field_coefficients, tnfw_mass_and_kappa_unit,
    tnfw_total_mass_unit, TruncatedNfw,
};

/// One lensing mass distribution on the lens plane.
pub trait MassComponent: Send + Sync + std::fmt::Debug {
    /// Convergence `kappa_ref = Sigma / Sigma_cr_ref` at `p` (arcsec).
    fn kappa(&self, p: DVec2) -> f64;
    /// Deflection `alpha_ref` at `p`, in arcsec.
    fn deflection(&self, p: DVec2) -> DVec2;
    /// Hessian of the lensing potential at `p`: `[psi_xx, psi_xy, psi_yy]` (dimensionless).
    /// `kappa = (psi_xx + psi_yy)/2`, `gamma1 = (psi_xx - psi_yy)/2`, `gamma2 = psi_xy`.
    fn hessian(&self, p: DVec2) -> [f64; 3];
    /// Deflection and Hessian together; profiles that share work between the two override it
    /// (map making calls this once per pixel and component).
    fn deflection_hessian(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        (self.deflection(p), self.hessian(p))
    }
    /// Adds this component's `kappa`, `gamma1`, `gamma2` and `alpha` (arcsec), all at
    /// `D_ls/D_s = 1`, to every pixel of `maps` by a faster whole-map method and returns true,
    /// or returns false and leaves `maps` untouched: the caller then evaluates
    /// [`Self::deflection_hessian`] pixel by pixel ([`LensMaps::from_lens`]).
    /// The default declines; a grid of Gaussian cells convolves by FFT.
    fn add_to_maps(&self, maps: &mut LensMaps) -> bool {
        let _ = maps;
        false
    }
    /// The components a composite lens ([`Lens`]) is made of, which map making evaluates each
    /// on its own (so that each can use its whole-map method); empty for a single component.
    fn parts(&self) -> &[Box<dyn MassComponent>] {
        &[]
    }
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
    fn deflection_hessian(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        self.components
            .iter()
            .fold((DVec2::ZERO, [0.0; 3]), |(a, h), c| {
                let (da, dh) = c.deflection_hessian(p);
                (a + da, [h[0] + dh[0], h[1] + dh[1], h[2] + dh[2]])
            })
    }
    fn parts(&self) -> &[Box<dyn MassComponent>] {
        &self.components
    }
}

//! Flat ΛCDM distances and the lens-plane quantities derived from them ([method §1]).
//!
//! Distances are angular-diameter distances in Mpc from numerical integration of `1/E(z)`,
//! radiation neglected (astropy's `FlatLambdaCDM(H0, Om0, Tcmb0=0)`).
//!
//! [method §1]: crate::method#1-frames-and-units

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::units::{c2_over_4pi_g_msun_per_mpc, ARCSEC_PER_RAD, C_KM_S, G_SI, MPC_M, MSUN_KG};

/// What can be wrong with cosmological parameters or redshifts.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CosmologyError {
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error(
        "source redshift z_s = {z_source} must be greater than the lens redshift z_l = {z_lens}"
    )]
    SourceNotBehindLens { z_lens: f64, z_source: f64 },
}

/// Flat ΛCDM: `H0` in km/s/Mpc and the matter density `Ωm` today (`ΩΛ = 1 - Ωm`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cosmology {
    /// Hubble constant in km/s/Mpc (default 70).
    #[serde(default = "default_h0")]
    pub h0: f64,
    /// Matter density parameter today (default 0.3).
    #[serde(default = "default_omega_m")]
    pub omega_m: f64,
}

fn default_h0() -> f64 {
    70.0
}
fn default_omega_m() -> f64 {
    0.3
}

impl Default for Cosmology {
    fn default() -> Self {
        Self {
            h0: default_h0(),
            omega_m: default_omega_m(),
        }
    }
}

/// Number of Simpson intervals per unit redshift; the integrand is smooth, so this gives
/// relative errors far below 1e-9.
const SIMPSON_INTERVALS_PER_UNIT_Z: f64 = 400.0;

/// The largest `H0` (km/s/Mpc) accepted from settings or a Lenstool file: seven times the
/// measured value, far beyond any cosmology anyone would lens with, but a bound that keeps a
/// typo (`H0 7000`) from passing as a universe.
pub const H0_MAX_KM_S_MPC: f64 = 500.0;

impl Cosmology {
    /// A validated cosmology.
    pub fn new(h0: f64, omega_m: f64) -> Result<Self, CosmologyError> {
        let c = Self { h0, omega_m };
        c.validate()?;
        Ok(c)
    }

    /// True for an `H0` (km/s/Mpc) the distances accept: `0 < H0 <=` [`H0_MAX_KM_S_MPC`].
    pub fn h0_allowed(h0: f64) -> bool {
        h0.is_finite() && h0 > 0.0 && h0 <= H0_MAX_KM_S_MPC
    }

    /// True for an `Ωm` of a flat universe: `0 <= Ωm <= 1`.
    pub fn omega_m_allowed(omega_m: f64) -> bool {
        omega_m.is_finite() && (0.0..=1.0).contains(&omega_m)
    }

    /// Checks [`Self::h0_allowed`] and [`Self::omega_m_allowed`].
    pub fn validate(&self) -> Result<(), CosmologyError> {
        if !Self::h0_allowed(self.h0) {
            return Err(CosmologyError::from(crate::error::BadFieldValue::new(
                "cosmology.h0",
                self.h0,
                "H0 in km/s/Mpc must be in (0, 500]",
            )));
        }
        if !Self::omega_m_allowed(self.omega_m) {
            return Err(CosmologyError::from(crate::error::BadFieldValue::new(
                "cosmology.omega_m",
                self.omega_m,
                "a flat universe needs 0 <= omega_m <= 1",
            )));
        }
        Ok(())
    }

    /// `E(z) = H(z)/H0` for flat ΛCDM without radiation.
    pub fn e_of_z(&self, z: f64) -> f64 {
        let a = 1.0 + z;
        (self.omega_m * a * a * a + (1.0 - self.omega_m)).sqrt()
    }

    /// Hubble distance `c/H0` in Mpc.
    pub fn hubble_distance_mpc(&self) -> f64 {
        C_KM_S / self.h0
    }

    /// Line-of-sight comoving distance from z1 to z2 in Mpc (z2 >= z1 >= 0).
    pub fn comoving_distance_z1z2_mpc(&self, z1: f64, z2: f64) -> f64 {
        if z2 <= z1 {
            return 0.0;
        }
        let n = (((z2 - z1) * SIMPSON_INTERVALS_PER_UNIT_Z).ceil() as usize).max(8) * 2;
        let h = (z2 - z1) / n as f64;
        let f = |z: f64| 1.0 / self.e_of_z(z);
        let mut sum = f(z1) + f(z2);
        for k in 1..n {
            let w = if k % 2 == 1 { 4.0 } else { 2.0 };
            sum += w * f(z1 + k as f64 * h);
        }
        self.hubble_distance_mpc() * sum * h / 3.0
    }

    /// Angular-diameter distance to `z` in Mpc.
    pub fn angular_diameter_distance_mpc(&self, z: f64) -> f64 {
        self.comoving_distance_z1z2_mpc(0.0, z) / (1.0 + z)
    }

    /// Angular-diameter distance between `z1` and `z2 > z1` in Mpc (flat universe).
    pub fn angular_diameter_distance_z1z2_mpc(&self, z1: f64, z2: f64) -> f64 {
        self.comoving_distance_z1z2_mpc(z1, z2) / (1.0 + z2)
    }

    /// Critical density `3 H(z)^2 / (8 pi G)` in Msun/Mpc^3.
    pub fn critical_density_msun_per_mpc3(&self, z: f64) -> f64 {
        let h_si = self.h0 * self.e_of_z(z) * 1.0e3 / MPC_M; // 1/s
        let rho_si = 3.0 * h_si * h_si / (8.0 * std::f64::consts::PI * G_SI); // kg/m^3
        rho_si * MPC_M * MPC_M * MPC_M / MSUN_KG
    }
}

/// Everything about the lens plane that the mass components need, computed once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensPlane {
    pub cosmology: Cosmology,
    pub z_lens: f64,
    /// `D_l` in Mpc.
    pub d_l_mpc: f64,
    /// Proper distance on the lens plane per arcsec, in Mpc.
    pub mpc_per_arcsec: f64,
    /// `Sigma_cr_ref = c^2 / (4 pi G D_l)` (the `D_ls/D_s = 1` normalisation) in Msun/arcsec^2.
    pub sigma_cr_ref_msun_per_arcsec2: f64,
    /// `rho_crit(z_l)` in Msun/Mpc^3.
    pub rho_crit_msun_per_mpc3: f64,
}

impl LensPlane {
    /// The lens plane at `z_lens > 0` in `cosmology`.
    pub fn new(cosmology: Cosmology, z_lens: f64) -> Result<Self, CosmologyError> {
        cosmology.validate()?;
        if !(z_lens.is_finite() && z_lens > 0.0 && z_lens < 20.0) {
            return Err(CosmologyError::from(crate::error::BadFieldValue::new(
                "cosmology.z_lens",
                z_lens,
                "the lens redshift must be in (0, 20)",
            )));
        }
        let d_l_mpc = cosmology.angular_diameter_distance_mpc(z_lens);
        let mpc_per_arcsec = d_l_mpc / ARCSEC_PER_RAD;
        let sigma_cr_mpc2 = c2_over_4pi_g_msun_per_mpc() / d_l_mpc;
        Ok(Self {
            cosmology,
            z_lens,
            d_l_mpc,
            mpc_per_arcsec,
            sigma_cr_ref_msun_per_arcsec2: sigma_cr_mpc2 * mpc_per_arcsec * mpc_per_arcsec,
            rho_crit_msun_per_mpc3: cosmology.critical_density_msun_per_mpc3(z_lens),
        })
    }

    /// `f(z_s) = D_ls / D_s`, the factor that scales the reference maps to a source at `z_s`.
    pub fn distance_ratio(&self, z_source: f64) -> Result<f64, CosmologyError> {
        if !(z_source.is_finite() && z_source > self.z_lens) {
            return Err(CosmologyError::SourceNotBehindLens {
                z_lens: self.z_lens,
                z_source,
            });
        }
        let d_s = self.cosmology.angular_diameter_distance_mpc(z_source);
        let d_ls = self
            .cosmology
            .angular_diameter_distance_z1z2_mpc(self.z_lens, z_source);
        Ok(d_ls / d_s)
    }

    /// `Sigma_cr` for a source at `z_s` in Msun/Mpc^2: `c^2 D_s / (4 pi G D_l D_ls)`.
    pub fn sigma_cr_msun_per_mpc2(&self, z_source: f64) -> Result<f64, CosmologyError> {
        Ok(c2_over_4pi_g_msun_per_mpc() / self.d_l_mpc / self.distance_ratio(z_source)?)
    }
}

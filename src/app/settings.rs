//! The app's settings: the lens plane (z_lens, cosmology) and a [`ReconstructConfig`], edited
//! one field at a time with validation, so that a bad value never replaces a good one.

use serde::{Deserialize, Serialize};

use crate::cosmology::{Cosmology, LensPlane};
use crate::lenstool_par::ParOptions;
use crate::limits::json_error_message;
use crate::reconstruct::{MemoryLimit, ReconstructConfig, RunSize, TooMuchMemory};

use super::ensemble::EnsembleSettings;

use super::AppError;

/// Map side in pixels the app uses by default (the CLI's default is 512).
pub const APP_MAP_PIXELS: usize = 256;

/// Every setting of a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AppSettings {
    /// Lens redshift (default 0.35).
    pub z_lens: f64,
    /// Hubble constant in km/s/Mpc (default 70).
    pub h0: f64,
    /// Omega_m of flat LCDM (default 0.3).
    pub omega_m: f64,
    /// The reconstruction settings (`CONFIG.json` of `wslap reconstruct`, with its defaults,
    /// "auto" regulariser strength included); the app's default map side is
    /// [`APP_MAP_PIXELS`].
    pub reconstruct: ReconstructConfig,
    /// Systems left out of the fit and predicted (`wslap reconstruct --holdout`), by id.
    pub holdout: Vec<String>,
    /// A Lenstool model file with potentials at several redshifts is evaluated in the
    /// single-plane approximation ([`ParOptions::single_plane`], `wslap maps --single-plane`);
    /// default `false`: such a model is refused.
    pub lenstool_single_plane: bool,
    /// What `wslap reconstruct --par` takes from a loaded Lenstool `.par`: the galaxies it
    /// models on its own (dPIE potentials with a core of at most 5 kpc and a `mag`: typically
    /// the BCG, which its member catalogue then leaves out), fitted as members, and the
    /// redshift priors of its `image` block ([`crate::Dataset::add_par`]); default `false`.
    pub members_from_model: bool,
    /// After each reconstruction, an ensemble of that many more (0, the default: none), as
    /// `wslap reconstruct --ensemble N --seed S` runs it.
    pub ensemble: EnsembleSettings,
}

impl Default for AppSettings {
    /// The CLI's reconstruction settings (the regulariser's strength "auto" too: the web app
    /// cross-validates its candidates in parallel workers, `www/js/pool.js`) with
    /// [`APP_MAP_PIXELS`]-pixel maps.
    fn default() -> Self {
        let mut reconstruct = ReconstructConfig::default();
        reconstruct.products.pixels = APP_MAP_PIXELS;
        Self {
            z_lens: 0.35,
            h0: 70.0,
            omega_m: 0.3,
            reconstruct,
            holdout: Vec::new(),
            lenstool_single_plane: false,
            members_from_model: false,
            ensemble: EnsembleSettings::default(),
        }
    }
}

impl AppSettings {
    /// Checks the cosmology, the lens redshift, every block of the reconstruction settings and
    /// the hold-out ids (non-empty, each once; whether the data has them is checked by a run).
    pub fn validate(&self) -> Result<(), AppError> {
        self.lens_plane()?;
        for (k, id) in self.holdout.iter().enumerate() {
            if id.is_empty() || id.trim() != id {
                return Err(AppError::Setting(format!(
                    "holdout: '{id}' is not a system id (no spaces around it, not empty)"
                )));
            }
            if self.holdout[..k].contains(id) {
                return Err(AppError::Setting(format!(
                    "holdout: system '{id}' is given twice"
                )));
            }
        }
        self.ensemble.validate()?;
        self.reconstruct
            .validate()
            .map_err(|e| AppError::Setting(e.to_string()))
    }

    /// How a Lenstool model file is read with these settings.
    pub fn par_options(&self) -> ParOptions {
        ParOptions {
            single_plane: self.lenstool_single_plane,
        }
    }

    /// The lens plane at `z_lens` in flat LCDM with `h0`, `omega_m`.
    pub fn lens_plane(&self) -> Result<LensPlane, AppError> {
        let cosmology =
            Cosmology::new(self.h0, self.omega_m).map_err(|e| AppError::Setting(e.to_string()))?;
        LensPlane::new(cosmology, self.z_lens).map_err(|e| AppError::Setting(e.to_string()))
    }

    /// These settings with the field at `path` (dot-separated, e.g. `reconstruct.grid.cells`)
    /// set to `value`; `null` clears an optional field. Fails, leaving `self` as it was, when
    /// the path is unknown, the value has the wrong type, or the result does not validate.
    pub fn with_field(&self, path: &str, value: serde_json::Value) -> Result<Self, AppError> {
        let mut tree = serde_json::to_value(self).map_err(|e| AppError::Setting(e.to_string()))?;
        let pointer = format!("/{}", path.replace('.', "/"));
        let slot = tree
            .pointer_mut(&pointer)
            .ok_or_else(|| AppError::Setting(format!("{path}: no such setting")))?;
        *slot = value;
        let next: Self = serde_json::from_value(tree)
            .map_err(|e| AppError::Setting(format!("{path}: {}", value_error_words(&e))))?;
        next.validate()
            .map_err(|e| AppError::Setting(format!("{path}: {e}")))?;
        next.check_sources_behind_lens()
            .map_err(|e| AppError::Setting(format!("{path}: {e}")))?;
        next.check_memory()
            .map_err(|e| AppError::Setting(format!("{path}: {e}")))?;
        next.ensemble
            .check_memory(next.reconstruct.products.pixels, MemoryLimit::here())
            .map_err(|e| AppError::Setting(format!("{path}: {e}")))?;
        Ok(next)
    }

    /// The least memory a run with these settings needs (the grid and the maps, before any
    /// data) must fit in what a run may use here ([`MemoryLimit::here`]: a browser tab's in
    /// the app), so that a size that cannot run is refused when it is set. Checked when a
    /// field changes, as the redshifts are; a run checks its own estimate with the data.
    fn check_memory(&self) -> Result<(), TooMuchMemory> {
        let config = &self.reconstruct;
        RunSize::of_settings(config)
            .memory(config)
            .check(MemoryLimit::here())
    }

    /// The curves' source redshift, and the redshift given to images with z = 0, must be
    /// behind the lens. Checked when a field changes, not in [`Self::validate`]: a project saved
    /// with such values still opens (its run reports them).
    fn check_sources_behind_lens(&self) -> Result<(), AppError> {
        let behind = |what: &str, z_s: f64| {
            if z_s > self.z_lens {
                return Ok(());
            }
            Err(AppError::Setting(format!(
                "{what} z_s = {z_s} is not behind the lens (z_lens = {}): a source must have \
                 z_s > z_lens",
                self.z_lens
            )))
        };
        behind("the curves'", self.reconstruct.products.z_source)?;
        if let Some([_, high]) = self.reconstruct.constraints.free_z_prior {
            behind("the top of the range of estimated redshifts:", high)?;
        }
        match self.reconstruct.constraints.default_z {
            Some(z) => behind("the redshift for images with z = 0:", z),
            None => Ok(()),
        }
    }

    /// Parses settings JSON (missing fields take their defaults); errors name the line.
    pub fn from_json_str(text: &str, source_name: &str) -> Result<Self, AppError> {
        if let Some(message) = crate::limits::not_an_object_message(text) {
            return Err(AppError::Setting(format!("{source_name}: {message}")));
        }
        let s: Self = serde_json::from_str(text).map_err(|e| {
            AppError::Setting(format!("{source_name}: {}", json_error_message(text, &e)))
        })?;
        s.validate()?;
        Ok(s)
    }
}

/// A setting's type error in words for a person ([`crate::limits::json_words`]): serde's
/// "invalid type: string \"abc\", expected usize" becomes "must be a whole number of 0 or more
/// (got the text \"abc\")".
fn value_error_words(e: &serde_json::Error) -> String {
    let text = e.to_string();
    // serde_json adds " at line L column C" to errors of JSON text; a value has none.
    crate::limits::json_words(text.split(" at line ").next().unwrap_or(&text))
}

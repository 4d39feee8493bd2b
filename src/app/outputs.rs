//! The downloadable files of a result, with the content `wslap reconstruct` writes:
//! `summary.json`, `sources.json`, `images.reg`, `convergence.json`, and the map files of the
//! products.

use serde::Serialize;

use crate::reconstruct::image_regions;

use super::{AppError, SessionResult};

impl SessionResult {
    /// `summary.json`: the CLI's reconstruction summary (with an ensemble's intervals, as
    /// `wslap reconstruct --ensemble` writes them), or the map summary of a forward model or
    /// look-up (what `wslap maps` writes).
    pub fn summary_json(&self) -> Result<String, AppError> {
        let Some(r) = self.reconstruction() else {
            return pretty(&self.products().summary());
        };
        let Some(ensemble) = &self.ensemble else {
            return pretty(&r.summary());
        };
        let mut summary =
            serde_json::to_value(r.summary()).map_err(|e| AppError::Run(e.to_string()))?;
        ensemble.add_to_summary(&mut summary);
        pretty(&summary)
    }

    /// `sources.json` (empty list without a reconstruction).
    pub fn sources_json(&self) -> Result<String, AppError> {
        match self.reconstruction() {
            Some(r) => pretty(&r.sources),
            None => Ok("[]".to_string()),
        }
    }

    /// `images.reg`: DS9 circles at the observed and predicted images (see
    /// [`crate::reconstruct::image_regions`]); an error without a reconstruction.
    pub fn images_regions(&self) -> Result<String, AppError> {
        let r = self.reconstruction().ok_or_else(|| {
            AppError::Missing("images.reg needs a reconstruction: press Reconstruct".to_string())
        })?;
        Ok(image_regions(&r.sources, &r.products))
    }

    /// `convergence.json` (empty list without a reconstruction).
    pub fn convergence_json(&self) -> Result<String, AppError> {
        match self.reconstruction() {
            Some(r) => pretty(&r.convergence),
            None => Ok("[]".to_string()),
        }
    }
}

/// Pretty JSON, as the CLI writes it.
pub(super) fn pretty<T: Serialize + ?Sized>(value: &T) -> Result<String, AppError> {
    serde_json::to_string_pretty(value).map_err(|e| AppError::Run(e.to_string()))
}

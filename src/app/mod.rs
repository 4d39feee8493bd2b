//! The browser app's core, free of JavaScript: a [`Session`] holds the loaded data (as texts, so
//! a project file can store them), the settings and the last result; it loads files without
//! losing what was loaded before, runs a reconstruction, a forward model or a look-up of
//! deflection maps, redraws curves at another source redshift from the stored maps, renders
//! the views and answers hover read-outs. `src/wasm/` is a thin shell around it.

mod compare;
mod data;
mod ensemble;
pub mod examples;
mod iterates;
mod outputs;
mod overlap;
mod plots;
mod project;
mod run;
mod settings;
mod source_plane;
mod views;

use crate::catalog::Member;
use thiserror::Error;

pub use crate::reconstruct::SHOWN_MIN_MAGNIFICATION;
pub use crate::reconstruct::{Dataset, ReconstructSummary};
pub use data::{
    ArcPixels, DataMarks, DataRole, DataViews, LoadReport, LoadedData, ModelLens, NamedMap,
    NamedText, MAX_STORED_FITS_BYTES,
};
pub use ensemble::{
    member_run, EnsembleReadout, EnsembleSettings, StoredEnsemble, MAX_STORED_ENSEMBLE_MAP_BYTES,
};
pub use iterates::{
    IterateList, IterateStep, StoredIterates, APP_KEPT_ITERATES, MAX_STORED_ITERATE_VALUES,
};
pub use overlap::{separation_arcsec, SkyFootprint, FIELD_MARGIN_ARCSEC};
pub use plots::{profile_relative_differences, ModelCurves, MODEL_PLANE_TOLERANCE};
pub use project::{Project, ProjectResult, StoredFits, PROJECT_FORMAT, PROJECT_VERSION};
pub use run::{Outcome, RunKind, SessionResult, StoredRun};
pub use settings::{AppSettings, APP_MAP_PIXELS};
pub use views::{
    system_rgb, CounterImages, HoverReadout, ViewOptions, ViewPng, COUNTER_IMAGE_RGB,
    FIGURE_SCALE_RANGE, MODEL_CURVE_RGB, OBSERVED_RGB, POINT_IMAGE_ARCSEC, PREDICTED_RGB,
    SYSTEM_RGB, WORST_RGB,
};

/// What the app reports to the user; every message names the file, line or setting.
#[derive(Debug, Error)]
pub enum AppError {
    /// A file that could not be read (the message names the file and line).
    #[error("{0}")]
    File(String),
    /// A setting that is not allowed (the message names the field).
    #[error("{0}")]
    Setting(String),
    /// Nothing to run, or a view asked for before any result.
    #[error("{0}")]
    Missing(String),
    /// The computation failed (the core's message).
    #[error("{0}")]
    Run(String),
    /// A file that reads only with a Lenstool `.par`, loaded before one: a member catalogue
    /// that is a `.par`'s potfile (headerless arcsec from its reference), or arclets without a
    /// redshift (the `.par`'s z_source gives them one). The page keeps the file and reads it
    /// again when a `.par` loads (the message says so).
    #[error("{0}")]
    WantsPar(String),
}

impl AppError {
    /// A short, stable name of the error's kind for the page's code (`"wants-par"` for
    /// [`AppError::WantsPar`], `None` for the rest), so that it does not match message text.
    pub fn code(&self) -> Option<&'static str> {
        match self {
            AppError::WantsPar(_) => Some("wants-par"),
            _ => None,
        }
    }
}

/// A galaxy the loaded Lenstool `.par` would add to the members ([`Session::model_galaxies`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelGalaxy {
    /// The member it would be (its `line` the `.par`'s, or the member catalogue's for a
    /// commented-out row that stands for it).
    pub member: Member,
    /// The `.par` writes it no `mag` and no catalogue row stands for it: `member.mag` is the
    /// magnitude whose halo mass under the member law is its dPIE's
    /// ([`crate::catalog::MemberCatalog::mass_galaxies`]), not one a file wrote.
    pub mag_from_mass: bool,
}

/// Loaded data, settings and the last result of one app session.
#[derive(Debug, Default)]
pub struct Session {
    pub data: LoadedData,
    pub settings: AppSettings,
    pub result: Option<SessionResult>,
    /// The example or project name shown by the app.
    pub name: String,
    /// The loaded model file's maps over the last reconstruction's map (the profile view's
    /// model profile and the kappa view's model curves), kept for the next result of the same
    /// field.
    pub(crate) model_maps: plots::ModelCache,
}

impl Session {
    /// An empty session with default settings.
    pub fn new() -> Self {
        Self::default()
    }

    /// Loads one text file in `role`; on an error nothing that was loaded changes.
    pub fn load_text(
        &mut self,
        role: DataRole,
        name: &str,
        text: &str,
    ) -> Result<LoadReport, AppError> {
        let pixel = self.settings.reconstruct.constraints.pixel_arcsec;
        let par = self.settings.par_options();
        self.data.load_text(role, name, text, pixel, &par)
    }

    /// The loaded files parsed into one frame (see [`LoadedData::parse`]); its warnings
    /// begin with [`Self::sky_warnings`]. The galaxies and redshift priors of the loaded `.par`
    /// are taken ([`Dataset::add_par`]) when the setting `members_from_model` is on, and
    /// commented-out BCG rows are fitted when `reconstruct.members.fit_commented_bcg` is
    /// ([`Dataset::fit_commented_bcgs`]).
    pub fn parsed(&self) -> Result<Dataset, AppError> {
        let mut parsed = self.data.parse(
            self.settings.reconstruct.constraints.pixel_arcsec,
            &self.settings.par_options(),
        )?;
        let mut warnings = self.sky_warnings();
        warnings.append(&mut parsed.warnings);
        parsed.warnings = warnings;
        let plane = self.settings.lens_plane()?;
        if self.settings.members_from_model {
            let options = self.settings.par_options().for_galaxies();
            if let Some(par) = self.data.model_par(&options)? {
                let notes = parsed
                    .add_par(&par, &plane, &self.settings.reconstruct)
                    .map_err(|e| AppError::File(e.to_string()))?;
                parsed.warnings.extend(notes);
            }
        }
        // The run's warnings say so when it fits commented-out BCG rows.
        parsed.fit_commented_bcgs(&plane, &self.settings.reconstruct);
        Ok(parsed)
    }

    /// One warning per loaded file whose sky positions lie apart from the first file's (see
    /// [`LoadedData::sky_warnings`]): files of different clusters.
    pub fn sky_warnings(&self) -> Vec<String> {
        let pixel = self.settings.reconstruct.constraints.pixel_arcsec;
        self.data.sky_warnings(pixel, &self.settings.par_options())
    }

    /// Loads one deflection FITS map (`axis` 0 for x, 1 for y); nothing changes on an error.
    pub fn load_fits(
        &mut self,
        axis: usize,
        name: &str,
        bytes: &[u8],
    ) -> Result<LoadReport, AppError> {
        self.data.load_fits(axis, name, bytes)
    }

    /// Sets one setting (see [`AppSettings::with_field`]); the old value stays on an error. A
    /// new constraint pixel must also suit loaded DS9 region arcs (their pixel count is
    /// limited).
    pub fn set_field(&mut self, path: &str, value: serde_json::Value) -> Result<(), AppError> {
        let next = self.settings.with_field(path, value)?;
        let pixel = next.reconstruct.constraints.pixel_arcsec;
        if pixel != self.settings.reconstruct.constraints.pixel_arcsec {
            self.data
                .check_region_arcs(pixel)
                .map_err(|e| AppError::Setting(format!("{path}: {e}")))?;
        }
        self.settings = next;
        Ok(())
    }

    /// Checks the loaded file of `role` again with the current settings (a DS9 region file's
    /// pixels follow the constraint pixel, a Lenstool model the single-plane setting) and
    /// reports on it; `None` when none is loaded.
    pub fn reload(&mut self, role: DataRole) -> Result<Option<LoadReport>, AppError> {
        let pixel = self.settings.reconstruct.constraints.pixel_arcsec;
        let par = self.settings.par_options();
        self.data.reload(role, pixel, &par)
    }

    /// The galaxies the loaded Lenstool `.par` would add to the members
    /// ([`Dataset::add_par_galaxies`]: its galaxies with a `mag` the member catalogue lacks,
    /// and the commented-out rows its galaxies without one name), when the setting
    /// `members_from_model` is off: what the verdict of a run that lacks its BCG offers to
    /// fit. Not the members a `best.par` lists again. Empty without a `.par`, or when it or
    /// the data cannot be read.
    pub fn model_galaxies(&self) -> Vec<ModelGalaxy> {
        if self.settings.members_from_model {
            return Vec::new();
        }
        let options = self.settings.par_options().for_galaxies();
        let (Ok(Some(par)), Ok(mut trial), Ok(plane)) = (
            self.data.model_par(&options),
            self.parsed(),
            self.settings.lens_plane(),
        ) else {
            return Vec::new();
        };
        let before = trial
            .members
            .as_ref()
            .map(|m| m.members.clone())
            .unwrap_or_default();
        if trial
            .add_par_galaxies(&par, &plane, &self.settings.reconstruct)
            .is_err()
        {
            return Vec::new();
        }
        let Some(members) = trial.members else {
            return Vec::new();
        };
        let by_mass = &members.mass_galaxies;
        members
            .members
            .iter()
            .enumerate()
            .filter(|(_, g)| !before.contains(g))
            .map(|(k, g)| ModelGalaxy {
                member: g.clone(),
                mag_from_mass: by_mass.contains(&k),
            })
            .collect()
    }

    /// Fits the commented-out rows on `lines` of the loaded member catalogue (e.g. the BCGs a
    /// result's verdict names: `BcgFacts::commented`); see [`LoadedData::uncomment_members`].
    pub fn uncomment_members(&mut self, lines: &[usize]) -> Result<LoadReport, AppError> {
        let pixel = self.settings.reconstruct.constraints.pixel_arcsec;
        let par = self.settings.par_options();
        self.data.uncomment_members(lines, pixel, &par)
    }

    /// The last result, or an error saying that nothing was computed yet.
    pub fn result(&self) -> Result<&SessionResult, AppError> {
        self.result
            .as_ref()
            .ok_or_else(|| AppError::Missing("nothing has been computed yet".to_string()))
    }
}

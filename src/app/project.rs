//! The project file: one JSON document with the data texts, the settings and the result
//! (summary, per-system reports, convergence, the solution vector `X` and the iterates kept
//! for the iteration slider), so that reloading a project rebuilds the maps from `X` without
//! iterating again, and the slider steps through the same iterates.
//!
//! ```json
//! {"format": "wslap-project", "version": 1, "name": "...",
//!  "data": {"images": {"name": "...", "text": "..."}, "members": null, "arcs": null, "model": null,
//!           "deflection_x": {"name": "...", "fits_base64": "..."}, "deflection_y": null},
//!  "settings": {...AppSettings...},
//!  "result": {"kind": "reconstruct", "summary": {...}, "x": [...], "iterations": 8000,
//!             "sources": [...], "convergence": [...],
//!             "iterates": {"unknowns": 580, "steps": [{"iteration": 0, "objective": 1.2}, ...],
//!                          "x_f32_base64": "..."},
//!             "ensemble": {"record": {...ensemble.json...}, "geometry": {...},
//!                          "maps_f32_base64": "..."}}}
//! ```
//! The iterates are kept as `f32`, at most [`super::MAX_STORED_ITERATE_VALUES`] values (a run
//! with more keeps every other one, [`StoredIterates::from_iterates`]).
//! Deflection FITS files (look-up mode) are stored as base64 up to
//! [`MAX_STORED_FITS_BYTES`] each; a larger one is left out (the app says so when it is
//! loaded) and must be loaded again. Files without the deflection fields still read.
//! A reconstruction's ensemble is kept with its five statistics maps as `f32`
//! ([`StoredEnsemble`], at most [`super::MAX_STORED_ENSEMBLE_MAP_BYTES`]; 1.7 MB of base64 for
//! the app's 256 x 256 maps), not the members' own maps. Files written before ensembles were
//! kept read without one; a stored ensemble that does not read or fit the result is dropped and
//! the reopen message says so, the rest of the project opens.
//! `format` and `version` are read first: a file of another format, or of a version this build
//! does not read (one saved by a newer wslap says so), is refused before its other fields are.

use serde::{Deserialize, Serialize};

use crate::limits::json_error_message;
use crate::reconstruct::{ConvergenceRecord, SourceReport};

use super::data::{LoadReport, NamedText, MAX_STORED_FITS_BYTES};
use super::ensemble::StoredEnsemble;
use super::iterates::StoredIterates;
use super::outputs::pretty;
use super::run::{RunKind, StoredRun};
use super::{AppError, AppSettings, Session};
use base64::Engine as _;

/// The `format` field of every project file.
pub const PROJECT_FORMAT: &str = "wslap-project";
/// The version this code writes and reads.
pub const PROJECT_VERSION: u32 = 1;

/// A deflection FITS file in a project: its name and bytes in base64.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredFits {
    pub name: String,
    pub fits_base64: String,
}

/// The data texts of a project and its deflection FITS files.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ProjectData {
    pub images: Option<NamedText>,
    pub members: Option<NamedText>,
    pub arcs: Option<NamedText>,
    pub model: Option<NamedText>,
    /// The arclet catalogue (weak lensing); absent in projects saved before it existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear: Option<NamedText>,
    pub deflection_x: Option<StoredFits>,
    pub deflection_y: Option<StoredFits>,
}

/// The bytes of a stored FITS file; refused (naming the project and file) when its text is
/// not base64 or would decode to more than [`MAX_STORED_FITS_BYTES`].
fn stored_bytes(f: &StoredFits, source_name: &str) -> Result<Vec<u8>, AppError> {
    let bad = |why: String| AppError::File(format!("{source_name}: {}: {why}", f.name));
    let decoded_len = f.fits_base64.len() / 4 * 3;
    if decoded_len > MAX_STORED_FITS_BYTES + 3 {
        return Err(bad(format!(
            "about {decoded_len} bytes, more than the {MAX_STORED_FITS_BYTES} a project may hold"
        )));
    }
    base64::engine::general_purpose::STANDARD
        .decode(&f.fits_base64)
        .map_err(|e| bad(format!("not base64: {e}")))
}

/// The two fields of a project file that say what it is, read before the rest: a project of a
/// newer format may have fields this version cannot read.
#[derive(Deserialize)]
struct ProjectHeader {
    #[serde(default)]
    format: Option<serde_json::Value>,
    #[serde(default)]
    version: Option<serde_json::Value>,
}

/// Refuses a text that is not JSON, not a project file, or a project of a format version this
/// build does not read: one saved by a newer wslap is said to be so, with both versions.
fn check_header(text: &str, source_name: &str) -> Result<(), AppError> {
    let bad = |why: String| AppError::File(format!("{source_name}: {why}"));
    let h: ProjectHeader =
        serde_json::from_str(text).map_err(|e| bad(json_error_message(text, &e)))?;
    if h.format.as_ref().and_then(|f| f.as_str()) != Some(PROJECT_FORMAT) {
        return Err(bad(format!(
            "not a wslap project (its \"format\" is {}, not \"{PROJECT_FORMAT}\")",
            h.format.map_or("missing".to_string(), |f| f.to_string())
        )));
    }
    match h.version.as_ref().and_then(serde_json::Value::as_u64) {
        Some(v) if v == u64::from(PROJECT_VERSION) => Ok(()),
        Some(v) if v > u64::from(PROJECT_VERSION) => Err(bad(format!(
            "saved by a newer version of wslap (project format version {v}; this version reads \
             version {PROJECT_VERSION}): open it with that version, or update this one"
        ))),
        _ => Err(bad(format!(
            "project format version {} is not one this version reads (version {PROJECT_VERSION})",
            h.version.map_or("missing".to_string(), |v| v.to_string())
        ))),
    }
}

/// The stored result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProjectResult {
    pub kind: RunKind,
    /// `summary.json` of the result.
    pub summary: serde_json::Value,
    /// The solution vector `X` of a reconstruction.
    #[serde(default)]
    pub x: Option<Vec<f64>>,
    #[serde(default)]
    pub iterations: usize,
    #[serde(default)]
    pub sources: Vec<SourceReport>,
    #[serde(default)]
    pub convergence: Vec<ConvergenceRecord>,
    /// The iterates a reconstruction kept, for the iteration slider after a reload (absent in
    /// files written before them, and for other results).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterates: Option<StoredIterates>,
    /// The ensemble run after a reconstruction ([`StoredEnsemble`]), absent in files written
    /// before projects kept it and without one. Read as any JSON here, so that one that does
    /// not read drops the ensemble, not the project.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<serde_json::Value>,
}

/// A saved session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Project {
    pub format: String,
    pub version: u32,
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub data: ProjectData,
    #[serde(default)]
    pub settings: AppSettings,
    #[serde(default)]
    pub result: Option<ProjectResult>,
}

/// What reopening a project did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReopenReport {
    pub name: String,
    /// "restored" (maps rebuilt from X), "recomputed" (a forward model or look-up was rerun),
    /// "solve_needed" (a reconstruction without a usable X: solve again) or "none".
    pub result: String,
    pub message: String,
    /// What loading each of the project's files found, as when it was loaded by hand.
    #[serde(default)]
    pub files: Vec<LoadReport>,
}

impl Session {
    /// Puts the `stored` ensemble (a project's, as JSON) on the restored reconstruction; what
    /// the reopen message adds: "" without one, else whether it was restored or dropped and why.
    fn restore_ensemble(&mut self, stored: Option<serde_json::Value>) -> String {
        let Some(value) = stored else {
            return String::new();
        };
        let Some(result) = self.result.as_mut() else {
            return String::new();
        };
        let geometry = result.products().maps.geometry();
        let restored = serde_json::from_value::<StoredEnsemble>(value)
            .map_err(|e| format!("it does not read: {e}"))
            .and_then(|s| s.to_ensemble(geometry));
        match restored {
            Ok(e) => {
                let n = e.members.len();
                let without = if e.maps.is_none() {
                    " (its intervals only: its maps were too large to keep, run it again for \
                     the spread view)"
                } else {
                    ""
                };
                result.ensemble = Some(Box::new(e));
                format!("; its ensemble of {n} members restored{without}")
            }
            Err(e) => format!(
                "; its stored ensemble was dropped ({e}): press Reconstruct to run it again"
            ),
        }
    }

    /// The project of this session (pretty JSON).
    pub fn project_json(&self) -> Result<String, AppError> {
        let d = &self.data;
        let stored = |axis: usize| {
            let m = d.deflection[axis].as_ref()?;
            Some(StoredFits {
                name: m.name.clone(),
                fits_base64: base64::engine::general_purpose::STANDARD.encode(m.fits.as_ref()?),
            })
        };
        let result = match &self.result {
            None => None,
            Some(r) => Some(ProjectResult {
                kind: r.kind,
                summary: serde_json::from_str(&r.summary_json()?)
                    .map_err(|e| AppError::Run(e.to_string()))?,
                x: r.reconstruction().map(|x| x.x.clone()),
                iterations: r.reconstruction().map_or(0, |x| x.iterations),
                sources: r
                    .reconstruction()
                    .map(|x| x.sources.clone())
                    .unwrap_or_default(),
                convergence: r
                    .reconstruction()
                    .map(|x| x.convergence.clone())
                    .unwrap_or_default(),
                iterates: r
                    .reconstruction()
                    .and_then(|x| StoredIterates::from_iterates(&x.iterates)),
                ensemble: match r.ensemble.as_deref() {
                    None => None,
                    Some(e) => {
                        let stored = StoredEnsemble::from_ensemble(e, r.products().maps.geometry());
                        Some(
                            serde_json::to_value(stored)
                                .map_err(|e| AppError::Run(e.to_string()))?,
                        )
                    }
                },
            }),
        };
        pretty(&Project {
            format: PROJECT_FORMAT.to_string(),
            version: PROJECT_VERSION,
            name: self.name.clone(),
            data: ProjectData {
                images: d.images.clone(),
                members: d.members.clone(),
                arcs: d.arcs.clone(),
                model: d.model.clone(),
                shear: d.shear.clone(),
                deflection_x: stored(0),
                deflection_y: stored(1),
            },
            settings: self.settings.clone(),
            result,
        })
    }

    /// Replaces the session by the project in `text` (`source_name` names it in errors). The
    /// session changes only if the whole project reads: format, version, every data file and
    /// the settings. A stored reconstruction is rebuilt from its `X` (no iterations); a forward
    /// model is recomputed.
    pub fn open_project(
        &mut self,
        text: &str,
        source_name: &str,
    ) -> Result<ReopenReport, AppError> {
        check_header(text, source_name)?;
        let p: Project = serde_json::from_str(text).map_err(|e| {
            AppError::File(format!("{source_name}: {}", json_error_message(text, &e)))
        })?;
        p.settings
            .validate()
            .map_err(|e| AppError::File(format!("{source_name}: settings: {e}")))?;
        let mut next = Session {
            settings: p.settings,
            name: p.name.clone(),
            ..Session::default()
        };
        use super::DataRole as R;
        let mut files = Vec::new();
        for (role, file) in [
            (R::Images, &p.data.images),
            (R::Members, &p.data.members),
            (R::Arcs, &p.data.arcs),
            (R::Model, &p.data.model),
            (R::Shear, &p.data.shear),
        ] {
            if let Some(f) = file {
                let report = next
                    .load_text(role, &f.name, &f.text)
                    .map_err(|e| AppError::File(format!("{source_name}: {e}")))?;
                files.push(report);
            }
        }
        for (axis, file) in [&p.data.deflection_x, &p.data.deflection_y]
            .into_iter()
            .enumerate()
        {
            if let Some(f) = file {
                let bytes = stored_bytes(f, source_name)?;
                let report = next
                    .load_fits(axis, &f.name, &bytes)
                    .map_err(|e| AppError::File(format!("{source_name}: {e}")))?;
                files.push(report);
            }
        }
        let (result, message) = match p.result {
            None => ("none", "project opened".to_string()),
            Some(r) => match (r.kind, r.x) {
                (RunKind::Reconstruct, Some(x)) => {
                    // Iterates that do not fit the result are left out, and the message says so.
                    let (iterates, dropped) = match r.iterates.map(|i| i.to_iterates(x.len())) {
                        None => (Vec::new(), String::new()),
                        Some(Ok(i)) => (i, String::new()),
                        Some(Err(e)) => (
                            Vec::new(),
                            format!("; its stored iterates were not used ({e})"),
                        ),
                    };
                    // An "auto" strength's choice, when summary.json has one that reads.
                    let choice = r
                        .summary
                        .get("strength_choice")
                        .and_then(|c| serde_json::from_value(c.clone()).ok());
                    // The run's warnings, as its summary.json lists them.
                    let warnings = r
                        .summary
                        .get("warnings")
                        .and_then(|w| serde_json::from_value(w.clone()).ok());
                    match next.restore_reconstruction(StoredRun {
                        x,
                        iterations: r.iterations,
                        convergence: r.convergence,
                        sources: r.sources,
                        iterates,
                        choice,
                        warnings,
                    }) {
                        Ok(()) => {
                            let ensemble = next.restore_ensemble(r.ensemble);
                            (
                                "restored",
                                format!(
                                    "the last reconstruction is back, its maps rebuilt from the \
                                     stored cell masses (not solved again){dropped}{ensemble}"
                                ),
                            )
                        }
                        Err(e) => (
                            "solve_needed",
                            format!("the stored solution was not used ({e}): reconstruct again"),
                        ),
                    }
                }
                (RunKind::Reconstruct, None) => (
                    "solve_needed",
                    "no stored solution: reconstruct again".to_string(),
                ),
                (kind, _) => match next.run(kind, &mut |_| crate::solver::Control::Continue) {
                    Ok(()) => ("recomputed", "maps computed again".to_string()),
                    Err(e) => ("solve_needed", format!("could not recompute: {e}")),
                },
            },
        };
        *self = next;
        Ok(ReopenReport {
            name: p.name,
            result: result.to_string(),
            message,
            files,
        })
    }
}

//! Ensembles in the app: after a reconstruction, `ensemble.members` more that differ in the
//! systems fitted and the grid's placement ([`crate::reconstruct::run_ensemble`], `wslap
//! reconstruct --ensemble N --seed S`). The app runs them in pieces so that web workers can
//! share them: [`Session::ensemble_plan`] draws every member from the seed, any session with
//! the same data and settings runs a member ([`Session::ensemble_member`]), and
//! [`Session::set_ensemble`] combines them into the result's ensemble: its spread view, its
//! files and the interval of the read-out. A project keeps it ([`StoredEnsemble`]): its record
//! and its five statistics maps, not the members' own maps.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::error::BadFieldValue;
use crate::map::{Map, MapGeometry};
use crate::reconstruct::{
    check_ensemble_size, ConvergenceRecord, Ensemble, EnsembleMaps, EnsembleMember, EnsemblePlan,
    MemberRun, MemoryLimit, MAX_ENSEMBLE_MEMBERS,
};
use crate::render::{KappaPlotOptions, Overlay};
use crate::solver::Control;
use base64::Engine as _;

use super::data::{f32_base64, f32_values, MAX_STORED_FITS_BYTES};
use super::outputs::pretty;
use super::views::{points, ViewOptions, ViewPng, OBSERVED_RGB};
use super::{AppError, Session};

/// The ensemble setting: how many members (0: none) and the seed of their draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnsembleSettings {
    /// Members after each reconstruction: 0 (default, none) or 2 to
    /// [`crate::MAX_ENSEMBLE_MEMBERS`].
    pub members: usize,
    /// Seed of the members' draws (default 1, as `wslap reconstruct --seed`).
    pub seed: u64,
}

impl Default for EnsembleSettings {
    fn default() -> Self {
        Self {
            members: 0,
            seed: 1,
        }
    }
}

impl EnsembleSettings {
    /// 0, or 2 to [`crate::MAX_ENSEMBLE_MEMBERS`] members.
    pub fn validate(&self) -> Result<(), AppError> {
        if self.members == 0 {
            return Ok(());
        }
        check_ensemble_size(self.members).map_err(|_| {
            let reason = format!("0 for none, or 2 to {MAX_ENSEMBLE_MEMBERS} members");
            AppError::Setting(
                BadFieldValue::new("members", self.members as f64, reason).to_string(),
            )
        })
    }

    /// Bytes of the members' maps the session keeps until they are combined: a kappa and a
    /// magnification map of `pixels` x `pixels` doubles per member.
    pub fn maps_bytes(&self, pixels: usize) -> u64 {
        self.members as u64 * 2 * (pixels as u64).pow(2) * 8
    }

    /// The members' maps must fit in half of `limit` (the other half is the main run's).
    pub fn check_memory(&self, pixels: usize, limit: MemoryLimit) -> Result<(), BadFieldValue> {
        let bytes = self.maps_bytes(pixels);
        if bytes <= limit.bytes / 2 {
            return Ok(());
        }
        Err(BadFieldValue::new(
            "ensemble.members",
            self.members as f64,
            format!(
                "its members' maps of {pixels} x {pixels} pixels take {}, more than half the {} \
                 {}; lower ensemble.members or reconstruct.products.pixels",
                crate::reconstruct::Bytes(bytes),
                crate::reconstruct::Bytes(limit.bytes),
                limit.what
            ),
        ))
    }
}

/// The ensemble's values under a point of the map (the click read-out).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EnsembleReadout {
    pub members: usize,
    /// Mean and standard deviation of kappa over the members (`D_ls/D_s = 1`).
    pub kappa_mean: f64,
    pub kappa_std: f64,
    /// 16th, 50th and 84th percentiles of the magnification at `z_source`.
    pub magnification_p16: f64,
    pub magnification_p50: f64,
    pub magnification_p84: f64,
    /// The source redshift of the percentiles: the main run's at the time of the ensemble,
    /// which the curves' z_s may have left since.
    pub z_source: f64,
}

fn run_error(e: impl std::fmt::Display) -> AppError {
    AppError::Run(e.to_string())
}

fn no_ensemble() -> AppError {
    AppError::Missing(
        "no ensemble yet: set \"Ensemble members\" in the settings (2 to 200) and press \
         Reconstruct"
            .to_string(),
    )
}

impl Session {
    /// The plan of the ensemble the settings ask for after the last result, a reconstruction
    /// of the loaded data with the current settings; `None` when `ensemble.members` is 0.
    pub fn ensemble_plan(&self) -> Result<Option<EnsemblePlan>, AppError> {
        let e = self.settings.ensemble;
        if e.members == 0 {
            return Ok(None);
        }
        let main = self.result()?.reconstruction().ok_or_else(|| {
            AppError::Missing("an ensemble needs a reconstruction: press Reconstruct".to_string())
        })?;
        e.check_memory(main.products.maps.geometry().pixels, MemoryLimit::here())
            .map_err(run_error)?;
        self.with_inputs(|inputs, config, _| {
            EnsemblePlan::new(inputs, config, main, e.members, e.seed)
                .map(Some)
                .map_err(run_error)
        })
    }

    /// Member `member` (1-based) of `plan` on the loaded data and settings (those of the run
    /// the plan was made from); the session's result is not touched. `progress` sees every
    /// solver report; a cancel is an error.
    pub fn ensemble_member(
        &self,
        plan: &EnsemblePlan,
        member: usize,
        progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
    ) -> Result<MemberRun, AppError> {
        self.with_inputs(|inputs, config, _| {
            plan.run_member(inputs, config, member, progress)
                .map_err(run_error)?
                .ok_or_else(|| AppError::Run("cancelled".to_string()))
        })
    }

    /// The ensemble of `runs` (members of `plan`, in any order) becomes the result's; the
    /// members' own maps are not kept (their statistics are). `complete`: every member ran.
    /// Fails when the result is not the reconstruction the plan was made from (another run
    /// replaced it) or a run is not of the plan.
    pub fn set_ensemble(
        &mut self,
        plan: &EnsemblePlan,
        runs: Vec<MemberRun>,
        complete: bool,
    ) -> Result<(), AppError> {
        let result = self
            .result
            .as_mut()
            .ok_or_else(|| AppError::Missing("nothing has been computed yet".to_string()))?;
        let main = result.reconstruction().filter(|r| {
            r.products.maps.geometry() == plan.geometry
                && r.system.grid.center == plan.grid_center_arcsec
                && r.system.grid.width_arcsec == plan.grid_width_arcsec
        });
        let Some(main) = main else {
            return Err(AppError::Run(
                "the reconstruction changed while its ensemble ran: press Reconstruct again"
                    .to_string(),
            ));
        };
        let mut ensemble = plan.combine(main, runs, complete).map_err(run_error)?;
        if let Some(maps) = &mut ensemble.maps {
            maps.member_kappa = Vec::new();
            maps.member_magnif = Vec::new();
        }
        result.ensemble = Some(Box::new(ensemble));
        Ok(())
    }

    /// The last result's ensemble, if it has one.
    pub fn ensemble(&self) -> Option<&Ensemble> {
        self.result.as_ref()?.ensemble.as_deref()
    }

    /// `ensemble.json` as `wslap reconstruct --ensemble` writes it: the members (their systems,
    /// grid shifts, Einstein radii and masses) and the intervals.
    pub fn ensemble_json(&self) -> Result<String, AppError> {
        pretty(self.ensemble().ok_or_else(no_ensemble)?)
    }

    /// The ensemble's files as `wslap reconstruct --ensemble` writes them, without the members'
    /// maps (`range/`): `kappa-mean.fits`, `kappa-std.fits`, `magnif-p16.fits`,
    /// `magnif-p50.fits`, `magnif-p84.fits` and `kappa-std.png` (with the result's curves).
    pub fn ensemble_files(&self) -> Result<Vec<(String, Vec<u8>)>, AppError> {
        let ensemble = self.ensemble().ok_or_else(no_ensemble)?;
        let p = self.result()?.products();
        ensemble
            .files(p.reference, p.plane.z_lens, Some(&p.curves))
            .map_err(run_error)
    }

    /// The spread view: the members' standard deviation of kappa with the result's critical
    /// curves and, as `opts` selects, the observed images (where the map is pinned down).
    pub fn spread_view(&self, opts: &ViewOptions) -> Result<ViewPng, AppError> {
        let ensemble = self.ensemble().ok_or_else(no_ensemble)?;
        let r = self.result()?;
        let mut overlay = Overlay {
            curves: Some(&r.products().curves),
            ..Overlay::default()
        };
        if opts.show_observed {
            let o = r.marks.observed.clone();
            let marker = crate::render::Marker::Plus;
            overlay
                .points
                .push(points("observed", OBSERVED_RGB, marker, o));
        }
        let base = KappaPlotOptions {
            map_pixels_on_screen: opts.map_side_px()?,
            legend: opts.legend,
            ..KappaPlotOptions::default()
        };
        let png = ensemble
            .spread_png(&overlay, base)
            .map_err(|e| AppError::Run(format!("rendering: {e}")))?
            .ok_or_else(no_ensemble)?;
        Ok(ViewPng {
            name: "kappa-std.png".to_string(),
            png,
        })
    }

    /// The ensemble's values at `p` (arcsec), `None` without an ensemble or off its map.
    pub fn ensemble_at(&self, p: DVec2) -> Option<EnsembleReadout> {
        let e = self.ensemble()?;
        let maps = e.maps.as_ref()?;
        let g = maps.kappa_std.geometry;
        if (p - g.center).abs().max_element() > 0.5 * g.size_arcsec {
            return None;
        }
        let at = |m: &Map| m.sample(p);
        Some(EnsembleReadout {
            members: e.members.len(),
            kappa_mean: at(&maps.kappa_mean),
            kappa_std: at(&maps.kappa_std),
            magnification_p16: at(&maps.magnif_p16),
            magnification_p50: at(&maps.magnif_p50),
            magnification_p84: at(&maps.magnif_p84),
            z_source: e.z_source,
        })
    }
}

/// A member's record and maps from their parts (as a web worker hands them over): the maps'
/// values must fill `plan`'s map.
pub fn member_run(
    plan: &EnsemblePlan,
    record: EnsembleMember,
    kappa: Vec<f64>,
    magnif: Vec<f64>,
) -> Result<MemberRun, AppError> {
    let geometry = plan.geometry;
    let n = geometry.pixels * geometry.pixels;
    if kappa.len() != n || magnif.len() != n {
        return Err(AppError::Run(format!(
            "ensemble member {}: its maps have {} and {} values, not the {n} of the ensemble's \
             {p} x {p} map",
            record.member,
            kappa.len(),
            magnif.len(),
            p = geometry.pixels
        )));
    }
    Ok(MemberRun {
        record,
        kappa: Map {
            geometry,
            data: kappa,
        },
        magnif: Map {
            geometry,
            data: magnif,
        },
    })
}

/// Most bytes of an ensemble's statistics maps a project keeps, as of a deflection FITS
/// ([`MAX_STORED_FITS_BYTES`]): the five maps as `f32` up to 1024 x 1024 pixels. The app's
/// 256 x 256 maps take 5 x 256² x 4 = 1 310 720 bytes, 1 747 628 characters of base64 (with
/// the members' records, about 1.76 MB for 20 members); a larger ensemble keeps its record
/// and intervals without the maps.
pub const MAX_STORED_ENSEMBLE_MAP_BYTES: usize = MAX_STORED_FITS_BYTES;

/// The statistics maps a project keeps, in the order of [`StoredEnsemble::maps_f32_base64`].
const STORED_MAPS: usize = 5;

/// An ensemble in a project file: its record (`ensemble.json`: members, intervals, note) and
/// its statistics maps, `kappa_mean`, `kappa_std`, `magnif_p16`, `magnif_p50` and
/// `magnif_p84` as little-endian `f32` in base64 (the read-out and the spread view need no
/// more). The members' own maps (`range/`) are not kept: the app drops them once combined.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredEnsemble {
    pub record: Ensemble,
    /// The maps' geometry: the reconstruction's map.
    pub geometry: MapGeometry,
    /// `5 x pixels²` values, map after map; `None` above [`MAX_STORED_ENSEMBLE_MAP_BYTES`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub maps_f32_base64: Option<String>,
}

impl StoredEnsemble {
    /// `e`, the ensemble of a result on maps of `geometry`, for a project file: its record,
    /// and its statistics maps when it has them within [`MAX_STORED_ENSEMBLE_MAP_BYTES`] (an
    /// ensemble reopened with its intervals only is kept so again).
    pub fn from_ensemble(e: &Ensemble, geometry: MapGeometry) -> Self {
        let maps_f32_base64 = e.maps.as_ref().and_then(|maps| {
            let all = [
                &maps.kappa_mean,
                &maps.kappa_std,
                &maps.magnif_p16,
                &maps.magnif_p50,
                &maps.magnif_p84,
            ];
            let bytes = all.iter().map(|m| m.data.len() * 4).sum::<usize>();
            (bytes <= MAX_STORED_ENSEMBLE_MAP_BYTES)
                .then(|| f32_base64(all.iter().flat_map(|m| m.data.iter().copied())))
        });
        Self {
            record: Ensemble {
                maps: None,
                ..e.clone()
            },
            geometry,
            maps_f32_base64,
        }
    }

    /// The ensemble again, its maps checked against `geometry` (the restored result's map);
    /// the error says what does not fit. Without stored maps, the record alone (the caption's
    /// intervals; no spread view or read-out).
    pub fn to_ensemble(&self, geometry: MapGeometry) -> Result<Ensemble, String> {
        if self.record.members.is_empty() {
            return Err("it has no members".to_string());
        }
        let mut e = Ensemble {
            maps: None,
            ..self.record.clone()
        };
        let Some(text) = &self.maps_f32_base64 else {
            return Ok(e);
        };
        if self.geometry != geometry {
            return Err(format!(
                "its maps are of {}, the result's of {geometry}",
                self.geometry
            ));
        }
        let n = geometry.pixels.saturating_mul(geometry.pixels);
        let want = n.saturating_mul(STORED_MAPS * 4);
        if want > MAX_STORED_ENSEMBLE_MAP_BYTES || text.len() / 4 * 3 > want + 3 {
            return Err(format!(
                "its maps take more than the {MAX_STORED_ENSEMBLE_MAP_BYTES} bytes a project keeps"
            ));
        }
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(text)
            .map_err(|err| format!("its maps are not base64: {err}"))?;
        if bytes.len() != want {
            return Err(format!(
                "its maps have {} bytes, not the {want} of five {p} x {p} maps",
                bytes.len(),
                p = geometry.pixels
            ));
        }
        let values = f32_values(&bytes);
        // kappa is finite wherever there is a map; a magnification may not be (at a critical
        // curve, or beyond f32's range), and is kept as stored.
        if values[..2 * n].iter().any(|v| !v.is_finite()) {
            return Err("a value of its kappa maps is not a finite number".to_string());
        }
        let maps: Vec<Map> = values
            .chunks_exact(n.max(1))
            .map(|data| Map {
                geometry,
                data: data.to_vec(),
            })
            .collect();
        let Ok([kappa_mean, kappa_std, magnif_p16, magnif_p50, magnif_p84]) =
            <[Map; STORED_MAPS]>::try_from(maps)
        else {
            return Err("its maps are not five maps".to_string());
        };
        e.maps = Some(EnsembleMaps {
            kappa_mean,
            kappa_std,
            magnif_p16,
            magnif_p50,
            magnif_p84,
            member_kappa: Vec::new(),
            member_magnif: Vec::new(),
        });
        Ok(e)
    }
}

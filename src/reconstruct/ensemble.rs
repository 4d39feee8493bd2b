//! Ensembles: how sure the map is.
//!
//! One reconstruction is one answer; an ensemble is many, each as good as the first, that
//! differ in what the data leave open. Member `k` is a full reconstruction with the main run's
//! settings and with
//!
//! - **the systems fitted drawn at random** (bootstrap over systems): as many draws with
//!   replacement as there are fitted systems; the systems drawn at least once are fitted
//!   (a system drawn twice counts once), the others (about a third) are left out;
//! - **the regulariser, its strength and the grid chosen again on that draw**, when the main
//!   run's were "auto": the main run's cross-validation is not rerun, but its rule (fewest
//!   unmatched, then smallest median held-out offset) is applied to the held-out offsets of
//!   the systems the member drew, each counted as often as drawn
//!   ([`StrengthChoice::best_for`]). Candidates the data cannot tell apart then share the
//!   members, so the choice's own uncertainty is in the spread (on the six synthetic
//!   clusters of `tests/data/fidelity`, 20 members: the main run's choice in 3 to 16 of
//!   them);
//! - **the grid moved** by up to half a cell in x and y (uniform), so that where the cells fall
//!   is not mistaken for structure.
//!
//! The start is not varied: the default objective has one minimiser, which the exact solver
//! finds from any start ([method §9]). Catalogue redshifts are not drawn (they carry no
//! uncertainty); a system whose redshift the main run estimated is fitted by each member at a
//! redshift drawn from that estimate (a normal of the interval's width on each side of the
//! most probable value, not below the interval).
//!
//! Every member's maps are sampled on the main run's map. Per pixel, the ensemble gives the
//! mean and standard deviation of kappa and the 16th, 50th and 84th percentiles of the
//! magnification (HFF `kappa-mean`, `kappa-std`, `magnif-p16/p50/p84`), and over the members
//! the 16th - 84th percentile range of the Einstein radius and of the masses inside 10, 20 and
//! 50 arcsec. The spread says how much the answer depends on which systems are fitted and on
//! the grid; it does not include errors common to every member (the members' mass-to-light
//! law, the cosmology, a wrong redshift, mass outside the grid that no image constrains).
//!
//! [method §9]: crate::method#9-the-default-objective

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::crossval::SpreadSum;
use super::{
    fitted_system_ids, reconstruct, reconstruct_with_choice, Candidate, ConvergenceRecord, Inputs,
    ReconstructConfig, ReconstructError, Reconstruction, Regulariser, StrengthChoice,
};
use crate::curves::CriticalCurves;
use crate::error::BadFieldValue;
use crate::fits::{write_image, Card, FitsWriteOptions};
use crate::map::{magnification_at_point, Map, MapGeometry};
use crate::products::ProductsError;
use crate::render::{render_kappa_png, ColorScale, KappaPlotOptions, Overlay};
use crate::simulate::rng::Rng;
use crate::sky::SkyReference;
use crate::solver::{Control, SolveStatus};
use crate::stats::quantile;

/// Most members of an ensemble: each is a full reconstruction.
pub const MAX_ENSEMBLE_MEMBERS: usize = 200;

/// One member of an ensemble.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnsembleMember {
    /// 1-based member number.
    pub member: usize,
    /// The systems it fitted (the bootstrap draw).
    pub fitted: Vec<String>,
    /// How far its grid was moved from the main run's (arcsec).
    pub grid_shift_arcsec: DVec2,
    /// The redshifts it fitted the systems at whose redshift the main run estimated.
    #[serde(default)]
    pub redshifts: Vec<(String, f64)>,
    /// The regulariser and strength it used (`None`: a fixed strength, the main run's).
    #[serde(default)]
    pub regulariser: Option<Regulariser>,
    #[serde(default)]
    pub strength: Option<f64>,
    /// The grid's cells a side it used (`None`: the main run's).
    #[serde(default)]
    pub cells: Option<usize>,
    pub status: String,
    /// `C_l` per layer.
    pub c: Vec<f64>,
    /// Its Einstein radius at the products' z_s (arcsec).
    pub einstein_radius_arcsec: f64,
    /// Its projected mass (Msun) inside 10, 20 and 50 arcsec of (0, 0).
    pub mass_within_arcsec: Vec<(f64, Option<f64>)>,
    /// Median offset of the images it did not fit from their predictions (arcsec).
    pub left_out_image_offset_median_arcsec: Option<f64>,
    pub elapsed_ms: f64,
}

/// The result of [`run_ensemble`] (`ensemble.json`, and the maps as FITS).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ensemble {
    /// "Completed", or "Cancelled" (the members before it are kept).
    pub status: String,
    pub seed: u64,
    pub z_source: f64,
    pub members: Vec<EnsembleMember>,
    /// 16th and 84th percentiles over the members (arcsec).
    pub einstein_radius_interval_arcsec: Option<[f64; 2]>,
    /// Per radius of `summary.json` (10, 20, 50 arcsec): the 16th and 84th percentiles of the
    /// enclosed mass over the members (Msun; `null` where a member's circle left its map).
    pub mass_within_interval_msun: Vec<(f64, Option<[f64; 2]>)>,
    /// What the spread includes and what it does not.
    pub note: String,
    #[serde(skip)]
    pub maps: Option<EnsembleMaps>,
}

/// Per-pixel statistics of the members, on the main run's map, and each member's own maps.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleMaps {
    pub kappa_mean: Map,
    pub kappa_std: Map,
    /// Magnification at the products' z_s: 16th, 50th and 84th percentiles.
    pub magnif_p16: Map,
    pub magnif_p50: Map,
    pub magnif_p84: Map,
    /// Each member's kappa and magnification (for `range/`).
    pub member_kappa: Vec<Map>,
    pub member_magnif: Vec<Map>,
}

const NOTE: &str = "Members differ in the systems fitted (bootstrap over systems), in the \
     regulariser and strength an \"auto\" choice makes on those systems, in the grid's \
     placement (up to half a cell) and in the redshifts of the systems whose redshift was \
     estimated (drawn from the estimate). Not included: the members' mass-to-light law, the \
     cosmology, errors of catalogue redshifts, and mass that no image constrains.";

impl Ensemble {
    /// The files of `wslap reconstruct --ensemble`: `kappa-mean.fits`, `kappa-std.fits`,
    /// `magnif-p16.fits`, `magnif-p50.fits`, `magnif-p84.fits` (HFF-style like `kappa.fits`:
    /// sky `reference`, `ZLENS`, the members in `NMEMBERS`, `ZSOURCE` on the magnifications),
    /// `range/NNN-kappa.fits` and `range/NNN-magnif.fits` per member, and `kappa-std.png`, the
    /// spread with the critical `curves` of the main run on top. Empty without maps.
    pub fn files(
        &self,
        reference: Option<SkyReference>,
        z_lens: f64,
        curves: Option<&CriticalCurves>,
    ) -> Result<Vec<(String, Vec<u8>)>, ProductsError> {
        let Some(maps) = &self.maps else {
            return Ok(Vec::new());
        };
        let n = self.members.len();
        let opts = |what: &str, magnification: bool| {
            let mut extra_cards = vec![
                Card::real("ZLENS", z_lens, "lens redshift"),
                Card::integer("NMEMBERS", n as i64, "members of the ensemble"),
            ];
            if magnification {
                extra_cards.push(Card::real("ZSOURCE", self.z_source, "source redshift"));
            }
            FitsWriteOptions {
                bunit: String::new(),
                comments: vec![
                    format!("{what}, written by wslap {}", env!("CARGO_PKG_VERSION")),
                    if magnification {
                        "Magnification at the source redshift ZSOURCE.".to_string()
                    } else {
                        "Normalised to D_ls/D_s = 1 (HFF convention).".to_string()
                    },
                ],
                reference,
                extra_cards,
            }
        };
        let mut files = vec![
            (
                "kappa-mean.fits".to_string(),
                write_image(
                    &maps.kappa_mean,
                    &opts("Mean convergence of the ensemble", false),
                )?,
            ),
            (
                "kappa-std.fits".to_string(),
                write_image(
                    &maps.kappa_std,
                    &opts(
                        "Standard deviation of the convergence over the ensemble",
                        false,
                    ),
                )?,
            ),
        ];
        for (name, map, q) in [
            ("magnif-p16.fits", &maps.magnif_p16, 16),
            ("magnif-p50.fits", &maps.magnif_p50, 50),
            ("magnif-p84.fits", &maps.magnif_p84, 84),
        ] {
            let what = format!("{q}th percentile of the magnification over the ensemble");
            files.push((name.to_string(), write_image(map, &opts(&what, true))?));
        }
        for (k, (kappa, magnif)) in maps
            .member_kappa
            .iter()
            .zip(&maps.member_magnif)
            .enumerate()
        {
            let what = format!("Member {} of the ensemble", k + 1);
            files.push((
                format!("range/{:03}-kappa.fits", k + 1),
                write_image(kappa, &opts(&what, false))?,
            ));
            files.push((
                format!("range/{:03}-magnif.fits", k + 1),
                write_image(magnif, &opts(&what, true))?,
            ));
        }
        let overlay = Overlay {
            curves,
            ..Overlay::default()
        };
        if let Some(png) = self.spread_png(&overlay, KappaPlotOptions::default())? {
            files.push(("kappa-std.png".to_string(), png));
        }
        Ok(files)
    }

    /// `kappa-std.png`: the spread of kappa over the members (linear, from 0) with what
    /// `overlay` draws on top (the critical curves of the main run), on a map of `base`'s size
    /// with its legend; `None` without maps.
    pub fn spread_png(
        &self,
        overlay: &Overlay<'_>,
        base: KappaPlotOptions,
    ) -> Result<Option<Vec<u8>>, ProductsError> {
        let Some(maps) = &self.maps else {
            return Ok(None);
        };
        let n = self.members.len();
        let title = match overlay.curves {
            Some(c) => format!(
                "Spread of κ over {n} members; critical curves at z_{{s}} = {}",
                c.z_source
            ),
            None => format!("Spread of kappa over {n} members"),
        };
        let plot = KappaPlotOptions {
            scale: ColorScale::Linear,
            vmin: Some(0.0),
            title: Some(title),
            colorbar_label: Some("kappa std".to_string()),
            ..base
        };
        Ok(Some(render_kappa_png(&maps.kappa_std, overlay, &plot)?))
    }

    /// Adds the ensemble's ranges to a `summary.json` object, as `wslap reconstruct
    /// --ensemble` writes them: `einstein_radius_interval_arcsec`, `mass_within_interval_msun`
    /// and `ensemble_members`.
    pub fn add_to_summary(&self, summary: &mut serde_json::Value) {
        if let Some(s) = summary.as_object_mut() {
            s.insert(
                "einstein_radius_interval_arcsec".to_string(),
                serde_json::json!(self.einstein_radius_interval_arcsec),
            );
            s.insert(
                "mass_within_interval_msun".to_string(),
                serde_json::json!(self.mass_within_interval_msun),
            );
            s.insert(
                "ensemble_members".to_string(),
                serde_json::json!(self.members.len()),
            );
        }
    }
}

fn interval(mut values: Vec<f64>) -> Option<[f64; 2]> {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    Some([quantile(&values, 0.16), quantile(&values, 0.84)])
}

/// Checks the number of members.
pub fn check_ensemble_size(members: usize) -> Result<(), ReconstructError> {
    if !(2..=MAX_ENSEMBLE_MEMBERS).contains(&members) {
        return Err(BadFieldValue::new(
            "ensemble",
            members as f64,
            "an ensemble needs 2 to 200 members",
        )
        .into());
    }
    Ok(())
}

/// `members` reconstructions of `inputs` that differ as the module says, with `main`'s
/// settings, sampled on `main`'s maps. `progress` sees the member number (1-based) and every
/// solver report, and may cancel.
///
/// The same as [`EnsemblePlan::new`], [`EnsemblePlan::run_member`] for every member and
/// [`EnsemblePlan::combine`]: the app runs the members in web workers that way. Natively the
/// members run side by side, one thread each, as many as the memory allows; `progress` is called
/// on this thread, the members' reports interleaved. After a cancel the ensemble holds the
/// members that finished.
pub fn run_ensemble(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    main: &Reconstruction,
    members: usize,
    seed: u64,
    progress: &mut dyn FnMut(usize, &ConvergenceRecord) -> Control,
) -> Result<Ensemble, ReconstructError> {
    let plan = EnsemblePlan::new(inputs, config, main, members, seed)?;
    let threads = super::side_by_side(inputs, config, members)?;
    let numbers: Vec<usize> = (1..=members).collect();
    let outcomes = crate::threads::map_reporting(
        &numbers,
        threads,
        |&member, report| {
            plan.run_member(inputs, config, member, &mut |rec| {
                Control::from(report(rec.clone()))
            })
        },
        &mut |k, rec| progress(numbers[k], &rec).into(),
    );
    let mut runs = Vec::new();
    let mut complete = true;
    for outcome in outcomes {
        match outcome {
            Some(Ok(Some(run))) => runs.push(run),
            Some(Err(e)) if !matches!(e, ReconstructError::Cancelled) => return Err(e),
            // Cancelled, or not started after a cancel.
            _ => complete = false,
        }
    }
    plan.combine(runs, complete)
}

/// How one member differs from the main run: the systems it fits and its grid's shift.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MemberDraw {
    /// 1-based member number.
    pub member: usize,
    /// The systems it fits (drawn at least once).
    pub fitted: Vec<String>,
    /// The fitted systems of the main run it leaves out (never drawn).
    pub left_out: Vec<String>,
    /// How far its grid is moved from the main run's (arcsec).
    pub grid_shift_arcsec: DVec2,
    /// The redshift it fits each system at whose redshift the main run estimated (drawn from
    /// the estimate).
    #[serde(default)]
    pub redshifts: Vec<(String, f64)>,
    /// The regulariser and strength it uses: the main run's "auto" rule applied to the
    /// cross-validation of the systems it drew ([`StrengthChoice::best_for`]). `None` with a
    /// fixed strength (the main run's is used).
    #[serde(default)]
    pub regulariser: Option<Regulariser>,
    #[serde(default)]
    pub strength: Option<f64>,
    /// The grid's cells a side it uses with them (`None`: the main run's choice or settings).
    #[serde(default)]
    pub cells: Option<usize>,
}

/// An ensemble before its members run: what they share, taken from the main run (its grid,
/// its maps, its strength), and every member's draw, all made from `seed` in member order.
/// A member then runs anywhere the same inputs and settings are ([`Self::run_member`]: a
/// thread, a web worker) and gives the same reconstruction; [`Self::combine`] makes the
/// ensemble of the members in any order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnsemblePlan {
    pub seed: u64,
    /// The main run's products' source redshift (magnifications and Einstein radii).
    pub z_source: f64,
    /// The main run's map: every member is sampled on it.
    pub geometry: MapGeometry,
    /// The main run's grid: its centre and width (arcsec) and cells per side.
    pub grid_center_arcsec: DVec2,
    pub grid_width_arcsec: f64,
    pub grid_cells_per_side: usize,
    /// The main run's "auto" choice of the strength (`None` for a fixed strength): the members
    /// use its strength and do not choose again.
    pub strength_choice: Option<StrengthChoice>,
    /// The radii of the main run's `summary.json` masses (arcsec).
    pub radii_arcsec: Vec<f64>,
    pub draws: Vec<MemberDraw>,
}

/// One member's reconstruction: its record and its maps on the plan's map.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberRun {
    pub record: EnsembleMember,
    /// kappa at `D_ls/D_s = 1`.
    pub kappa: Map,
    /// Magnification at the plan's `z_source`.
    pub magnif: Map,
}

impl EnsemblePlan {
    /// The plan of `members` members of `main` (the reconstruction of `inputs` with `config`)
    /// drawn from `seed`: the bootstrap over the fitted systems, redrawn until at least two
    /// distinct systems are fitted, then the grid's shift, member after member from one
    /// random stream.
    pub fn new(
        inputs: &Inputs<'_>,
        config: &ReconstructConfig,
        main: &Reconstruction,
        members: usize,
        seed: u64,
    ) -> Result<Self, ReconstructError> {
        check_ensemble_size(members)?;
        // Systems whose redshift the main run estimated are fitted by every member, at a
        // redshift drawn from the estimate (from a stream of their own: the other draws are
        // those of an ensemble without them).
        let estimated = super::free_z::estimates_of(&main.sources);
        let mut fitting = config.clone();
        fitting.constraints.z_estimates = super::free_z::most_probable_of(&estimated);
        let ids = fitted_system_ids(inputs, &fitting)?;
        if ids.len() < 2 {
            return Err(ReconstructError::Folds {
                folds: 2,
                systems: ids.len(),
            });
        }
        let grid = &main.system.grid;
        let cell = grid.width_arcsec / grid.cells_per_side.max(1) as f64;
        let mut rng = Rng::stream(seed, 0xE25E);
        let mut z_rng = Rng::stream(seed, 0x2ED5);
        let draws = (1..=members)
            .map(|member| {
                // How many times each system was drawn.
                let counts = loop {
                    let mut counts = vec![0usize; ids.len()];
                    for _ in 0..ids.len() {
                        counts[rng.index(ids.len())] += 1;
                    }
                    if counts.iter().filter(|&&n| n > 0).count() >= 2 {
                        break counts;
                    }
                };
                let pick = |want: bool| {
                    ids.iter()
                        .zip(&counts)
                        .filter(|(_, &n)| (n > 0) == want)
                        .map(|(id, _)| id.clone())
                        .collect()
                };
                let shift = DVec2::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5)) * cell;
                let choice = main.strength_choice.as_ref().and_then(|c| {
                    c.best_for(|id| ids.iter().position(|i| i == id).map_or(0, |k| counts[k]))
                });
                MemberDraw {
                    member,
                    fitted: pick(true),
                    left_out: pick(false),
                    grid_shift_arcsec: shift,
                    redshifts: super::free_z::draw(&estimated, &mut z_rng),
                    regulariser: choice.map(|c| c.regulariser),
                    strength: choice.map(|c| c.strength),
                    cells: choice.and_then(|c| c.cells),
                }
            })
            .collect();
        Ok(Self {
            seed,
            z_source: main.products.curves.z_source,
            geometry: main.products.maps.geometry(),
            grid_center_arcsec: grid.center,
            grid_width_arcsec: grid.width_arcsec,
            grid_cells_per_side: grid.cells_per_side,
            strength_choice: main.strength_choice.clone(),
            radii_arcsec: main
                .products
                .summary()
                .mass_within_arcsec
                .iter()
                .map(|(r, _)| *r)
                .collect(),
            draws,
        })
    }

    /// The number of members.
    pub fn members(&self) -> usize {
        self.draws.len()
    }

    /// Member `member` (1-based) of the plan, reconstructed from the `inputs` and `config`
    /// of the main run: its systems, its grid moved, the main run's grid width, map and
    /// strength. `None` when `progress` cancelled it.
    pub fn run_member(
        &self,
        inputs: &Inputs<'_>,
        config: &ReconstructConfig,
        member: usize,
        progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
    ) -> Result<Option<MemberRun>, ReconstructError> {
        let draw = member
            .checked_sub(1)
            .and_then(|k| self.draws.get(k))
            .ok_or_else(|| {
                BadFieldValue::new(
                    "member",
                    member as f64,
                    format!("this ensemble has members 1 to {}", self.members()),
                )
            })?;
        let clock = crate::products::Clock::start();
        let mut member_config = config.clone();
        member_config.grid.width_arcsec = Some(self.grid_width_arcsec);
        member_config.grid.center_arcsec = Some(self.grid_center_arcsec + draw.grid_shift_arcsec);
        member_config.products.size_arcsec = Some(self.geometry.size_arcsec);
        member_config.products.pixels = self.geometry.pixels;
        member_config
            .constraints
            .z_estimates
            .clone_from(&draw.redshifts);
        let left_out: Vec<String> = inputs
            .holdout
            .iter()
            .chain(&draw.left_out)
            .cloned()
            .collect();
        let member_inputs = Inputs {
            holdout: &left_out,
            ..*inputs
        };
        let r = match &self.strength_choice {
            Some(c) => {
                let choice = match (draw.regulariser, draw.strength) {
                    (Some(regulariser), Some(strength)) => c.with_chosen(Candidate {
                        regulariser,
                        strength,
                        cells: draw.cells,
                    }),
                    _ => c.clone(),
                };
                reconstruct_with_choice(&member_inputs, &member_config, choice, progress)?
            }
            None => reconstruct(&member_inputs, &member_config, progress)?,
        };
        if r.status == SolveStatus::Cancelled {
            return Ok(None);
        }
        let (kappa, magnif) = sampled_maps(&r, self.geometry);
        let summary = r.products.summary();
        let record = EnsembleMember {
            member,
            fitted: draw.fitted.clone(),
            grid_shift_arcsec: draw.grid_shift_arcsec,
            redshifts: draw.redshifts.clone(),
            regulariser: draw.regulariser,
            strength: draw.strength,
            cells: draw.cells,
            status: r.status.name().to_string(),
            c: r.layer_factors(),
            einstein_radius_arcsec: summary.einstein_radius_arcsec,
            mass_within_arcsec: summary.mass_within_arcsec,
            left_out_image_offset_median_arcsec: r.image_offset_median_arcsec(true),
            elapsed_ms: clock.ms(),
        };
        Ok(Some(MemberRun {
            record,
            kappa,
            magnif,
        }))
    }

    /// The ensemble of `runs` (members of this plan, in any order, each once), "Completed"
    /// when `complete`, else "Cancelled". Fails when a run is not of this plan (its number or
    /// its maps) or comes twice.
    pub fn combine(
        &self,
        mut runs: Vec<MemberRun>,
        complete: bool,
    ) -> Result<Ensemble, ReconstructError> {
        runs.sort_by_key(|r| r.record.member);
        for (k, run) in runs.iter().enumerate() {
            let m = run.record.member;
            if m == 0 || m > self.members() || (k > 0 && runs[k - 1].record.member == m) {
                return Err(BadFieldValue::new(
                    "member",
                    m as f64,
                    format!(
                        "an ensemble of {} members has each of 1 to {0} once",
                        self.members()
                    ),
                )
                .into());
            }
            if run.kappa.geometry != self.geometry || run.magnif.geometry != self.geometry {
                return Err(BadFieldValue::new(
                    "member",
                    m as f64,
                    "its maps are not on the ensemble's map",
                )
                .into());
            }
        }
        let records: Vec<&EnsembleMember> = runs.iter().map(|r| &r.record).collect();
        let mass_within_interval_msun = self
            .radii_arcsec
            .iter()
            .enumerate()
            .map(|(i, &r)| {
                let values: Option<Vec<f64>> = records
                    .iter()
                    .map(|m| m.mass_within_arcsec.get(i).and_then(|(_, v)| *v))
                    .collect();
                (r, values.and_then(interval))
            })
            .collect();
        let einstein_radius_interval_arcsec =
            interval(records.iter().map(|m| m.einstein_radius_arcsec).collect());
        let mut members = Vec::with_capacity(runs.len());
        let mut kappas = Vec::with_capacity(runs.len());
        let mut magnifs = Vec::with_capacity(runs.len());
        for run in runs {
            members.push(run.record);
            kappas.push(run.kappa);
            magnifs.push(run.magnif);
        }
        Ok(Ensemble {
            status: if complete { "Completed" } else { "Cancelled" }.to_string(),
            seed: self.seed,
            z_source: self.z_source,
            members,
            einstein_radius_interval_arcsec,
            mass_within_interval_msun,
            note: NOTE.to_string(),
            maps: (!kappas.is_empty()).then(|| statistics(self.geometry, kappas, magnifs)),
        })
    }
}

/// A member's kappa (`D_ls/D_s = 1`) and magnification at the products' z_s on the pixels of
/// `geometry` (its own maps have that geometry, or are sampled onto it).
fn sampled_maps(r: &Reconstruction, geometry: MapGeometry) -> (Map, Map) {
    let maps = &r.products.maps;
    if maps.geometry() == geometry {
        return (maps.kappa.clone(), r.products.magnification.clone());
    }
    let f = r.products.distance_ratio;
    let kappa = Map::from_fn(geometry, |p| maps.kappa.sample(p));
    let magnif = Map::from_fn(geometry, |p| {
        let (k, g1, g2) = (
            maps.kappa.sample(p),
            maps.gamma1.sample(p),
            maps.gamma2.sample(p),
        );
        magnification_at_point(f, k, g1, g2)
    });
    (kappa, magnif)
}

fn statistics(geometry: MapGeometry, kappas: Vec<Map>, magnifs: Vec<Map>) -> EnsembleMaps {
    let mut kappa = SpreadSum::new(geometry);
    for k in &kappas {
        kappa.add(&k.data);
    }
    let kappa = kappa.finish().expect("an ensemble has members");
    let n = geometry.pixels * geometry.pixels;
    let mut p = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    let mut column = Vec::with_capacity(magnifs.len());
    for i in 0..n {
        column.clear();
        column.extend(magnifs.iter().map(|mu| mu.data[i]));
        column.sort_by(f64::total_cmp);
        for (out, q) in p.iter_mut().zip([0.16, 0.5, 0.84]) {
            out[i] = quantile(&column, q);
        }
    }
    let map = |data| Map { geometry, data };
    let [p16, p50, p84] = p;
    EnsembleMaps {
        kappa_mean: kappa.mean,
        kappa_std: kappa.spread,
        magnif_p16: map(p16),
        magnif_p50: map(p50),
        magnif_p84: map(p84),
        member_kappa: kappas,
        member_magnif: magnifs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_is_the_16th_to_84th_percentile_of_the_finite_values() {
        let v = vec![5.0, 1.0, f64::NAN, 3.0, 2.0, 4.0];
        let [lo, hi] = interval(v).unwrap();
        assert!((lo - 1.64).abs() < 1e-12 && (hi - 4.36).abs() < 1e-12);
        assert_eq!(interval(vec![f64::NAN]), None);
    }
}

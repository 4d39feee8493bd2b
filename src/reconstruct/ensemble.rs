//! Ensembles: how sure the map is.
//!
//! One reconstruction is one answer; an ensemble is many, each as good as the first, that
//! differ in what the data leave open. Member `k` is a full reconstruction with the main run's
//! settings and with
//!
//! - **the systems fitted drawn at random** (bootstrap over systems): as many draws with
//!   replacement as there are fitted systems (sources: the knots of one galaxy, systems `2.1`
//!   and `2.2`, are drawn together); the systems drawn at least once are fitted
//!   (a system drawn twice counts once), the others (about a third) are left out;
//! - **the regulariser, its strength and the grid chosen again on that draw**, when the main
//!   run's were "auto": the main run's cross-validation is not rerun, but its rule (fewest
//!   unmatched, then smallest median held-out offset) is applied to the held-out offsets of
//!   the systems the member drew, each counted as often as drawn
//!   ([`StrengthChoice::best_for`]). Candidates the data cannot tell apart then share the
//!   members, so the choice's own uncertainty is in the spread (on the six synthetic
//!   clusters of `tests/data/fidelity`, 20 members: the main run's choice in 3 to 16 of
//!   them). A candidate whose map the main run passed over as crowded
//!   ([`avoid_crowded_map`](super::avoid_crowded_map)) is none of the members' choices, and a
//!   member whose own map is crowded moves on to the next candidates of its draw's ranking
//!   as the main run does ([`MemberDraw::then`]; [`EnsembleMember::crowding`] says how
//!   crowded the map it kept is), so that the spread describes maps the verdict would let
//!   stand;
//! - **the grid moved** by up to half a cell in x and y (uniform), so that where the cells fall
//!   is not mistaken for structure;
//! - **the members' mass-to-light law drawn**, when the run has a member catalogue: a factor
//!   `10^(s n)` on `members.mass_to_light` (`n` standard normal, `s` =
//!   `members.mass_to_light_scatter_dex`, default 0.3 dex). Point images hardly measure the
//!   members' mass (their factor `C` then stays at its prior about the law), so without the
//!   draw every member would share the law's error.
//!
//! The start is not varied: the default objective has one minimiser, which the exact solver
//! finds from any start ([method §9]). Catalogue redshifts are not drawn (they carry no
//! uncertainty); a system whose redshift the main run estimated is drawn like the others and
//! fitted, by each member that draws it, at a redshift drawn from that estimate (a normal of
//! the interval's width on each side of the most probable value, not below the interval); a
//! member that leaves it out does not predict it (its redshift came from the other systems).
//!
//! Every member's maps are sampled on the main run's map. The ensemble describes that map,
//! the one the run reports:
//!
//! - per pixel, `kappa-std` is the members' rms deviation from the main run's kappa (their
//!   standard deviation when they centre on it), `kappa-mean` their mean, and
//!   `magnif-p16/p50/p84` the percentiles of their magnifications (HFF names);
//! - the Einstein radius and the masses inside 10, 20 and 50 arcsec get a 68% interval about
//!   the main run's value: the members' 16th and 84th percentiles lie that far below and above
//!   their median. A member fits about two thirds of the systems and its map is not centred on
//!   the main run's (on the synthetic clusters of `tests/data/fidelity` the members' Einstein
//!   radii lie 0.5 - 1.5% above it); the members' own percentile range then misses the value
//!   it should describe, while the distances keep what the spread measures.
//!
//! Both are widened by the [`Calibration`] factor when the members' predictions of the
//! images they left out miss by more than their spread says (never narrowed). The spread
//! says how much the answer depends on which systems are fitted, on the grid and on the
//! members' law; it does not include errors common to every member (the cosmology, a wrong
//! catalogue redshift, the members' profile shape, mass outside the grid that no image
//! constrains), except as far as the calibration sees them at the images.
//!
//! [method §9]: crate::method#9-the-default-objective

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::{
    avoid_crowded_map_trying, fitted_system_ids, reconstruct, reconstruct_with_choice, Candidate,
    ConvergenceRecord, CrowdedMap, Crowding, Inputs, LayerSource, ReconstructConfig,
    ReconstructError, Reconstruction, Regulariser, StrengthChoice, CROWDED_MAP_RETRIES,
};
use crate::catalog::galaxy_indices;
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
    /// How crowded its map is over the systems it fitted (those predicted far more images
    /// than observed, of all it fitted: [`Crowding::of_fitted`], what its choice looked at;
    /// the verdict's rule, [`Crowding::distrusted`]). `None` in an ensemble made before it
    /// was kept.
    #[serde(default)]
    pub crowding: Option<Crowding>,
    /// Whether the map it kept is crowded by the verdict's rule ([`Crowding::distrusted`] of
    /// [`Self::crowding`]): every candidate it tried was, and it kept the least crowded.
    #[serde(default)]
    pub crowded: bool,
    /// The candidates its draw ranked first whose maps were crowded, passed over for the one
    /// it used ([`MemberDraw::then`]), in the order fitted.
    #[serde(default)]
    pub crowded_maps: Vec<CrowdedMap>,
    /// The factor on the members' mass-to-light law it used (drawn from
    /// `members.mass_to_light_scatter_dex`; 1 without member galaxies).
    #[serde(default = "unit_factor")]
    pub member_mass_factor: f64,
    pub status: String,
    /// `C_l` per member layer (not an external shear's).
    pub c: Vec<f64>,
    /// Its Einstein radius at the products' z_s (arcsec).
    pub einstein_radius_arcsec: f64,
    /// Its projected mass (Msun) inside 10, 20 and 50 arcsec of (0, 0).
    pub mass_within_arcsec: Vec<(f64, Option<f64>)>,
    /// Median offset of the images it did not fit from their predictions (arcsec).
    pub left_out_image_offset_median_arcsec: Option<f64>,
    /// The images of the systems its draw left out, each with the position it predicts for
    /// it (the nearest predicted image; absent where it found none). They measure how far the
    /// members' spread is from the model's actual error (`Ensemble::calibration`).
    #[serde(default)]
    pub left_out_images: Vec<LeftOutImage>,
    pub elapsed_ms: f64,
}

fn unit_factor() -> f64 {
    1.0
}

/// An image of a system a member did not fit, and where the member predicts it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LeftOutImage {
    /// The catalogue id of the image.
    pub id: String,
    /// Its observed position (arcsec).
    pub observed_arcsec: DVec2,
    /// The member's nearest predicted image (arcsec), `None` when it predicts none.
    pub predicted_arcsec: Option<DVec2>,
}

/// The result of [`run_ensemble`] (`ensemble.json`, and the maps as FITS).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ensemble {
    /// "Completed", or "Cancelled" (the members before it are kept).
    pub status: String,
    pub seed: u64,
    pub z_source: f64,
    pub members: Vec<EnsembleMember>,
    /// The 68% interval of the main run's Einstein radius (arcsec): the members' 16th and
    /// 84th percentiles' distances from their median, times the calibration factor, about the
    /// main run's value (the module documentation says why).
    pub einstein_radius_interval_arcsec: Option<[f64; 2]>,
    /// Per radius of `summary.json` (10, 20, 50 arcsec): the same interval of the enclosed
    /// mass (Msun; `null` where a member's circle left its map).
    pub mass_within_interval_msun: Vec<(f64, Option<[f64; 2]>)>,
    /// How the members' spread compares with the model's actual error at the images of the
    /// systems they left out, and the factor every spread above was widened by (`None` when
    /// too few such images were predicted, e.g. in ensembles saved before it was measured).
    #[serde(default)]
    pub calibration: Option<Calibration>,
    /// What the spread includes and what it does not.
    pub note: String,
    #[serde(skip)]
    pub maps: Option<EnsembleMaps>,
}

/// The members' spread against the model's error where the data can tell: at the images of
/// the systems a member left out (its bootstrap draw did not include them), which it predicts
/// as a model that never saw them.
///
/// For each such image `j`, the `n_j` members that left its system out and predicted it give
/// predictions `p_mj`: their mean `p_j`, their spread `s_j` (rms distance from `p_j`, over
/// `n_j - 1`) and the miss `e_j = |p_j - observed_j|`. If the observed image were one more
/// draw from the members' distribution (an isotropic normal), `e_j` would have the spread
/// `s_j sqrt(1 + 1/n_j)`, and the median of `e_j` would be `sqrt(ln 2)` times the median of
/// that spread. `ratio` is the measured median miss over that: about 1 when the members'
/// spread is as large as the error, above 1 when the error is larger than the spread.
/// Every spread of the ensemble (the Einstein radius and mass intervals, `kappa-std`) is
/// widened by `factor = max(1, ratio)`: never narrowed, since the members' own spread is
/// the least the data leave open.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Images predicted by at least [`CALIBRATION_MIN_PREDICTIONS`] members.
    pub images: usize,
    /// Median of the misses `e_j` (arcsec).
    pub miss_median_arcsec: f64,
    /// Median of the spreads `s_j sqrt(1 + 1/n_j)` (arcsec).
    pub spread_median_arcsec: f64,
    /// `miss_median / (sqrt(ln 2) spread_median)`.
    pub ratio: f64,
    /// `max(1, ratio)`: what the spreads were widened by.
    pub factor: f64,
}

/// Fewest members that must predict an image for it to count in [`Calibration`].
pub const CALIBRATION_MIN_PREDICTIONS: usize = 3;
/// Fewest such images for a [`Calibration`] (below it the spreads are not widened).
pub const CALIBRATION_MIN_IMAGES: usize = 5;

impl Calibration {
    /// The calibration of `members`' predictions of the images they left out; `None` with
    /// fewer than [`CALIBRATION_MIN_IMAGES`] images predicted by at least
    /// [`CALIBRATION_MIN_PREDICTIONS`] members each.
    pub fn of(members: &[&EnsembleMember]) -> Option<Self> {
        let mut by_image: Vec<(&str, DVec2, Vec<DVec2>)> = Vec::new();
        for image in members.iter().flat_map(|m| &m.left_out_images) {
            let Some(p) = image.predicted_arcsec else {
                continue;
            };
            match by_image.iter_mut().find(|(id, _, _)| *id == image.id) {
                Some((_, _, predictions)) => predictions.push(p),
                None => by_image.push((&image.id, image.observed_arcsec, vec![p])),
            }
        }
        let mut misses = Vec::new();
        let mut spreads = Vec::new();
        for (_, observed, predictions) in &by_image {
            let n = predictions.len();
            if n < CALIBRATION_MIN_PREDICTIONS {
                continue;
            }
            let mean = predictions.iter().copied().sum::<DVec2>() / n as f64;
            let ss: f64 = predictions.iter().map(|p| p.distance_squared(mean)).sum();
            let spread = (ss / (n - 1) as f64).sqrt() * (1.0 + 1.0 / n as f64).sqrt();
            misses.push(mean.distance(*observed));
            spreads.push(spread);
        }
        if misses.len() < CALIBRATION_MIN_IMAGES {
            return None;
        }
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            quantile(&v, 0.5)
        };
        let images = misses.len();
        let miss = median(misses);
        let spread = median(spreads);
        let ratio = miss / (std::f64::consts::LN_2.sqrt() * spread);
        // Members that all predict the same point (spread 0) say nothing about the error.
        let ratio = if ratio.is_finite() { ratio } else { 1.0 };
        Some(Self {
            images,
            miss_median_arcsec: miss,
            spread_median_arcsec: spread,
            ratio,
            factor: ratio.max(1.0),
        })
    }
}

/// Per-pixel statistics of the members, on the main run's map, and each member's own maps.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleMaps {
    pub kappa_mean: Map,
    /// The members' rms deviation from the main run's kappa, times the calibration factor.
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
     regulariser and strength an \"auto\" choice makes on those systems (passing over \
     crowded maps as the main run does), in the grid's \
     placement (up to half a cell), in the redshifts of the systems whose redshift was \
     estimated (drawn from the estimate) and in the member galaxies' mass-to-light law \
     (drawn from members.mass_to_light_scatter_dex). The intervals and kappa-std describe \
     the main map: they are the members' deviations from it, widened by the calibration \
     factor where the members' predictions of the images they did not fit miss by more than \
     their spread. Not included: the cosmology, errors of catalogue redshifts, the member \
     halos' shape, and mass that no image constrains.";

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
            s.insert(
                "ensemble_calibration".to_string(),
                serde_json::json!(self.calibration),
            );
        }
    }
}

/// The interval of the main run's `value` from the members' `values`: the distances of the
/// members' 16th and 84th percentiles from their median, times `factor`, on either side of
/// `value` (of the members' median when the main run has none). The members fit about two
/// thirds of the systems each and may centre away from the main run; the interval is about
/// the map the run reports, and always holds it.
fn interval(value: Option<f64>, mut values: Vec<f64>, factor: f64) -> Option<[f64; 2]> {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let [q16, q50, q84] = [0.16, 0.5, 0.84].map(|q| quantile(&values, q));
    let centre = value.filter(|v| v.is_finite()).unwrap_or(q50);
    Some([centre - factor * (q50 - q16), centre + factor * (q84 - q50)])
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
    plan.combine(main, runs, complete)
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
    /// The candidates its draw ranks next (at most [`CROWDED_MAP_RETRIES`]), fitted in turn
    /// when its own map is crowded, as the main run's are
    /// ([`avoid_crowded_map`](super::avoid_crowded_map)). Candidates
    /// whose map the main run passed over as crowded are not among its own nor these
    /// ([`StrengthChoice::ranked_for`]).
    #[serde(default)]
    pub then: Vec<Candidate>,
    /// The factor on the members' mass-to-light law it fits with: `10^(s n)`, `n` a
    /// standard normal and `s` = `members.mass_to_light_scatter_dex` (1 when the run has no
    /// member catalogue).
    #[serde(default = "unit_factor")]
    pub member_mass_factor: f64,
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
    /// The image-plane error each system whose redshift the main run estimated was fitted
    /// with (`constraints.z_estimate_errors`): every member fits it so too.
    #[serde(default)]
    pub z_position_errors: Vec<(String, f64)>,
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
        // Systems whose redshift the main run estimated are drawn like the others and fitted
        // at a redshift drawn from the estimate (from a stream of their own: the other draws
        // are those of an ensemble without them).
        let estimated = super::free_z::estimates_of(&main.sources);
        let mut fitting = config.clone();
        fitting.constraints.z_estimates = super::free_z::most_probable_of(&estimated);
        let ids = fitted_system_ids(inputs, &fitting)?;
        if ids.len() < 2 {
            return Err(ReconstructError::EnsembleSystems { systems: ids.len() });
        }
        let grid = &main.system.grid;
        let cell = grid.width_arcsec / grid.cells_per_side.max(1) as f64;
        let mut rng = Rng::stream(seed, 0xE25E);
        let mut z_rng = Rng::stream(seed, 0x2ED5);
        // The members' law from a stream of its own too.
        let mut law_rng = Rng::stream(seed, 0x3A5E);
        let law_scatter = match inputs.layers {
            LayerSource::Members(_) => config.members.mass_to_light_scatter_dex,
            _ => 0.0,
        };
        // The bootstrap draws sources: the knots of one galaxy (systems 2.1 and 2.2) together,
        // as a fold holds them out together. Without knots, one system each.
        let (galaxy_of, galaxies) = galaxy_indices(&ids);
        let draws = (1..=members)
            .map(|member| {
                // How many times each system was drawn (its galaxy's draws).
                let counts = loop {
                    let mut drawn = vec![0usize; galaxies];
                    for _ in 0..galaxies {
                        drawn[rng.index(galaxies)] += 1;
                    }
                    let counts: Vec<usize> = galaxy_of.iter().map(|&g| drawn[g]).collect();
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
                let ranked = main.strength_choice.as_ref().and_then(|c| {
                    c.ranked_for(|id| ids.iter().position(|i| i == id).map_or(0, |k| counts[k]))
                });
                let choice = ranked.as_ref().and_then(|r| r.first().copied());
                let then = ranked.map_or_else(Vec::new, |r| {
                    r.into_iter().skip(1).take(CROWDED_MAP_RETRIES).collect()
                });
                MemberDraw {
                    member,
                    fitted: pick(true),
                    left_out: pick(false),
                    grid_shift_arcsec: shift,
                    redshifts: super::free_z::draw(
                        &estimated,
                        |id| super::free_z::search_range(config, id),
                        &mut z_rng,
                    ),
                    regulariser: choice.map(|c| c.regulariser),
                    strength: choice.map(|c| c.strength),
                    cells: choice.and_then(|c| c.cells),
                    then,
                    member_mass_factor: 10f64.powf(law_scatter * law_rng.normal()),
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
            z_position_errors: super::free_z::position_errors_of(&main.sources),
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
        member_config
            .constraints
            .z_estimate_errors
            .clone_from(&self.z_position_errors);
        // Within the law's allowed range (a draw far in the tail of a wide scatter).
        member_config.members.mass_to_light = (config.members.mass_to_light
            * draw.member_mass_factor)
            .clamp(1e-6, crate::inversion::MAX_MASS_TO_LIGHT);
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
        let mut r = match &self.strength_choice {
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
        // A crowded map gives way to the next candidates of the draw's ranking, as the main
        // run's does: the spread then describes maps the verdict would let stand.
        let mut crowded_maps = Vec::new();
        let mut used = (draw.regulariser, draw.strength, draw.cells);
        if let Some(choice) = r.strength_choice.clone() {
            let (choice, map) =
                avoid_crowded_map_trying(&member_inputs, &r, &choice, &draw.then, progress)?;
            crowded_maps.clone_from(&choice.crowded_maps);
            match map {
                Some(map) => {
                    let c = choice.chosen_candidate();
                    used = (Some(c.regulariser), Some(c.strength), c.cells);
                    r = map;
                }
                None => r.strength_choice = Some(choice),
            }
        }
        let (kappa, magnif) = sampled_maps(&r, self.geometry);
        let summary = r.products.summary();
        let crowding = Crowding::of_fitted(&r.sources);
        let record = EnsembleMember {
            member,
            fitted: draw.fitted.clone(),
            grid_shift_arcsec: draw.grid_shift_arcsec,
            redshifts: draw.redshifts.clone(),
            regulariser: used.0,
            strength: used.1,
            cells: used.2,
            crowding: Some(crowding),
            crowded: crowding.distrusted(),
            crowded_maps,
            member_mass_factor: draw.member_mass_factor,
            status: r.status.name().to_string(),
            c: r.member_factors(),
            einstein_radius_arcsec: summary.einstein_radius_arcsec,
            mass_within_arcsec: summary.mass_within_arcsec,
            left_out_image_offset_median_arcsec: r.image_offset_median_arcsec(true),
            left_out_images: r
                .sources
                .iter()
                .filter(|s| s.held_out && draw.left_out.contains(&s.id))
                .flat_map(|s| &s.observed)
                .map(|o| LeftOutImage {
                    id: o.id.clone(),
                    observed_arcsec: o.position_arcsec,
                    predicted_arcsec: o.predicted_arcsec,
                })
                .collect(),
            elapsed_ms: clock.ms(),
        };
        Ok(Some(MemberRun {
            record,
            kappa,
            magnif,
        }))
    }

    /// The ensemble of `runs` (members of this plan, in any order, each once) about `main`,
    /// the reconstruction the plan was made from: "Completed" when `complete`, else
    /// "Cancelled". Its intervals and `kappa-std` describe `main`'s map ([`Calibration`] says
    /// by how much they were widened). Fails when a run is not of this plan (its number or its
    /// maps) or comes twice, or when `main`'s map is not the plan's.
    pub fn combine(
        &self,
        main: &Reconstruction,
        mut runs: Vec<MemberRun>,
        complete: bool,
    ) -> Result<Ensemble, ReconstructError> {
        if main.products.maps.geometry() != self.geometry {
            return Err(BadFieldValue::new(
                "ensemble",
                self.members() as f64,
                "the reconstruction is not the one its members were planned from",
            )
            .into());
        }
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
        let calibration = Calibration::of(&records);
        let factor = calibration.as_ref().map_or(1.0, |c| c.factor);
        let main_summary = main.products.summary();
        let mass_within_interval_msun = self
            .radii_arcsec
            .iter()
            .enumerate()
            .map(|(i, &r)| {
                let values: Option<Vec<f64>> = records
                    .iter()
                    .map(|m| m.mass_within_arcsec.get(i).and_then(|(_, v)| *v))
                    .collect();
                let value = main_summary
                    .mass_within_arcsec
                    .iter()
                    .find(|(radius, _)| *radius == r)
                    .and_then(|(_, v)| *v);
                (r, values.and_then(|v| interval(value, v, factor)))
            })
            .collect();
        let einstein_radius_interval_arcsec = interval(
            Some(main_summary.einstein_radius_arcsec),
            records.iter().map(|m| m.einstein_radius_arcsec).collect(),
            factor,
        );
        let mut members = Vec::with_capacity(runs.len());
        let mut kappas = Vec::with_capacity(runs.len());
        let mut magnifs = Vec::with_capacity(runs.len());
        for run in runs {
            members.push(run.record);
            kappas.push(run.kappa);
            magnifs.push(run.magnif);
        }
        let maps = (!kappas.is_empty())
            .then(|| statistics(&main.products.maps.kappa, factor, kappas, magnifs));
        Ok(Ensemble {
            status: if complete { "Completed" } else { "Cancelled" }.to_string(),
            seed: self.seed,
            z_source: self.z_source,
            members,
            einstein_radius_interval_arcsec,
            mass_within_interval_msun,
            calibration,
            note: NOTE.to_string(),
            maps,
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

/// The ensemble's maps: `kappa_mean` the members' mean; `kappa_std` their rms deviation
/// from `main_kappa` (the map the run reports; equal to their standard deviation when they
/// centre on it) times `factor`; the magnification's percentiles over the members.
fn statistics(main_kappa: &Map, factor: f64, kappas: Vec<Map>, magnifs: Vec<Map>) -> EnsembleMaps {
    let geometry = main_kappa.geometry;
    let n = geometry.pixels * geometry.pixels;
    let count = kappas.len().max(1) as f64;
    let mut mean = vec![0.0; n];
    let mut about_main = vec![0.0; n];
    for k in &kappas {
        for (i, &v) in k.data.iter().enumerate() {
            mean[i] += v / count;
            about_main[i] += (v - main_kappa.data[i]).powi(2) / count;
        }
    }
    for v in &mut about_main {
        *v = factor * v.sqrt();
    }
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
        kappa_mean: map(mean),
        kappa_std: map(about_main),
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
    fn interval_is_the_members_percentile_spread_about_the_main_value() {
        // Percentiles of 1..5: 16th 1.64, median 3, 84th 4.36.
        let v = vec![5.0, 1.0, f64::NAN, 3.0, 2.0, 4.0];
        let close =
            |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12;
        assert!(close(interval(None, v.clone(), 1.0).unwrap(), [1.64, 4.36]));
        assert!(close(
            interval(Some(2.0), v.clone(), 1.0).unwrap(),
            [0.64, 3.36]
        ));
        assert!(close(
            interval(Some(2.0), v.clone(), 2.0).unwrap(),
            [-0.72, 4.72]
        ));
        assert!(close(
            interval(Some(f64::NAN), v, 1.0).unwrap(),
            [1.64, 4.36]
        ));
        assert_eq!(interval(Some(1.0), vec![f64::NAN], 1.0), None);
    }

    fn member(images: Vec<LeftOutImage>) -> EnsembleMember {
        EnsembleMember {
            member: 1,
            fitted: Vec::new(),
            grid_shift_arcsec: DVec2::ZERO,
            redshifts: Vec::new(),
            regulariser: None,
            strength: None,
            cells: None,
            crowding: None,
            crowded: false,
            crowded_maps: Vec::new(),
            member_mass_factor: 1.0,
            status: "Converged".to_string(),
            c: Vec::new(),
            einstein_radius_arcsec: 30.0,
            mass_within_arcsec: Vec::new(),
            left_out_image_offset_median_arcsec: None,
            left_out_images: images,
            elapsed_ms: 0.0,
        }
    }

    /// Six images, each predicted by four members at the corners of a square of side 2 about
    /// a point 3 arcsec from the observed image: spread sqrt(8/3) sqrt(5/4), miss 3.
    #[test]
    fn calibration_compares_the_miss_with_the_spread_of_the_predictions() {
        let corners = [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];
        let members: Vec<EnsembleMember> = corners
            .iter()
            .map(|&(dx, dy)| {
                member(
                    (0..6)
                        .map(|j| LeftOutImage {
                            id: format!("{j}.1"),
                            observed_arcsec: DVec2::new(10.0 * j as f64, 0.0),
                            predicted_arcsec: Some(DVec2::new(10.0 * j as f64 + dx, 3.0 + dy)),
                        })
                        .collect(),
                )
            })
            .collect();
        let refs: Vec<&EnsembleMember> = members.iter().collect();
        let c = Calibration::of(&refs).unwrap();
        let spread = (8.0f64 / 3.0).sqrt() * 1.25f64.sqrt();
        assert_eq!(c.images, 6);
        assert!((c.miss_median_arcsec - 3.0).abs() < 1e-12);
        assert!((c.spread_median_arcsec - spread).abs() < 1e-12);
        let ratio = 3.0 / (std::f64::consts::LN_2.sqrt() * spread);
        assert!((c.ratio - ratio).abs() < 1e-12 && (c.factor - ratio).abs() < 1e-12);
        // Predictions on the observed image: nothing to widen, the factor stays 1.
        let mut on = members.clone();
        for m in &mut on {
            for im in &mut m.left_out_images {
                im.observed_arcsec.y = 3.0;
            }
        }
        let refs: Vec<&EnsembleMember> = on.iter().collect();
        let c = Calibration::of(&refs).unwrap();
        assert!(c.ratio < 1e-12 && c.factor == 1.0);
        // Images predicted by fewer than three members do not count; too few images, none.
        let refs: Vec<&EnsembleMember> = members.iter().take(2).collect();
        assert_eq!(Calibration::of(&refs), None);
    }
}

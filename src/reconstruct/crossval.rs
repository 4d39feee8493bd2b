//! K-fold cross-validation: how well a reconstruction predicts images it was not given.
//!
//! The fitted systems are dealt into `folds` groups in catalogue order (the k-th system to group
//! `k mod folds`, so that neighbouring ids, often neighbours on the sky, are spread over the
//! groups). Each group is held out in turn: the lens is reconstructed from the other systems
//! with the same settings (exactly `wslap reconstruct --holdout GROUP`) and the group's images
//! are predicted by it (beta from the back-projected observed images, each weighted by its
//! inverse lens Jacobian as the image-plane fit weighs them, then the lens equation solved
//! forward). So every system is predicted once, by a lens that never saw it.
//!
//! With an "auto" strength each fold makes the whole choice again on the systems it fits,
//! crowded maps passed over as in the whole run (their crowding counted over the fold's
//! fitted systems only, so that the group it predicts has no say in its map); each fold's
//! `chosen`, `crowded_maps` and `crowding` in `crossval.json` say what it used.
//!
//! A fit's own image offsets say how well the model reproduces its constraints; these say how
//! well it predicts, which is what matters when a model is used to look for new images or to
//! choose between settings. A free-form grid with many more cells than constraints can fit
//! every image and still predict poorly (AS1063's 19 gold systems, default settings, 5 folds:
//! the fitted images lie 0.2″ from their predictions, the held-out ones 2.7″; README,
//! "Cross-validation").

use serde::{Deserialize, Serialize};

use super::summary::{image_offsets_arcsec, median_arcsec, rms_arcsec};
use super::{
    reconstruct_free_z, Candidate, ConvergenceRecord, CrowdedMap, Crowding, Inputs,
    ReconstructConfig, ReconstructError, Reconstruction, SourceReport,
};
use crate::catalog::galaxy_indices;
use crate::curves::CriticalCurves;
use crate::fits::{write_image, Card, FitsWriteOptions};
use crate::inversion::build_constraints;
use crate::map::LensMaps;
use crate::map::{Map, MapGeometry};
use crate::products::ProductsError;
use crate::profiles::MassComponent;
use crate::render::{render_kappa_png, ColorScale, KappaPlotOptions, Overlay};
use crate::sky::SkyReference;
use crate::solver::{Control, SolveStatus};

/// Default number of folds of `wslap reconstruct --folds` and the app.
pub const DEFAULT_FOLDS: usize = 5;

/// One reconstruction of the cross-validation: the lens without one group of systems.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoldRun {
    /// 1-based fold number.
    pub fold: usize,
    /// The systems this fold held out (and predicted).
    pub held_out: Vec<String>,
    pub status: String,
    pub iterations: usize,
    /// `C_l` per member layer of this fold's lens (not an external shear's).
    pub c: Vec<f64>,
    /// Its grid mass in Msun.
    pub grid_mass_msun: f64,
    /// Its Einstein radius at the products' z_s (arcsec): the spread over the folds is a quick
    /// measure of how much the answer depends on which systems are fitted.
    pub einstein_radius_arcsec: f64,
    /// That z_s.
    pub einstein_radius_z_source: f64,
    /// Its projected mass (Msun) inside 10, 20 and 50 arcsec of (0, 0), as in `summary.json`
    /// (`null` where the circle leaves its map).
    #[serde(default)]
    pub mass_within_arcsec: Vec<(f64, Option<f64>)>,
    /// Median offset of the fitted systems' images from their predictions (arcsec).
    pub fit_image_offset_median_arcsec: Option<f64>,
    /// Median offset of the held-out systems' images from their predictions (arcsec).
    pub holdout_image_offset_median_arcsec: Option<f64>,
    /// With an "auto" strength, what the fold's own choice used (`None`: a fixed strength).
    #[serde(default)]
    pub chosen: Option<Candidate>,
    /// The candidates its choice passed over because their maps were crowded, as the whole
    /// run's does ([`super::avoid_crowded_map`]).
    #[serde(default)]
    pub crowded_maps: Vec<CrowdedMap>,
    /// How crowded its map is over the systems it fitted ([`Crowding::of_fitted`]).
    #[serde(default)]
    pub crowding: Option<Crowding>,
    /// Wall-clock time of the fold (ms).
    pub elapsed_ms: f64,
}

/// A system as predicted by the fold that held it out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PredictedSystem {
    /// The fold that held it out (1-based).
    pub fold: usize,
    #[serde(flatten)]
    pub report: SourceReport,
}

/// The result of [`cross_validate`] (`crossval.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrossValidation {
    /// How many folds, whether they all ran, and what they predicted (`crossval.json` has
    /// these at its top level; `summary.json` has them as `crossval`).
    #[serde(flatten)]
    pub totals: CrossvalTotals,
    pub runs: Vec<FoldRun>,
    /// The systems every fold fits and none holds out: those at an estimated redshift
    /// (`constraints.z_estimates`).
    #[serde(default)]
    pub always_fitted: Vec<String>,
    /// Every predicted system once, in catalogue order within each fold.
    pub systems: Vec<PredictedSystem>,
    /// The folds' convergence maps, when asked for (not part of `crossval.json`: the CLI writes
    /// them as FITS).
    #[serde(skip)]
    pub kappa: Option<KappaSpread>,
}

/// A cross-validation's totals ([`CrossValidation::totals`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrossvalTotals {
    pub folds: usize,
    /// "Completed", or "Cancelled" when a fold was cancelled (the folds that finished are
    /// kept).
    pub status: String,
    /// Observed images of the predicted systems, and how many of them had no predicted image
    /// at all (their source lies outside every caustic of the fold's lens at that redshift).
    pub holdout_images: usize,
    pub holdout_images_unmatched: usize,
    /// Median and rms of the held-out images' offsets from their nearest predicted image, over
    /// all folds (arcsec).
    pub holdout_image_offset_median_arcsec: Option<f64>,
    pub holdout_image_plane_rms_arcsec: Option<f64>,
    /// The same for the fitted systems' images, pooled over the folds' fits (arcsec): the
    /// in-sample figure to compare with.
    pub fit_image_offset_median_arcsec: Option<f64>,
}

impl CrossValidation {
    /// Whether every fold ran (not cancelled).
    pub fn completed(&self) -> bool {
        self.totals.status == "Completed"
    }
}

/// The folds' convergence (`D_ls/D_s = 1`) on one map: where the mass map depends on which
/// systems are fitted. Pixels are those of the geometry given to [`cross_validate`].
#[derive(Debug, Clone, PartialEq)]
pub struct KappaSpread {
    /// Mean of the folds' kappa.
    pub mean: Map,
    /// Standard deviation of the folds' kappa about that mean (over the `K` folds, divided by
    /// `K`). A delete-a-group jackknife would take `sqrt(K - 1)` times this as the standard
    /// error of the map made from all the systems.
    pub spread: Map,
}

impl KappaSpread {
    /// The files of `wslap reconstruct --folds` and the app's downloads:
    /// `crossval-kappa-mean.fits` and `crossval-kappa-spread.fits`, HFF-style like
    /// `kappa.fits` (sky `reference` of the frame, lens redshift `ZLENS`, the number of folds
    /// in `NFOLDS`), and `crossval-kappa-spread.png`, the spread as a figure (linear scale from
    /// 0) with critical `curves` on top when given (those of the reconstruction from all the
    /// systems).
    pub fn files(
        &self,
        reference: Option<SkyReference>,
        z_lens: f64,
        curves: Option<&CriticalCurves>,
        folds: usize,
    ) -> Result<Vec<(&'static str, Vec<u8>)>, ProductsError> {
        let opts = |what: &str| FitsWriteOptions {
            bunit: String::new(),
            comments: vec![
                format!(
                    "{what} of the convergence over the {folds} folds of a cross-validation, \
                     written by wslap {}",
                    env!("CARGO_PKG_VERSION")
                ),
                "Normalised to D_ls/D_s = 1 (HFF convention).".to_string(),
            ],
            reference,
            extra_cards: vec![
                Card::real("ZLENS", z_lens, "lens redshift"),
                Card::integer("NFOLDS", folds as i64, "folds of the cross-validation"),
            ],
        };
        let overlay = Overlay {
            curves,
            ..Overlay::default()
        };
        let title = match curves {
            Some(c) => format!(
                "Spread of κ over {folds} folds; critical curves at z_{{s}} = {}",
                c.z_source
            ),
            None => format!("Spread of kappa over {folds} folds"),
        };
        let plot = KappaPlotOptions {
            scale: ColorScale::Linear,
            vmin: Some(0.0),
            title: Some(title),
            colorbar_label: Some("kappa spread".to_string()),
            ..KappaPlotOptions::default()
        };
        Ok(vec![
            (
                "crossval-kappa-mean.fits",
                write_image(&self.mean, &opts("Mean"))?,
            ),
            (
                "crossval-kappa-spread.fits",
                write_image(&self.spread, &opts("Standard deviation (1/K)"))?,
            ),
            (
                "crossval-kappa-spread.png",
                render_kappa_png(&self.spread, &overlay, &plot)?,
            ),
        ])
    }
}

/// Running mean and sum of squared deviations per pixel (Welford): the folds' kappa here, the
/// members' in an ensemble.
pub(super) struct SpreadSum {
    geometry: MapGeometry,
    folds: f64,
    mean: Vec<f64>,
    m2: Vec<f64>,
}

impl SpreadSum {
    pub(super) fn new(geometry: MapGeometry) -> Self {
        let n = geometry.pixels * geometry.pixels;
        Self {
            geometry,
            folds: 0.0,
            mean: vec![0.0; n],
            m2: vec![0.0; n],
        }
    }

    pub(super) fn add(&mut self, kappa: &[f64]) {
        self.folds += 1.0;
        for ((mean, m2), &k) in self.mean.iter_mut().zip(&mut self.m2).zip(kappa) {
            let d = k - *mean;
            *mean += d / self.folds;
            *m2 += d * (k - *mean);
        }
    }

    pub(super) fn finish(self) -> Option<KappaSpread> {
        (self.folds > 0.0).then(|| KappaSpread {
            spread: Map {
                geometry: self.geometry,
                data: self.m2.iter().map(|m2| (m2 / self.folds).sqrt()).collect(),
            },
            mean: Map {
                geometry: self.geometry,
                data: self.mean,
            },
        })
    }
}

/// A fold's convergence at the pixels of `geometry`. Its grid's map is made on the fold's own
/// product map (where its cells fall on the pixel lattice, so by FFT) and interpolated
/// ([`Map::sample_cubic`]) where that map covers a pixel with a pixel to spare; elsewhere the
/// cells are summed at the pixel. The galaxy layers, whose halos are sharper than a pixel, are
/// evaluated at every pixel, times the fold's `C_l`.
fn fold_kappa(r: &Reconstruction, geometry: MapGeometry) -> Result<Vec<f64>, ReconstructError> {
    let grid = r.system.grid_mass(&r.x)?;
    let own = r.products.maps.geometry();
    let grid_map = LensMaps::from_lens(&grid, own).kappa;
    let half = 0.5 * own.size_arcsec - 1.5 * own.pixel_arcsec();
    let layers: Vec<_> = r
        .system
        .layers
        .iter()
        .zip(r.layer_factors())
        .filter(|(_, c)| *c != 0.0)
        .collect();
    Ok(Map::from_fn(geometry, |p| {
        let d = p - own.center;
        let cells = if d.x.abs() <= half && d.y.abs() <= half {
            grid_map.sample_cubic(p)
        } else {
            grid.kappa(p)
        };
        cells + layers.iter().map(|(l, c)| c * l.lens.kappa(p)).sum::<f64>()
    })
    .data)
}

/// The ids of the systems a reconstruction of `inputs` fits, in catalogue order (not the
/// held-out ones, nor those left out for want of a redshift or a second image).
pub fn fitted_system_ids(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
) -> Result<Vec<String>, ReconstructError> {
    config.validate()?;
    let constraints = build_constraints(inputs.images, &config.constraints, inputs.holdout)?;
    Ok(constraints.systems.into_iter().map(|s| s.id).collect())
}

/// The systems a fold may hold out: those `inputs` fits ([`fitted_system_ids`]) at a
/// redshift of their own, not at an estimate (`constraints.z_estimates`: such a redshift was
/// found with the other systems' help, so predicting the system would not be a test).
pub fn holdable_system_ids(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
) -> Result<Vec<String>, ReconstructError> {
    let mut own_redshifts = config.clone();
    own_redshifts.constraints.z_estimates.clear();
    fitted_system_ids(inputs, &own_redshifts)
}

/// The systems a fold may hold out ([`holdable_system_ids`]) by the galaxy they are sources
/// of ([`crate::galaxy_of_system`]: the knots `2.1` and `2.2` of galaxy `2` together,
/// since one predicts the other), galaxies in the order of their first system. Without knots,
/// one system each.
pub fn holdable_sources(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
) -> Result<Vec<Vec<String>>, ReconstructError> {
    let ids = holdable_system_ids(inputs, config)?;
    let (galaxy, galaxies) = galaxy_indices(&ids);
    let mut sources = vec![Vec::new(); galaxies];
    for (id, g) in ids.into_iter().zip(galaxy) {
        sources[g].push(id);
    }
    Ok(sources)
}

/// The groups of system ids that [`cross_validate`] holds out in turn: the systems `inputs`
/// fits ([`fitted_system_ids`]) but those fitted at an estimated redshift
/// (`constraints.z_estimates`), by galaxy ([`holdable_sources`]), the k-th galaxy's to group
/// `k mod folds`. Needs `2 <= folds <=` the number of such galaxies.
pub fn fold_groups(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    folds: usize,
) -> Result<Vec<Vec<String>>, ReconstructError> {
    let sources = holdable_sources(inputs, config)?;
    if folds < 2 || folds > sources.len() {
        return Err(ReconstructError::Folds {
            folds,
            systems: sources.len(),
        });
    }
    let mut groups = vec![Vec::new(); folds];
    for (k, ids) in sources.into_iter().enumerate() {
        groups[k % folds].extend(ids);
    }
    Ok(groups)
}

/// Reconstructs the lens `folds` times, each time without one group of [`fold_groups`], and
/// predicts the images of the group left out. Systems in `inputs.holdout` stay out of every
/// fit and of the result. Systems without a redshift are left out of every fold, unless
/// `constraints.z_estimates` gives them one (as a reconstruction's
/// [`Reconstruction::fit_estimates_in`] sets it): then every fold fits them at it, and none
/// holds them out (their redshift was found with the other systems' help, so predicting them
/// would not be a test). On a catalogue with many such systems (MACS1931: 4 of 10) the folds then have the
/// constraints the reconstruction had, less the group. With `kappa_on`, also the mean and
/// spread of the folds' convergence on that map ([`KappaSpread`]; the map of the
/// reconstruction from all the systems, say). `progress` sees the fold number (1-based) and
/// every QADP report, and may cancel: the result then holds the folds that finished, with
/// status "Cancelled". Natively the folds run side by side, one thread each, as many as the
/// memory allows; `progress` is called on this thread, the folds' reports interleaved.
pub fn cross_validate(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    folds: usize,
    kappa_on: Option<MapGeometry>,
    progress: &mut dyn FnMut(usize, &ConvergenceRecord) -> Control,
) -> Result<CrossValidation, ReconstructError> {
    let groups = fold_groups(inputs, config, folds)?;
    let mut always_fitted = fitted_system_ids(inputs, config)?;
    always_fitted.retain(|id| !groups.iter().flatten().any(|g| g == id));
    let threads = super::side_by_side(inputs, config, groups.len())?;
    let jobs: Vec<(usize, &Vec<String>)> = (1..).zip(&groups).collect();
    let outcomes = crate::threads::map_reporting(
        &jobs,
        threads,
        |&(fold, group), report| {
            run_fold(inputs, config, fold, group, kappa_on, &mut |record| {
                Control::from(report(record.clone()))
            })
        },
        &mut |k, record| progress(k + 1, &record).into(),
    );
    let mut spread = kappa_on.map(SpreadSum::new);
    let mut runs = Vec::new();
    let mut systems = Vec::new();
    let mut fitted = Vec::new();
    let mut status = "Completed";
    for outcome in outcomes {
        let Some(fold) = outcome.transpose()?.flatten() else {
            // Cancelled, or not started after a cancel.
            status = "Cancelled";
            continue;
        };
        fitted.extend(fold.fitted_offsets);
        if let (Some(sum), Some(kappa)) = (&mut spread, &fold.kappa) {
            sum.add(kappa);
        }
        systems.extend(fold.predicted.into_iter().map(|report| PredictedSystem {
            fold: fold.run.fold,
            report,
        }));
        runs.push(fold.run);
    }
    let offsets = image_offsets_arcsec(systems.iter().map(|s| &s.report));
    let holdout_images = systems.iter().map(|s| s.report.observed.len()).sum();
    Ok(CrossValidation {
        totals: CrossvalTotals {
            folds,
            status: status.to_string(),
            holdout_images,
            holdout_images_unmatched: holdout_images - offsets.len(),
            holdout_image_plane_rms_arcsec: rms_arcsec(&offsets),
            holdout_image_offset_median_arcsec: median_arcsec(offsets),
            fit_image_offset_median_arcsec: median_arcsec(fitted),
        },
        runs,
        always_fitted,
        systems,
        kappa: spread.and_then(SpreadSum::finish),
    })
}

/// What one fold of [`cross_validate`] gives.
struct FoldOutcome {
    run: FoldRun,
    /// The held-out group's systems, predicted.
    predicted: Vec<SourceReport>,
    /// The fold's own fitted image offsets (arcsec).
    fitted_offsets: Vec<f64>,
    /// Its convergence on the map asked for.
    kappa: Option<Vec<f64>>,
}

/// Fold `fold` (1-based) of [`cross_validate`]: the lens reconstructed without `group`, and
/// the group predicted. `None` when `progress` cancelled it.
fn run_fold(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    fold: usize,
    group: &[String],
    kappa_on: Option<MapGeometry>,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Option<FoldOutcome>, ReconstructError> {
    let clock = crate::products::Clock::start();
    let holdout: Vec<String> = inputs.holdout.iter().chain(group).cloned().collect();
    let fold_inputs = Inputs {
        holdout: &holdout,
        ..*inputs
    };
    // A fold cancelled while an "auto" strength chose its candidate has no result at all.
    let r = match reconstruct_free_z(&fold_inputs, config, false, progress) {
        Err(ReconstructError::Cancelled) => return Ok(None),
        r => r?,
    };
    if r.status == SolveStatus::Cancelled {
        return Ok(None);
    }
    let predicted: Vec<SourceReport> = r
        .sources
        .iter()
        .filter(|s| s.held_out && group.contains(&s.id))
        .cloned()
        .collect();
    let fitted_offsets = image_offsets_arcsec(r.sources.iter().filter(|s| !s.held_out));
    let kappa = kappa_on.map(|g| fold_kappa(&r, g)).transpose()?;
    let summary = r.products.summary();
    let run = FoldRun {
        fold,
        held_out: group.to_vec(),
        status: r.status.name().to_string(),
        iterations: r.iterations,
        c: r.member_factors(),
        grid_mass_msun: r.grid_mass_msun(),
        einstein_radius_arcsec: summary.einstein_radius_arcsec,
        einstein_radius_z_source: r.products.curves.z_source,
        mass_within_arcsec: summary.mass_within_arcsec,
        fit_image_offset_median_arcsec: r.image_offset_median_arcsec(false),
        holdout_image_offset_median_arcsec: median_arcsec(image_offsets_arcsec(predicted.iter())),
        chosen: r.strength_choice.as_ref().map(|c| c.chosen_candidate()),
        crowded_maps: r
            .strength_choice
            .as_ref()
            .map_or_else(Vec::new, |c| c.crowded_maps.clone()),
        crowding: Some(Crowding::of_fitted(&r.sources)),
        elapsed_ms: clock.ms(),
    };
    Ok(Some(FoldOutcome {
        run,
        predicted,
        fitted_offsets,
        kappa,
    }))
}

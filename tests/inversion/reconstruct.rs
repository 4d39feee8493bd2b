//! The WSLAP+ reconstruction end to end: a synthetic lens with known truth, the two real
//! clusters of ../shared/data, hold-out predictions and bad inputs.

use crate::common;

use glam::DVec2;
use wslap::source_position;
use wslap::Control;
use wslap::ImageCatalog;
use wslap::{reconstruct, Inputs, LayerSource, ReconstructConfig};
use wslap::{ArcCatalog, ArcSystem};
use wslap::{ConstraintMode, ConstraintSource, Layer};
use wslap::{Cosmology, LensPlane};
use wslap::{Lens, MassComponent, Nfw, TruncatedNfw};

/// Median deflection error (arcsec, at D_ls/D_s = 1) at the observed images.
/// A constant deflection is absorbed by the betas, so it is removed before comparing.
const TRUE_LAYER_DEFLECTION_ERROR_ARCSEC: f64 = 1.0;
/// Every system's back-projected arc pixels gather within this rms of its beta (the sources
/// have a radius of 0.4 arcsec).
const SOURCE_SCATTER_ARCSEC: f64 = 1.0;
/// Observed images are predicted within this rms.
const IMAGE_PLANE_RMS_ARCSEC: f64 = 1.5;

struct Truth {
    plane: LensPlane,
    halo: Nfw,
    galaxies: Vec<TruncatedNfw>,
}

impl Truth {
    fn new() -> Self {
        let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
        // A smooth halo and 30 members holding about a third of the mass inside the arcs, as in
        // the paper's simulation (galaxies ~ 1/4 of the total).
        let halo = Nfw::new(DVec2::new(1.5, -1.0), 9e14, 5.0, &plane).unwrap();
        // Members on a fixed pattern (a spiral), masses from 3e11 to 6e12 Msun.
        let galaxies = (0..30)
            .map(|k| {
                let t = k as f64;
                let r = 4.0 + 1.4 * t;
                let phi = 2.4 * t;
                let m = 6e12 * 0.9f64.powi(k);
                let p = DVec2::new(r * phi.cos(), r * phi.sin());
                TruncatedNfw::new(p, m, 10.0, 3.0 + 10.0 * (m / 2e12).cbrt(), &plane).unwrap()
            })
            .collect();
        Self {
            plane,
            halo,
            galaxies,
        }
    }

    fn lens(&self) -> Lens {
        let mut c: Vec<Box<dyn MassComponent>> = vec![Box::new(self.halo)];
        c.extend(
            self.galaxies
                .iter()
                .map(|g| Box::new(g.clone()) as Box<dyn MassComponent>),
        );
        Lens::new(c)
    }

    fn galaxy_layer(&self) -> Layer {
        let c = self
            .galaxies
            .iter()
            .map(|g| Box::new(g.clone()) as Box<dyn MassComponent>)
            .collect();
        Layer::from_components("true galaxies", c)
    }

    /// Point images of sources on a fixed pattern, at redshifts 1.2 to 4, found by solving the
    /// lens equation forward; systems with fewer than 2 images are dropped.
    fn catalog(&self) -> ImageCatalog {
        let sources = (0..16).map(|k| {
            let t = k as f64;
            let z = 1.2 + 2.8 * ((t * 0.618_034) % 1.0);
            let beta = DVec2::new(4.0 * (1.7 * t).cos(), 4.0 * (1.3 * t + 0.5).sin())
                * (0.3 + 0.7 * ((t * 0.37) % 1.0));
            (z, beta)
        });
        common::point_image_catalog(&self.lens(), &self.plane, sources)
    }

    /// Lensed arcs of small circular sources (radius `SOURCE_RADIUS_ARCSEC`) centred on the
    /// point sources of [`Self::catalog`]: every pixel of a 0.25 arcsec lattice around each
    /// image whose ray lands inside the source, grouped by image.
    fn arcs(&self, catalog: &ImageCatalog) -> ArcCatalog {
        const SOURCE_RADIUS_ARCSEC: f64 = 0.4;
        const PIXEL_ARCSEC: f64 = 0.25;
        const HALF_BOX: i32 = 16;
        let lens = self.lens();
        let systems = catalog
            .systems
            .iter()
            .map(|s| {
                let f = self.plane.distance_ratio(s.z.unwrap()).unwrap();
                let beta = source_position(&lens, f, s.images[0].position);
                let images = s
                    .images
                    .iter()
                    .map(|img| {
                        let mut pixels = Vec::new();
                        for j in -HALF_BOX..=HALF_BOX {
                            for i in -HALF_BOX..=HALF_BOX {
                                let p =
                                    img.position + DVec2::new(i as f64, j as f64) * PIXEL_ARCSEC;
                                if source_position(&lens, f, p).distance(beta)
                                    < SOURCE_RADIUS_ARCSEC
                                {
                                    pixels.push(p);
                                }
                            }
                        }
                        if pixels.is_empty() {
                            pixels.push(img.position);
                        }
                        pixels
                    })
                    .collect();
                ArcSystem {
                    id: s.id.clone(),
                    z: s.z,
                    images,
                    image_ids: Vec::new(),
                    line: 0,
                }
            })
            .collect();
        ArcCatalog {
            source_name: "synthetic arcs".into(),
            systems,
        }
    }
}

fn quiet(_: &wslap::ConvergenceRecord) -> Control {
    Control::Continue
}

/// Reconstructs the synthetic lens from its arcs (16 x 16 cells, 8000 iterations) with the
/// given layers; returns the result and the median deflection error at the observed images.
fn reconstruct_synthetic(
    truth: &Truth,
    catalog: &ImageCatalog,
    layers: &[Layer],
) -> (wslap::Reconstruction, f64) {
    // The paper's method (QADP stopped early on the source-plane chi^2).
    let mut config = ReconstructConfig::paper();
    config.constraints.mode = ConstraintMode::Arcs;
    let arcs = truth.arcs(catalog);
    config.grid.cells = 16;
    config.solver.iterations = 8000;
    config.products.pixels = 64;
    let inputs = Inputs {
        images: ConstraintSource::Arcs(&arcs),
        layers: LayerSource::Given(layers),
        plane: truth.plane,
        reference: None,
        holdout: &[],
        catalog: Some(catalog),
        shear: None,
    };
    let r = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let true_lens = truth.lens();
    // A constant deflection is unobservable (every beta absorbs it), so compare after removing
    // the mean difference over the images.
    let diffs: Vec<DVec2> = catalog
        .systems
        .iter()
        .flat_map(|s| s.images.iter())
        .map(|i| true_lens.deflection(i.position) - r.lens.deflection(i.position))
        .collect();
    let mean = diffs.iter().copied().sum::<DVec2>() / diffs.len() as f64;
    let mut errors: Vec<f64> = diffs.iter().map(|d| (*d - mean).length()).collect();
    errors.sort_by(f64::total_cmp);
    let median = errors[errors.len() / 2];
    (r, median)
}

/// The issue asks for C within 10% of 1 here. It is not met, and this test does not claim it:
/// these data do not pin down how the mass splits between the grid and the galaxy layer.
/// Measured: C = 3.9 with 16 x 16 cells from the default start. With 12 x 12 cells (small
/// enough for the exact solver), C went from 4.3 to 0.58 as the start cell mass went from 1e9
/// to 1e12 Msun while the objective stayed within 3e-5 (relative) of the exact optimum, whose
/// C is 0.39. Minimising the objective with many more systems does not pin C either
/// (`solver.method = "accelerated_gradient"`, point images of this lens's sources, measured
/// once): 55 systems (174 images), 20000 iterations: C = 0.49, 0.58, 0.77 on 8, 12, 16 cells
/// (QADP at the same count: 3.3 - 3.7); 94 systems (292 images), 30000 iterations: C = 0.68,
/// 0.63, 0.81 on 12, 16, 20 cells, median deflection errors 0.27, 0.16, 0.13 arcsec. What the
/// Gaussian cells cannot represent of the halo is traded against the layer. And the data hardly
/// see the layer apart from the grid: with these arcs (6630 rows for 285 unknowns) the grid and
/// the source positions reproduce all but 2.2e-5 of its deflection at the arc pixels
/// (`LinearSystem::layer_independence`, measured once; the run warns of it). The layer's
/// normalisation is checked by `a_layer_holding_the_whole_lens_comes_back_at_c_one` instead.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn synthetic_lens_with_the_true_galaxy_layer() {
    let truth = Truth::new();
    let catalog = truth.catalog();
    let n_images: usize = catalog.systems.iter().map(|s| s.images.len()).sum();
    assert!(
        catalog.systems.len() >= 8 && n_images >= 24,
        "{} systems, {n_images} images",
        catalog.systems.len()
    );
    let (r, median) = reconstruct_synthetic(&truth, &catalog, &[truth.galaxy_layer()]);
    let c = r.layer_factors()[0];
    let scatter: Vec<f64> = r.sources.iter().map(|s| s.scatter_arcsec).collect();
    let rms = r.image_plane_rms_arcsec(false).unwrap();
    println!(
        "C = {c}, median deflection error {median} arcsec, scatter {scatter:?}, image rms {rms}"
    );
    assert!(c.is_finite() && c > 0.0, "C = {c}");
    assert!(
        median <= TRUE_LAYER_DEFLECTION_ERROR_ARCSEC,
        "median deflection error {median} arcsec"
    );
    assert!(
        scatter.iter().all(|&s| s <= SOURCE_SCATTER_ARCSEC),
        "source-plane scatter {scatter:?}"
    );
    assert!(
        rms <= IMAGE_PLANE_RMS_ARCSEC,
        "image-plane rms {rms} arcsec"
    );
    // Each observed image reports the model's magnification at its position (exact lens). Where
    // the predicted image is close (< 0.35 arcsec) it has the same parity, and away from the
    // critical curves (|mu| < 5) about the same magnification (found on the interpolated maps,
    // a little way off). Measured: 13 such images, within 11%.
    let mut compared = 0;
    for src in &r.sources {
        for o in &src.observed {
            let mu = o
                .magnification
                .expect("magnification at the observed image");
            let Some(offset) = o.offset_arcsec.filter(|&d| d < 0.35) else {
                continue;
            };
            let pred = src
                .predicted
                .iter()
                .find(|p| Some(p.position_arcsec) == o.predicted_arcsec)
                .unwrap()
                .magnification;
            assert_eq!(
                mu.signum(),
                pred.signum(),
                "{}: mu {mu}, predicted {pred}",
                o.id
            );
            if mu.abs() < 5.0 {
                compared += 1;
                assert!(
                    (mu - pred).abs() <= 0.15 * pred.abs() + 0.05,
                    "{}: mu {mu} at the observed image, {pred} at the predicted one {offset} arcsec away",
                    o.id
                );
            }
        }
    }
    assert!(compared >= 5, "{compared} images compared");
}

/// Point images on a grid with more unknowns than constraint rows: the run warns that the data
/// cannot fix the map, nor C, and nothing of the layer's deflection is its own (the other
/// columns span every row). The same systems as small arcs give more rows than unknowns and
/// no such warning, and a share of the layer's deflection that the grid cannot reproduce.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_system_with_fewer_rows_than_unknowns_is_flagged() {
    let truth = Truth::new();
    let catalog = truth.catalog();
    let arcs = truth.arcs(&catalog);
    let layers = [truth.galaxy_layer()];
    let mut config = ReconstructConfig::default();
    config.grid.cells = 16;
    config.solver.iterations = 100;
    config.products.pixels = 32;
    let run = |config: &ReconstructConfig, images| {
        let inputs = Inputs {
            images,
            layers: LayerSource::Given(&layers),
            plane: truth.plane,
            reference: None,
            holdout: &[],
            catalog: Some(&catalog),
            shear: None,
        };
        reconstruct(&inputs, config, &mut quiet).unwrap()
    };
    let flagged = |r: &wslap::Reconstruction| {
        r.warnings
            .iter()
            .any(|w| w.contains("constraint rows") && w.contains("C are not measured"))
    };
    config.constraints.mode = ConstraintMode::Point;
    let points = run(&config, ConstraintSource::Catalog(&catalog));
    assert!(points.system.n_rows < points.system.n_columns());
    assert!(flagged(&points), "{:?}", points.warnings);
    // The rows it counts are the images' two each and one per prior (C's, the shear's).
    let images = 2 * catalog.images().count();
    let priors = points
        .system
        .layers
        .iter()
        .filter(|l| l.prior_sigma.is_some())
        .count();
    assert!(priors > 0, "the default holds an unmeasured C with a prior");
    let counted = format!(
        "{} constraint rows ({images} from the images or arc pixels, two each, {priors} from \
         the priors",
        images + priors
    );
    assert_eq!(points.system.n_rows, images + priors);
    assert!(
        points.warnings.iter().any(|w| w.starts_with(&counted)),
        "{counted}: {:?}",
        points.warnings
    );
    // About the ridge of the computation (1e-10): none.
    let share = |r: &wslap::Reconstruction| r.system.layer_independence()[0].unwrap();
    assert!(share(&points) < 1e-8, "{}", share(&points));
    config.constraints.mode = ConstraintMode::Arcs;
    let pixels = run(&config, ConstraintSource::Arcs(&arcs));
    assert!(pixels.system.n_rows >= pixels.system.n_columns());
    assert!(!flagged(&pixels), "{:?}", pixels.warnings);
    assert!(
        share(&pixels) > 1e-6 && share(&pixels) <= 1.0,
        "{}",
        share(&pixels)
    );
}

/// `system.threads` holds for the whole run: every parallel section (rows, normal equations,
/// QADP passes, maps, image search) takes its thread count from `wslap::available_threads()`
/// on the run's thread, which is also where the progress callback runs.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn system_threads_limits_every_parallel_section_of_the_run() {
    let truth = Truth::new();
    let catalog = truth.catalog();
    let all = wslap::available_threads();
    for threads in [1, 3] {
        let mut config = ReconstructConfig::default();
        config.grid.cells = 8;
        config.solver.iterations = 20;
        config.solver.report_every = 5;
        config.products.pixels = 32;
        config.system.threads = threads;
        let inputs = Inputs {
            images: ConstraintSource::Catalog(&catalog),
            layers: LayerSource::None,
            plane: truth.plane,
            reference: None,
            holdout: &[],
            catalog: Some(&catalog),
            shear: None,
        };
        let mut seen = Vec::new();
        reconstruct(&inputs, &config, &mut |_| {
            seen.push(wslap::available_threads());
            Control::Continue
        })
        .unwrap();
        assert!(
            !seen.is_empty() && seen.iter().all(|&t| t == threads),
            "system.threads = {threads}: the run's sections saw {seen:?}"
        );
    }
    assert_eq!(
        wslap::available_threads(),
        all,
        "the limit ends with the run"
    );
}

/// When the layer is the whole true lens (halo and galaxies), nothing is left for the grid to
/// trade against, and C must come back at 1: this checks the layer column's normalisation
/// (`a_l` at C = 1 is the catalogue mass) end to end. Measured: C = 0.984, median deflection
/// error 0.055 arcsec.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_layer_holding_the_whole_lens_comes_back_at_c_one() {
    let truth = Truth::new();
    let catalog = truth.catalog();
    let whole = Layer::from_components("true lens", truth.lens().components);
    let (r, median) = reconstruct_synthetic(&truth, &catalog, &[whole]);
    let c = r.layer_factors()[0];
    println!("C = {c}, median deflection error {median} arcsec");
    assert!((c - 1.0).abs() <= 0.1, "C = {c}");
    assert!(median <= 0.2, "median deflection error {median} arcsec");
}

/// `solver.method = "accelerated_gradient"` minimises the same objective as QADP much further in
/// the same number of iterations (here 400 on the synthetic lens's point images): a lower
/// chi2, and more mass in the grid (towards the over-fitting "point-source solution").
/// Measured: chi2 0.38 against 205, grid mass 1.2e14 against 2.8e12 Msun.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_accelerated_gradient_goes_further_than_qadp() {
    let truth = Truth::new();
    let catalog = truth.catalog();
    let layers = [truth.galaxy_layer()];
    let config: ReconstructConfig = ReconstructConfig::from_json_str(
        r#"{"grid": {"cells": 12}, "constraints": {"mode": "point"},
            "solver": {"iterations": 400, "method": "accelerated_gradient"},
            "objective": {"regulariser": "none", "strength": 0, "image_plane_iterations": 0},
            "members": {"c_prior_sigma_unmeasured": null},
            "products": {"pixels": 32}}"#,
        "config.json",
    )
    .unwrap();
    let inputs = Inputs {
        images: ConstraintSource::Catalog(&catalog),
        layers: LayerSource::Given(&layers),
        plane: truth.plane,
        reference: None,
        holdout: &[],
        catalog: Some(&catalog),
        shear: None,
    };
    let chi2 = |r: &wslap::Reconstruction| {
        2.0 * wslap::quadratic_objective(&r.system.a, &r.system.b, &r.x) + r.system.theta_w_theta
    };
    let fast = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let mut qadp_config = config.clone();
    qadp_config.solver.method = wslap::SolverMethod::Qadp;
    let qadp = reconstruct(&inputs, &qadp_config, &mut quiet).unwrap();
    println!(
        "chi2 {} vs QADP {}; grid mass {:e} vs {:e}",
        chi2(&fast),
        chi2(&qadp),
        fast.grid_mass_msun(),
        qadp.grid_mass_msun()
    );
    assert_eq!(fast.iterations, 400);
    assert_eq!(fast.convergence.last().unwrap().iteration, 400);
    assert!(chi2(&fast) < 0.5 * chi2(&qadp));
    assert!(fast.grid_mass_msun() > qadp.grid_mass_msun());
}

/// `solver.keep_iterates` keeps solutions on the way, without changing the result: at
/// increasing iteration counts of the whole run, the last one the solution, within the bound.
/// The passes of the image-plane weights follow one another in one list.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_reconstruction_keeps_its_iterates_when_asked() {
    let truth = Truth::new();
    let catalog = truth.catalog();
    let layers = [truth.galaxy_layer()];
    let inputs = Inputs {
        images: ConstraintSource::Catalog(&catalog),
        layers: LayerSource::Given(&layers),
        plane: truth.plane,
        reference: None,
        holdout: &[],
        catalog: Some(&catalog),
        shear: None,
    };
    let mut config = ReconstructConfig::paper();
    config.grid.cells = 12;
    config.constraints.mode = ConstraintMode::Point;
    config.solver.iterations = 400;
    config.products.pixels = 32;
    let plain = reconstruct(&inputs, &config, &mut quiet).unwrap();
    assert!(plain.iterates.is_empty(), "none unless asked for");
    let keep = 40;
    let check = |r: &wslap::Reconstruction, what: &str| {
        let kept = &r.iterates;
        let counts: Vec<usize> = kept.iter().map(|i| i.iteration).collect();
        assert!(kept.len() >= 2 && kept.len() <= keep, "{what}: {counts:?}");
        assert!(counts.windows(2).all(|w| w[0] < w[1]), "{what}: {counts:?}");
        assert_eq!(counts.last(), Some(&r.iterations), "{what}");
        assert_eq!(kept.last().unwrap().x, r.x, "{what}");
        let bytes: usize = kept.iter().map(|i| i.x.len() * 8).sum();
        assert!(
            bytes <= keep * r.system.n_columns() * 8,
            "{what}: {bytes} bytes"
        );
    };
    config.solver.keep_iterates = keep;
    let qadp = reconstruct(&inputs, &config, &mut quiet).unwrap();
    check(&qadp, "QADP");
    assert_eq!(qadp.x, plain.x, "keeping iterates changes nothing");
    assert_eq!(qadp.iterates[0].iteration, 0);
    assert_ne!(qadp.iterates[keep / 2].x, qadp.x);

    // The default objective: the exact solver, then two passes of the image-plane weights.
    let mut exact = ReconstructConfig::default();
    exact.grid.cells = 12;
    exact.constraints.mode = ConstraintMode::Point;
    exact.objective.strength = wslap::Strength::Value(0.1);
    exact.products.pixels = 32;
    exact.solver.keep_iterates = keep;
    let r = reconstruct(&inputs, &exact, &mut quiet).unwrap();
    check(&r, "exact with image-plane passes");
}

/// The images of `c_smooth` (tests/data/fidelity: lenstronomy's synthetic cluster of 25
/// systems without members, z_l = 0.32).
#[cfg(not(target_arch = "wasm32"))]
fn c_smooth() -> ImageCatalog {
    let text = include_str!("../data/fidelity/c_smooth/images.cat");
    wslap::parse_image_catalog(text, "c_smooth/images.cat", None)
        .unwrap()
        .0
}

/// The inputs of a reconstruction of `c_smooth`'s images alone.
#[cfg(not(target_arch = "wasm32"))]
fn c_smooth_inputs(catalog: &ImageCatalog) -> Inputs<'_> {
    Inputs {
        images: ConstraintSource::Catalog(catalog),
        layers: LayerSource::None,
        plane: LensPlane::new(Cosmology::default(), 0.32).unwrap(),
        reference: catalog.reference,
        holdout: &[],
        catalog: Some(catalog),
        shear: None,
    }
}

/// Per system of `free`: its catalogue redshift, the estimate `r` fitted it at and the
/// estimate's interval, which holds it.
#[cfg(not(target_arch = "wasm32"))]
fn estimates_against_truth(
    catalog: &ImageCatalog,
    r: &wslap::Reconstruction,
    free: &[String],
) -> Vec<(f64, f64, [f64; 2])> {
    free.iter()
        .map(|id| {
            let truth = catalog
                .systems
                .iter()
                .find(|s| &s.id == id)
                .unwrap()
                .z
                .unwrap();
            let s = r.sources.iter().find(|s| &s.id == id).unwrap();
            let (z, [lo, hi]) = (s.z_estimate.unwrap(), s.z_interval.unwrap());
            assert_eq!(s.z, z, "system {id} is fitted at its estimate");
            assert!(lo <= z && z <= hi, "system {id}: {z} outside {lo} - {hi}");
            println!("system {id}: z {truth}, estimate {z:.3} ({lo:.3} - {hi:.3})");
            (truth, z, [lo, hi])
        })
        .collect()
}

/// Redshifts blanked on a synthetic cluster made with lenstronomy (tests/data/fidelity,
/// `c_smooth`: 25 systems, no members): every third system is estimated (`free_z_systems`)
/// and compared with its true redshift. The issue's bars: median |dz|/(1+z) below 0.1, the
/// true z inside the 68% interval for at least 60% of the systems; and the systems that kept
/// their redshift are fitted about as well as without the others (measured with the defaults:
/// 0.14" without, 0.13" with).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn blanked_redshifts_of_a_synthetic_cluster_are_found_again() {
    let catalog = c_smooth();
    let mut config = ReconstructConfig::default();
    // The strength "auto" picks for this cluster, fixed to keep the test short (the
    // estimates then start from the fallback image error instead of the measured one).
    config.objective.strength = wslap::Strength::Value(0.01);
    config.products.pixels = 160;
    let free: Vec<String> = catalog
        .systems
        .iter()
        .skip(2)
        .step_by(3)
        .map(|s| s.id.clone())
        .collect();
    assert_eq!(free.len(), 8);
    config.constraints.free_z_systems.clone_from(&free);
    let inputs = c_smooth_inputs(&catalog);
    let r = reconstruct(&inputs, &config, &mut quiet).unwrap();
    assert_eq!(
        r.system.constraints.systems.len(),
        25,
        "every system is fitted"
    );
    let mut dz = Vec::new();
    let mut inside = 0;
    for (truth, z, [lo, hi]) in estimates_against_truth(&catalog, &r, &free) {
        dz.push((z - truth).abs() / (1.0 + truth));
        inside += usize::from(lo <= truth && truth <= hi);
    }
    dz.sort_by(f64::total_cmp);
    let median = 0.5 * (dz[3] + dz[4]);
    assert!(median < 0.1, "median |dz|/(1+z) = {median}");
    assert!(
        inside >= 5,
        "the truth inside the interval for {inside} of 8"
    );
    let known = r.free_z.as_ref().unwrap();
    let (without, with) = (
        known.known_fit_median_without_arcsec.unwrap(),
        known.known_fit_median_with_arcsec.unwrap(),
    );
    assert!(
        with <= 1.5 * without + 0.05,
        "known systems: {without} -> {with}"
    );
    assert_eq!(known.sigma_arcsec, wslap::FALLBACK_SIGMA_ARCSEC);
    assert_estimates_settled(&catalog, &inputs, &config, &r);
    // The eight estimates are said on one line, each with its interval, as sources.json has
    // them; "open above" where the interval reaches the top of the range searched (8).
    let said: Vec<&String> = r
        .warnings
        .iter()
        .filter(|w| w.contains("redshift") && w.contains("estimated") && !w.contains("named"))
        .collect();
    let [line] = &said[..] else {
        panic!("{said:?}")
    };
    assert!(
        line.starts_with(
            "redshifts estimated for 8 systems on the lens of the systems with a known one"
        ),
        "{line}"
    );
    for id in &free {
        let s = r.sources.iter().find(|s| &s.id == id).unwrap();
        let [lo, hi] = s.z_interval.unwrap();
        assert_eq!(s.z_open_above, hi >= 8.0 - 0.005, "system {id}: {hi}");
        let open = if s.z_open_above { ", open above" } else { "" };
        let each = format!(
            "system {id} at z = {:.2} ({lo:.2} - {hi:.2}{open})",
            s.z_estimate.unwrap()
        );
        assert!(line.contains(&each), "{each} not in {line}");
    }
}

/// A system whose given redshift lies just behind the lens (here 0.34 behind `c_smooth`'s
/// z_l = 0.32, typed for its true 1 - 5.5) is fitted, and the run says it is suspicious with
/// D_ls/D_s as astropy gives it; the systems farther behind are not named.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn a_redshift_just_behind_the_lens_is_said() {
    let mut catalog = c_smooth();
    let id = catalog.systems[3].id.clone();
    catalog.systems[3].z = Some(0.34);
    let mut config = ReconstructConfig::default();
    config.objective.strength = wslap::Strength::Value(0.01);
    config.products.pixels = 64;
    let r = reconstruct(&c_smooth_inputs(&catalog), &config, &mut quiet).unwrap();
    // summary.json says where the frame's origin lies on the sky: the file's `#REFERENCE 3
    // 342.183200 -44.530900`.
    let json = serde_json::to_value(r.products.summary()).unwrap();
    assert_eq!(
        json["frame_reference"],
        serde_json::json!({"ra": 342.1832, "dec": -44.5309})
    );
    let said: Vec<&String> = r
        .warnings
        .iter()
        .filter(|w| w.contains("just behind the lens"))
        .collect();
    let [line] = &said[..] else {
        panic!("{:?}", r.warnings)
    };
    // astropy 8: FlatLambdaCDM(H0=70, Om0=0.3).angular_diameter_distance(0.32, z) /
    // angular_diameter_distance(z) for z = 0.34 and 2.
    // The lines that give the redshift, counted in the file's text (ids `<system>.<image>`).
    let text = include_str!("../data/fidelity/c_smooth/images.cat");
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            let first = l.split_whitespace().next().unwrap_or("");
            first.split('.').next() == Some(id.as_str()) && first.contains('.')
        })
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    assert!(lines.len() >= 2, "{lines:?}");
    let expected = format!(
        "system {id} (c_smooth/images.cat, lines {}): z_s = 0.34 lies just behind the lens \
         (z_lens = 0.32): D_ls/D_s = 0.054 against 0.76 for a source at z = 2",
        lines.join(", ")
    );
    assert!(line.starts_with(&expected), "{line}");
}

/// The estimates of `r` were made again on the map of every system until they settled: each
/// is where that map itself puts its system, within 0.01 (1 + z), unless every pass allowed
/// was used.
#[cfg(not(target_arch = "wasm32"))]
fn assert_estimates_settled(
    catalog: &ImageCatalog,
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    r: &wslap::Reconstruction,
) {
    let known = r.free_z.as_ref().unwrap();
    if known.passes == config.constraints.free_z_passes {
        return;
    }
    for (id, e) in &known.systems {
        let system = catalog.systems.iter().find(|s| &s.id == id).unwrap();
        let images: Vec<DVec2> = system.images.iter().map(|i| i.position).collect();
        let prior = config.constraints.free_z_prior.unwrap();
        let (sigma, stretch) = (known.sigma_arcsec, config.objective.max_stretch);
        let again =
            wslap::estimate_redshift(&r.lens, &inputs.plane, &images, prior, sigma, stretch)
                .unwrap();
        assert!(
            (again.z - e.z).abs() <= 0.01 * (1.0 + e.z) + 1e-9,
            "system {id}: fitted at {} but its map puts it at {}",
            e.z,
            again.z
        );
    }
}

/// `catalog`'s systems by the median distance of their images from the centre, innermost
/// first.
#[cfg(not(target_arch = "wasm32"))]
fn innermost_first(catalog: &ImageCatalog) -> Vec<&wslap::ImageSystem> {
    let radius = |s: &wslap::ImageSystem| {
        let mut r: Vec<f64> = s.images.iter().map(|i| i.position.length()).collect();
        r.sort_by(f64::total_cmp);
        let n = r.len();
        0.5 * (r[(n - 1) / 2] + r[n / 2])
    };
    let mut systems: Vec<&wslap::ImageSystem> = catalog.systems.iter().collect();
    systems.sort_by(|a, b| radius(a).total_cmp(&radius(b)));
    systems
}

/// The ids of `catalog`'s systems but its `keep` innermost, and the default settings (small
/// maps) with their redshifts to be estimated.
#[cfg(not(target_arch = "wasm32"))]
fn keeping_innermost(catalog: &ImageCatalog, keep: usize) -> (Vec<String>, ReconstructConfig) {
    let free: Vec<String> = innermost_first(catalog)[keep..]
        .iter()
        .map(|s| s.id.clone())
        .collect();
    let mut config = ReconstructConfig::default();
    config.products.pixels = 96;
    config.constraints.free_z_systems.clone_from(&free);
    (free, config)
}

/// `r`'s estimates were made again on the map of every system at least once, and its notes
/// say so; returns how many times.
#[cfg(not(target_arch = "wasm32"))]
fn assert_made_again(r: &wslap::Reconstruction) -> usize {
    let passes = r.free_z.as_ref().unwrap().passes;
    assert!(passes >= 1, "no estimate moved on the map of every system");
    assert!(
        r.warnings
            .iter()
            .any(|w| w.contains("on the map of every system")),
        "{:?}",
        r.warnings
    );
    passes
}

/// Few redshifts (`c_smooth` with only its five innermost systems' kept, as a JWST catalogue
/// might have): the first estimates, made on the lens of those five, are made again on the
/// map of every system and fitted again until they settle (`constraints.free_z_passes`).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn few_redshifts_are_made_consistent_with_the_map_of_every_system() {
    let catalog = c_smooth();
    let (free, mut config) = keeping_innermost(&catalog, 5);
    config.objective.strength = wslap::Strength::Value(0.01);
    let inputs = c_smooth_inputs(&catalog);
    let median_dz = |config: &ReconstructConfig| {
        let r = reconstruct(&inputs, config, &mut quiet).unwrap();
        let mut dz: Vec<f64> = estimates_against_truth(&catalog, &r, &free)
            .iter()
            .map(|(truth, z, _)| (z - truth).abs() / (1.0 + truth))
            .collect();
        dz.sort_by(f64::total_cmp);
        (dz[dz.len() / 2], r)
    };
    let mut first_only = config.clone();
    first_only.constraints.free_z_passes = 0;
    let (before, r0) = median_dz(&first_only);
    let (after, r) = median_dz(&config);
    assert_eq!(r0.free_z.as_ref().unwrap().passes, 0);
    let passes = assert_made_again(&r);
    // The map and the redshifts it is fitted at agree better: its images are reproduced
    // more closely (here 0.20 -> 0.16", the estimates' median error unchanged).
    let fit = |r: &wslap::Reconstruction| r.image_offset_median_arcsec(false).unwrap();
    println!(
        "median |dz|/(1+z): first {before:.3}, after {passes} passes {after:.3}; fitted {:.3} -> {:.3}",
        fit(&r0),
        fit(&r)
    );
    assert!(fit(&r) < fit(&r0), "{} -> {}", fit(&r0), fit(&r));
    assert!(after <= before + 0.02, "{before} -> {after}");
}

/// One redshift only (`c_smooth` with its innermost system's kept): an "auto" strength has no
/// folds to choose with, so no second round either, and the estimates are still made again
/// on the map of every system (they were once left as the one system's lens gave them).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn one_redshift_has_the_estimates_made_consistent_without_folds() {
    let catalog = c_smooth();
    let (free, config) = keeping_innermost(&catalog, 1);
    let inputs = c_smooth_inputs(&catalog);
    let r = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let choice = r.strength_choice.as_ref().expect("an auto strength");
    assert!(!choice.was_cross_validated(), "{}", choice.describe());
    assert_eq!(r.free_z.as_ref().unwrap().systems.len(), free.len());
    assert_made_again(&r);
    assert_estimates_settled(&catalog, &inputs, &config, &r);
}

/// Redshifts blanked where the lens of the others is least constrained: the outer third of
/// `c_smooth`'s systems (by the median distance of their images from the centre), as in real
/// catalogues, whose measured redshifts are mostly of the inner arcs. There the map is the
/// regulariser's, and one regulariser's map gave intervals that held the truth for 3 of these
/// 8 systems (`benches/free_z.py --pick outer`); averaged over the regularisers the "auto"
/// choice tried, at least 5 (the issue's 60%). The defaults on one grid: the least mass, whose
/// map lets the outskirts fall off where the smoothest keeps them level, is tried among them
/// (without the external shear the others fit); 6 of 8 hold the truth here (2026-12-07).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn outer_redshifts_are_estimated_over_the_regularisers_tried() {
    let catalog = c_smooth();
    let by_radius = innermost_first(&catalog);
    let free: Vec<String> = by_radius[by_radius.len() - 8..]
        .iter()
        .map(|s| s.id.clone())
        .collect();
    let mut config = ReconstructConfig::default();
    config.objective.auto_grid_scales = vec![1.0];
    config.products.pixels = 96;
    config.constraints.free_z_systems.clone_from(&free);
    let inputs = c_smooth_inputs(&catalog);
    let r = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let choice = r.strength_choice.as_ref().expect("an auto choice");
    assert_eq!(choice.best_of_other_regularisers().len(), 2);
    let inside = estimates_against_truth(&catalog, &r, &free)
        .iter()
        .filter(|(truth, _, [lo, hi])| lo <= truth && truth <= hi)
        .count();
    assert!(
        inside >= 5,
        "the truth inside the interval for {inside} of 8"
    );
}

/// An ensemble of one fitted system cannot redraw the systems: refused in words that name the
/// ensemble, not folds.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn an_ensemble_of_one_system_is_refused_in_its_own_words() {
    let catalog = c_smooth();
    let mut config = ReconstructConfig::default();
    config.objective.strength = wslap::Strength::Value(0.01);
    config.products.pixels = 64;
    let others: Vec<String> = catalog.systems[1..].iter().map(|s| s.id.clone()).collect();
    let inputs = Inputs {
        holdout: &others,
        ..c_smooth_inputs(&catalog)
    };
    let main = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let err = wslap::EnsemblePlan::new(&inputs, &config, &main, 3, 1).unwrap_err();
    assert_eq!(
        err.to_string(),
        "an ensemble redraws the fitted systems and needs at least 2 of them, and 1 is fitted \
         here: run without an ensemble"
    );
}

/// An ensemble carries an estimated redshift's interval into its members: each fits the
/// system at a redshift drawn from the estimate, inside the range the draw allows, and the
/// members' redshifts differ (c_smooth, two systems blanked, small maps to keep it short).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn ensemble_members_draw_estimated_redshifts() {
    let catalog = c_smooth();
    let mut config = ReconstructConfig::default();
    config.objective.strength = wslap::Strength::Value(0.01);
    config.products.pixels = 64;
    config.constraints.free_z_systems = vec!["9".to_string(), "24".to_string()];
    let inputs = c_smooth_inputs(&catalog);
    let main = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let ensemble =
        wslap::run_ensemble(&inputs, &config, &main, 3, 1, &mut |_, _| Control::Continue).unwrap();
    for id in ["9", "24"] {
        let s = main.sources.iter().find(|s| s.id == id).unwrap();
        let (z, [lo, hi]) = (s.z_estimate.unwrap(), s.z_interval.unwrap());
        let drawn: Vec<f64> = ensemble
            .members
            .iter()
            .map(|m| m.redshifts.iter().find(|(s, _)| s == id).unwrap().1)
            .collect();
        assert!(
            drawn.iter().all(|&d| d >= lo && d <= 2.0 * hi - z),
            "system {id}: {drawn:?} for {z} ({lo} - {hi})"
        );
        assert!(drawn.windows(2).any(|w| w[0] != w[1]), "{drawn:?}");
    }
}

/// An ensemble of a catalogue with member galaxies draws each member's mass-to-light law
/// (`members.mass_to_light_scatter_dex`, log-normal, from a stream of its own: the other draws
/// are those of an ensemble without it), a member fits with the law it drew, and the spread
/// then holds the images the members left out (d_few_systems of tests/data/fidelity, 15
/// systems and 60 members, small maps).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn ensemble_members_draw_the_member_law() {
    let dir = "tests/data/fidelity/d_few_systems";
    let read = |f: &str| std::fs::read_to_string(format!("{dir}/{f}")).unwrap();
    let (catalog, _) = wslap::parse_image_catalog(&read("images.cat"), "images.cat", None).unwrap();
    let (members, _) =
        wslap::parse_member_catalog(&read("members.cat"), "members.cat", catalog.reference)
            .unwrap();
    let inputs = Inputs {
        images: ConstraintSource::Catalog(&catalog),
        layers: LayerSource::Members(&members),
        plane: LensPlane::new(Cosmology::default(), 0.3).unwrap(),
        reference: catalog.reference,
        holdout: &[],
        catalog: Some(&catalog),
        shear: None,
    };
    let mut config = ReconstructConfig::default();
    config.objective.strength = wslap::Strength::Value(0.01);
    config.grid.cells = 16;
    config.products.pixels = 64;
    let main = reconstruct(&inputs, &config, &mut quiet).unwrap();

    let plan = wslap::EnsemblePlan::new(&inputs, &config, &main, 200, 3).unwrap();
    let logs: Vec<f64> = plan
        .draws
        .iter()
        .map(|d| d.member_mass_factor.log10())
        .collect();
    let mean = logs.iter().sum::<f64>() / logs.len() as f64;
    let sd = (logs.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / logs.len() as f64).sqrt();
    assert!(
        mean.abs() < 0.06 && (sd - 0.3).abs() < 0.05,
        "mean {mean}, sd {sd}"
    );
    let mut fixed = config.clone();
    fixed.members.mass_to_light_scatter_dex = 0.0;
    let unscattered = wslap::EnsemblePlan::new(&inputs, &fixed, &main, 200, 3).unwrap();
    for (a, b) in plan.draws.iter().zip(&unscattered.draws) {
        assert_eq!(b.member_mass_factor, 1.0);
        assert_eq!(
            (&a.fitted, a.grid_shift_arcsec),
            (&b.fitted, b.grid_shift_arcsec)
        );
    }

    // Member 1 with a law four times heavier and with the law as set: the members' own peaks
    // of kappa grow with it (their factor C stays at its prior: point images do not measure it).
    let mut heavy = plan.clone();
    heavy.draws[0].member_mass_factor = 4.0;
    let mut as_set = plan.clone();
    as_set.draws[0].member_mass_factor = 1.0;
    let run = |p: &wslap::EnsemblePlan| {
        p.run_member(&inputs, &config, 1, &mut |_| Control::Continue)
            .unwrap()
            .unwrap()
    };
    let (h, s) = (run(&heavy), run(&as_set));
    assert_eq!(h.record.member_mass_factor, 4.0);
    let brightest = members
        .members
        .iter()
        .min_by(|a, b| a.mag.total_cmp(&b.mag))
        .unwrap()
        .position;
    let (kh, ks) = (h.kappa.sample(brightest), s.kappa.sample(brightest));
    assert!(
        kh > 1.5 * ks,
        "kappa at the brightest member: {kh} (x4 law) against {ks}"
    );

    // Coverage at the images the members left out: this cluster's members are lighter than
    // the law (C true 0.86), which every member shared without the draw, so their predictions
    // missed the left-out images by more than they spread (calibration ratio above 1; 1.74
    // measured); with the law drawn the spread holds the misses (0.61 measured).
    let ratio = |c: &ReconstructConfig| {
        let e =
            wslap::run_ensemble(&inputs, c, &main, 12, 1, &mut |_, _| Control::Continue).unwrap();
        e.calibration.unwrap().ratio
    };
    let (without, with) = (ratio(&fixed), ratio(&config));
    assert!(
        without > 1.2 && with < 1.0,
        "without the draw {without}, with it {with}"
    );
}

#[cfg(not(target_arch = "wasm32"))]
pub(crate) mod real {
    //! The two real clusters of ../shared/data, end to end.
    use std::path::{Path, PathBuf};

    use super::*;
    use wslap::einstein_radius_for;
    use wslap::load_lenstool_model;
    use wslap::Reconstruction;
    use wslap::{Dataset, InputText, InputTexts};

    /// How far the free-form Einstein radius at z_s = 2 may lie from the published parametric
    /// model's (the issue asks for 25%), with a prior on the member factor C of width
    /// [`C_PRIOR_SIGMA`] around the M/L of 20: measured +16% (34.5 vs 29.8 arcsec, C = 1.06)
    /// with the quick settings at the default 8000 iterations, +15% (34.3 arcsec, C = 1.04)
    /// with all defaults (32 cells).
    const EINSTEIN_RADIUS_RTOL: f64 = 0.25;
    /// Width of the prior on C in that run.
    const C_PRIOR_SIGMA: f64 = 0.1;
    /// The same without the prior (C free, the default and the paper's method): 50 point images
    /// do not fix C, which runs to 3.9 and takes the Einstein radius to +33% (39.5 arcsec,
    /// measured). This bound catches regressions beyond that. Measured with `wslap
    /// reconstruct` on maps of 160 arcsec or more: 35-40 arcsec with the members (24 or 32
    /// cells, 3000-50000 iterations, other starts, bcg/brightest:3 layers, M/L 60; C = 2.0-3.9),
    /// 34 arcsec without them.
    const EINSTEIN_RADIUS_RTOL_FREE_C: f64 = 0.40;
    /// Share of the systems whose images lie on both sides of the tangential critical curve
    /// of their own redshift (measured 0.63 for AS1063, 0.9 for MACS1931, quick settings).
    pub const STRADDLING_SHARE: f64 = 0.5;

    pub fn data(path: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../shared/data")
            .join(path)
    }

    pub fn read(path: &Path) -> String {
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// A quick configuration: 24 x 24 cells, 3000 iterations, small maps.
    pub fn quick_config() -> ReconstructConfig {
        let mut config = ReconstructConfig::default();
        config.grid.cells = 24;
        config.solver.iterations = 3000;
        config.products.pixels = 160;
        config.products.size_arcsec = Some(160.0);
        config
    }

    /// `wslap reconstruct --images IMAGES --members MEMBERS --z-lens Z` with `config`: the
    /// files read as the CLI and the app read them (commented-out BCG rows fitted when
    /// `config.members.fit_commented_bcg` says so).
    pub fn run(
        images: &str,
        members: &str,
        z_lens: f64,
        config: &ReconstructConfig,
        holdout: &[String],
    ) -> (Reconstruction, ImageCatalog) {
        let (images_text, members_text) = (read(&data(images)), read(&data(members)));
        let files = InputTexts {
            images: Some(InputText {
                name: images,
                text: &images_text,
            }),
            members: Some(InputText {
                name: members,
                text: &members_text,
            }),
            ..InputTexts::default()
        };
        let mut config = config.clone();
        let mut dataset = Dataset::read(&files, config.constraints.pixel_arcsec).unwrap();
        let plane = LensPlane::new(Cosmology::default(), z_lens).unwrap();
        dataset.fit_commented_bcgs(&plane, &config);
        let inputs = dataset.inputs(plane, holdout, &mut config).unwrap();
        let r = reconstruct(&inputs, &config, &mut quiet).unwrap();
        (r, dataset.images.clone().unwrap())
    }

    /// Share of fitted systems with images on both sides of the tangential critical curve
    /// (lambda_t = 1 - f (kappa + |gamma|) changes sign among its images).
    pub fn straddling_share(r: &Reconstruction) -> f64 {
        let maps = &r.products.maps;
        let fitted: Vec<_> = r.sources.iter().filter(|s| !s.held_out).collect();
        let straddle = fitted
            .iter()
            .filter(|s| {
                let f = r.products.plane.distance_ratio(s.z).unwrap();
                let signs: Vec<bool> = s
                    .observed
                    .iter()
                    .map(|i| {
                        let k = maps.kappa.sample(i.position_arcsec);
                        let g = maps
                            .gamma1
                            .sample(i.position_arcsec)
                            .hypot(maps.gamma2.sample(i.position_arcsec));
                        1.0 - f * (k + g) > 0.0
                    })
                    .collect();
                signs.iter().any(|&b| b) && signs.iter().any(|&b| !b)
            })
            .count();
        straddle as f64 / fitted.len() as f64
    }

    /// The published CATS gold model's Einstein radius at z_s = 2 (dPIE halos + potfile,
    /// evaluated with our dPIE) on the quick settings' 160 arcsec field.
    fn as1063_published_einstein_radius() -> f64 {
        let published = load_lenstool_model(
            &data("AS1063/lenstool_cats/cats_gold_bestopt.par"),
            &[&data(
                "AS1063/lenstool_cats/cats_gold_ref_potential_w_clumpNE.cat",
            )],
        )
        .unwrap();
        einstein_radius_for(
            &published.lens,
            wslap::MapGeometry::centered(160.0, 200),
            &published.plane,
            2.0,
        )
        .unwrap()
    }

    /// AS1063 gold images and members with `config`: checks the Einstein radius at z_s = 2
    /// against the published model within `rtol`, and that most systems straddle the curve.
    /// Returns the run.
    fn check_as1063(config: &ReconstructConfig, rtol: f64) -> Reconstruction {
        let (r, _) = run(
            "AS1063/lenstool_cats/cats_gold_mul_gold.cat",
            "AS1063/lenstool_cats/cats_gold_ref_potential_w_clumpNE.cat",
            0.348,
            config,
            &[],
        );
        let theta_e_published = as1063_published_einstein_radius();
        let theta_e = r.products.curves.einstein_radius_arcsec;
        let share = straddling_share(&r);
        println!("AS1063: theta_E {theta_e} vs published {theta_e_published}, C = {:?}, straddling {share}", r.layer_factors());
        assert!(
            (theta_e - theta_e_published).abs() <= rtol * theta_e_published,
            "Einstein radius {theta_e} vs published model {theta_e_published}"
        );
        assert!(
            share >= STRADDLING_SHARE,
            "only {share} of the systems straddle the critical curve"
        );
        assert_eq!(r.system.constraints.systems.len(), 19);
        r
    }

    /// The paper's method leaves C to QADP's start on point images.
    #[test]
    fn as1063_gold_with_members_and_the_paper_method() {
        let quick = quick_config();
        let mut config = ReconstructConfig::paper();
        (config.grid, config.products) = (quick.grid, quick.products);
        config.solver.iterations = quick.solver.iterations;
        let r = check_as1063(&config, EINSTEIN_RADIUS_RTOL_FREE_C);
        assert!(r.layer_factors()[0] > 2.0, "C is left to the start");
    }

    /// The stated objective (the defaults, its strength fixed here at the one "auto" picks on
    /// this catalogue, 0.1, to keep the test short): C held at the luminosity scaling, the
    /// Einstein radius within 10% of the published CATS model's, and one main tangential
    /// curve.
    #[test]
    fn as1063_gold_with_members_and_the_stated_objective() {
        let mut config = quick_config();
        config.objective.strength = wslap::Strength::Value(0.1);
        let r = check_as1063(&config, 0.10);
        let c = r.layer_factors()[0];
        assert!((c - 1.0).abs() < 0.2, "C = {c}");
        let share = r.products.summary().tangential_main_area_share.unwrap();
        assert!(
            share > 0.8,
            "the main tangential curve holds {share} of the area"
        );
    }

    #[test]
    fn as1063_gold_with_a_prior_on_c_meets_the_published_einstein_radius() {
        let mut config = quick_config();
        config.members.c_prior_sigma = Some(C_PRIOR_SIGMA);
        // The default iteration count: QADP takes C to the prior's value slowly (C = 1.52,
        // straddling share 0.47 at 3000 iterations; 1.19 and 0.53 at 5000).
        config.solver.iterations = ReconstructConfig::default().solver.iterations;
        let r = check_as1063(&config, EINSTEIN_RADIUS_RTOL);
        let c = r.layer_factors()[0];
        assert!((c - 1.0).abs() < 0.2, "the prior holds C near 1: {c}");
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn a_commented_out_bcg_row_is_fitted_unless_the_settings_say_not() {
    use real::*;
    use wslap::{Dataset, InputText, InputTexts};
    let read_macs = || {
        let (i, m) = (
            read(&data("MACS1931/lenstool_cats/immul_ongoing.cat")),
            read(&data("MACS1931/lenstool_cats/m1931.cat")),
        );
        let files = InputTexts {
            images: Some(InputText {
                name: "immul_ongoing.cat",
                text: &i,
            }),
            members: Some(InputText {
                name: "m1931.cat",
                text: &m,
            }),
            ..InputTexts::default()
        };
        Dataset::read(&files, 0.2).unwrap()
    };
    let plane = LensPlane::new(Cosmology::default(), 0.352).unwrap();
    let mut config = ReconstructConfig::default();
    let mut data = read_macs();
    let (members, commented) = {
        let m = data.members.as_ref().unwrap();
        (m.members.len(), m.commented.len())
    };
    let rows = data.fit_commented_bcgs(&plane, &config);
    let row = wslap::CatalogRow {
        line: 10,
        id: "1009.0".to_string(),
    };
    // Line 10 only: the other commented rows are fainter than 1 L*.
    assert_eq!(rows, std::slice::from_ref(&row));
    let m = data.members.as_ref().unwrap();
    assert_eq!(
        (m.members.len(), m.commented.len()),
        (members + 1, commented - 1)
    );
    assert_eq!(m.members.last().unwrap().line, 10);
    assert!(m.commented.iter().all(|c| c.line != 10));
    assert_eq!(
        m.fitted_bcgs.as_ref().map(|b| &b.rows[..]),
        Some(std::slice::from_ref(&row))
    );
    // Not twice.
    assert!(data.fit_commented_bcgs(&plane, &config).is_empty());
    assert_eq!(data.members.as_ref().unwrap().members.len(), members + 1);
    // A `.par` that models a galaxy near the images on its own has chosen the cluster's BCG,
    // however faint: no commented row is taken for a missing one.
    let par = wslap::parse_par(
        "runmode\n\treference 3 292.95682 -26.575718\n\tend\n\
         potentiel G1\n\tprofil 81\n\tx_centre 3.0\n\ty_centre 3.0\n\tellipticite 0.1\n\
         \tangle_pos 0\n\tcore_radius_kpc 0.2\n\tcut_radius_kpc 50\n\tv_disp 150\n\
         \tmag 20.5\n\tz_lens 0.352\n\tend\n\
         cosmologie\n\tH0 70\n\tomegaM 0.3\n\tomegaX 0.7\n\tend\nfini\n",
        "one.par",
    )
    .unwrap();
    let mut data = read_macs();
    data.add_par_galaxies(&par, &par.lens_plane().unwrap(), &Default::default())
        .unwrap();
    let named = data.members.as_ref().unwrap();
    assert_eq!(named.ids(&named.par_galaxies), ["G1"]);
    assert!(data.fit_commented_bcgs(&plane, &config).is_empty());
    assert_eq!(data.members.as_ref().unwrap().members.len(), members + 1);
    assert_eq!(
        data.members.as_ref().unwrap().par_source.as_deref(),
        Some("one.par")
    );
    // A `.par` of cluster-scale halos only is remembered too (a missing BCG's warning then
    // does not ask for a `.par`), and leaves the commented BCG row to be looked for.
    let halo = wslap::parse_par(
        "runmode\n\treference 3 292.95682 -26.575718\n\tend\n\
         potentiel 1\n\tprofil 81\n\tx_centre 0.0\n\ty_centre 0.0\n\tellipticite 0.2\n\
         \tangle_pos 0\n\tcore_radius_kpc 50\n\tcut_radius_kpc 1000\n\tv_disp 1000\n\
         \tz_lens 0.352\n\tend\n\
         cosmologie\n\tH0 70\n\tomegaM 0.3\n\tomegaX 0.7\n\tend\nfini\n",
        "halo.par",
    )
    .unwrap();
    let mut data = read_macs();
    assert_eq!(
        data.add_par_galaxies(&halo, &halo.lens_plane().unwrap(), &Default::default())
            .unwrap(),
        [
            "halo.par: `potentiel 1` (line 4, core 50 kpc) has a core wider than a galaxy's (over \
          5 kpc): not fitted as a member; the grid models its mass"
        ]
    );
    let m = data.members.as_ref().unwrap();
    assert_eq!(
        (m.par_source.as_deref(), m.par_galaxies.len()),
        (Some("halo.par"), 0)
    );
    assert_eq!(data.fit_commented_bcgs(&plane, &config), [row]);
    // Off, the catalogue stays as written.
    config.members.fit_commented_bcg = false;
    let mut data = read_macs();
    assert!(data.fit_commented_bcgs(&plane, &config).is_empty());
    let m = data.members.as_ref().unwrap();
    assert_eq!((m.members.len(), m.commented.len()), (members, commented));
    assert_eq!(m.fitted_bcgs, None);
}

/// A cluster with two cores whose BCGs are both commented out (b_bimodal of
/// tests/data/fidelity, lenstronomy's truth: its members 1 and 2, 6 and 5 L*, on lines 4
/// and 5) gets both fitted; with one of them listed, the core has its BCG and nothing is.
#[test]
fn both_commented_bcg_rows_of_a_bimodal_cluster_are_fitted() {
    use wslap::{Dataset, InputText, InputTexts};
    let images = include_str!("../data/fidelity/b_bimodal/images.cat");
    let members = include_str!("../data/fidelity/b_bimodal/members.cat");
    let commented = |lines: &[usize]| {
        members
            .split('\n')
            .enumerate()
            .map(|(i, l)| {
                if lines.contains(&(i + 1)) {
                    format!("#{l}")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    let read = |members: &str| {
        let files = InputTexts {
            images: Some(InputText {
                name: "images.cat",
                text: images,
            }),
            members: Some(InputText {
                name: "members.cat",
                text: members,
            }),
            ..InputTexts::default()
        };
        Dataset::read(&files, 0.2).unwrap()
    };
    // The truth's lens redshift (tests/data/fidelity/b_bimodal/truth.json).
    let plane = LensPlane::new(Cosmology::default(), 0.38).unwrap();
    let config = ReconstructConfig::default();
    let text = commented(&[4, 5]);
    let mut data = read(&text);
    let n = data.members.as_ref().unwrap().members.len();
    let rows = data.fit_commented_bcgs(&plane, &config);
    let got: Vec<(usize, &str)> = rows.iter().map(|r| (r.line, r.id.as_str())).collect();
    assert_eq!(got, [(4, "1"), (5, "2")]);
    let m = data.members.as_ref().unwrap();
    assert_eq!(m.members.len(), n + 2);
    assert!(m.commented.iter().all(|c| c.line != 4 && c.line != 5));
    let note = &m.fitted_bcgs.as_ref().unwrap().note;
    assert!(
        note.contains(", but lines 4 and 5 comment out members 1 (")
            && note.contains("): they are fitted as BCGs, "),
        "{note}"
    );
    // Member 2 listed: a BCG near the images, so neither row is taken for a missing one.
    let mut data = read(&commented(&[4]));
    assert!(data.fit_commented_bcgs(&plane, &config).is_empty());
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn macs1931_runs_end_to_end_with_a_default_redshift() {
    use real::*;
    let mut config = quick_config();
    config.constraints.default_z = Some(2.0);
    let (r, catalog) = run(
        "MACS1931/lenstool_cats/immul_ongoing.cat",
        "MACS1931/lenstool_cats/m1931.cat",
        0.352,
        &config,
        &[],
    );
    let theta_e = r.products.curves.einstein_radius_arcsec;
    println!(
        "MACS1931: theta_E {theta_e}, C = {:?}, systems {}, straddling {}",
        r.layer_factors(),
        r.system.constraints.systems.len(),
        straddling_share(&r)
    );
    assert_eq!(
        r.system.constraints.systems.len(),
        catalog
            .systems
            .iter()
            .filter(|s| s.images.len() > 1)
            .count()
    );
    assert!(
        r.sources.iter().any(|s| s.z_assumed),
        "systems with unknown z take the default"
    );
    assert!(theta_e > 5.0 && theta_e < 60.0, "Einstein radius {theta_e}");
    // The catalogue comments its BCG out (line 10, mag 17.325, at its frame's origin, where no
    // other member is brighter than 1 L*): the run fits it and says so.
    assert!(!r.bcg.missing);
    let fitted = &r.bcg.fitted;
    assert_eq!(
        fitted
            .iter()
            .map(|f| (f.line, f.id.as_str()))
            .collect::<Vec<_>>(),
        [(10, "1009.0")]
    );
    assert_eq!(&r.verdict().bcg.fitted, fitted);
    let bcg = r
        .warnings
        .iter()
        .find(|w| w.contains("as bright as a brightest cluster galaxy"))
        .expect("a note on the BCG");
    assert!(
        bcg.contains(", but line 10 comments out member 1009.0 (")
            && bcg.contains(" mag 17.32, ")
            && bcg.contains(" L*): it is fitted as the BCG, "),
        "{bcg}"
    );
    // The curve passes between the images of most systems (measured 0.9).
    let share = straddling_share(&r);
    assert!(
        share >= STRADDLING_SHARE,
        "only {share} of the systems straddle the critical curve"
    );
}

//! Hold-out predictions and K-fold cross-validation (`wslap reconstruct --holdout`, `--folds`),
//! on the teaching example (four two-image systems behind one halo): quick, and every system
//! has a redshift.

use glam::DVec2;
use wslap::app::examples::teaching_image_catalog;
use wslap::Control;
use wslap::{
    cross_validate, fold_groups, reconstruct, ConvergenceRecord, Inputs, LayerSource,
    ReconstructConfig, ReconstructError,
};
use wslap::{parse_image_catalog, ImageCatalog};
use wslap::{ArcCatalog, ArcSystem};
use wslap::{ConstraintMode, ConstraintSource, Layer};
use wslap::{Cosmology, LensPlane};
use wslap::{Map, MapGeometry};
use wslap::{MassComponent, TruncatedNfw};

fn quiet(_: &ConvergenceRecord) -> Control {
    Control::Continue
}

fn catalog() -> ImageCatalog {
    let text = teaching_image_catalog().unwrap();
    parse_image_catalog(&text, "images.cat", None).unwrap().0
}

/// The teaching example's settings, made quick: 16 x 16 cells, 300 iterations, 64-pixel maps.
fn config() -> ReconstructConfig {
    let mut c = ReconstructConfig::default();
    c.grid.cells = 16;
    c.solver.iterations = 300;
    c.products.pixels = 64;
    c.products.size_arcsec = Some(60.0);
    c
}

fn plane() -> LensPlane {
    LensPlane::new(Cosmology::default(), 0.3).unwrap()
}

fn inputs<'a>(cat: &'a ImageCatalog, holdout: &'a [String]) -> Inputs<'a> {
    Inputs {
        images: ConstraintSource::Catalog(cat),
        layers: LayerSource::None,
        plane: plane(),
        reference: cat.reference,
        holdout,
        catalog: Some(cat),
        shear: None,
    }
}

fn ids(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// Arc pixels instead of a catalogue: each image a 3 x 3 square of 0.2 arcsec pixels centred on
/// the catalogue position.
fn arcs_from(cat: &ImageCatalog) -> ArcCatalog {
    let square = |c: DVec2| -> Vec<DVec2> {
        (-1..=1)
            .flat_map(|i| (-1..=1).map(move |j| c + 0.2 * DVec2::new(i as f64, j as f64)))
            .collect()
    };
    ArcCatalog {
        source_name: "arcs.json".into(),
        systems: cat
            .systems
            .iter()
            .map(|s| ArcSystem {
                id: s.id.clone(),
                z: s.z,
                images: s.images.iter().map(|i| square(i.position)).collect(),
                image_ids: Vec::new(),
                line: 0,
            })
            .collect(),
    }
}

/// With arc pixels and no catalogue, a held-out system is predicted from its pixels: one
/// observed image per arc at the mean of its pixels (here the catalogue position), named
/// `system.k`, each with its nearest predicted image. Before, `--holdout` with `--arcs`
/// reported nothing for the held-out systems.
#[test]
fn held_out_arc_systems_are_predicted_from_their_pixels() {
    let cat = catalog();
    let arcs = arcs_from(&cat);
    let holdout = ids(&["2"]);
    let mut config = config();
    config.constraints.mode = ConstraintMode::Arcs;
    let inputs = Inputs {
        images: ConstraintSource::Arcs(&arcs),
        layers: LayerSource::None,
        plane: plane(),
        reference: cat.reference,
        holdout: &holdout,
        catalog: None,
        shear: None,
    };
    let r = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let held: Vec<_> = r.sources.iter().filter(|s| s.held_out).collect();
    assert_eq!(held.len(), 1);
    let (report, truth) = (held[0], &cat.systems[1]);
    assert_eq!(report.id, "2");
    assert_eq!(report.z, truth.z.unwrap());
    assert_eq!(report.observed.len(), truth.images.len());
    for (o, image) in report.observed.iter().zip(&truth.images) {
        assert_eq!(o.id, image.id);
        assert!(o.position_arcsec.distance(image.position) < 1e-12);
        let nearest = report
            .predicted
            .iter()
            .map(|p| p.position_arcsec.distance(o.position_arcsec))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(o.offset_arcsec, Some(nearest));
    }
    assert!(r.image_offset_median_arcsec(true).is_some());
}

/// The folds deal the fitted systems out in catalogue order, leave the user's hold-out list
/// out of every group, and refuse fewer than 2 folds or more folds than systems (naming the
/// count).
#[test]
fn fold_groups_deal_the_fitted_systems_out_in_turn() {
    let cat = catalog();
    let none: Vec<String> = Vec::new();
    let groups = fold_groups(&inputs(&cat, &none), &config(), 2).unwrap();
    assert_eq!(groups, [ids(&["1", "3"]), ids(&["2", "4"])]);
    let groups = fold_groups(&inputs(&cat, &none), &config(), 4).unwrap();
    assert_eq!(groups, [ids(&["1"]), ids(&["2"]), ids(&["3"]), ids(&["4"])]);
    let user = ids(&["3"]);
    let groups = fold_groups(&inputs(&cat, &user), &config(), 3).unwrap();
    assert_eq!(groups, [ids(&["1"]), ids(&["2"]), ids(&["4"])]);
    for folds in [0, 1, 5] {
        let err = fold_groups(&inputs(&cat, &none), &config(), folds).unwrap_err();
        assert!(
            matches!(err, ReconstructError::Folds { systems: 4, .. }),
            "{err}"
        );
        let text = err.to_string();
        assert!(
            text.starts_with(&format!("folds = {folds}: "))
                && text.contains("use folds from 2 to 4 (systems with a redshift of their own"),
            "{text}"
        );
    }
    // With one system there is nothing to hold out in turn, whatever the folds: said so.
    let one = wslap::ImageCatalog {
        systems: cat.systems[..1].to_vec(),
        ..cat.clone()
    };
    let err = fold_groups(&inputs(&one, &none), &config(), 5).unwrap_err();
    assert_eq!(
        err.to_string(),
        "folds = 5: holding systems out needs at least 2 that can be, and there is 1 (systems \
         with a redshift of their own, the knots of one galaxy (2.1, 2.2) counted once; a \
         system whose redshift is estimated is never held out): run without folds"
    );
    // Two knots of one galaxy (systems 2.1 and 2.2, as images 2.1a and 2.2a name them) are
    // held out together: one predicts the other. So three sources, at most three folds.
    let mut knots = cat.clone();
    knots.systems[1].id = "2.1".into();
    knots.systems[2].id = "2.2".into();
    let groups = fold_groups(&inputs(&knots, &none), &config(), 2).unwrap();
    assert_eq!(groups, [ids(&["1", "4"]), ids(&["2.1", "2.2"])]);
    let groups = fold_groups(&inputs(&knots, &none), &config(), 3).unwrap();
    assert_eq!(groups, [ids(&["1"]), ids(&["2.1", "2.2"]), ids(&["4"])]);
    let err = fold_groups(&inputs(&knots, &none), &config(), 4).unwrap_err();
    assert!(
        matches!(err, ReconstructError::Folds { systems: 3, .. }),
        "{err}"
    );
}

/// Each fold is exactly `reconstruct` with that group held out: the same predicted images and
/// offsets. Every fitted system is predicted once, and the totals are the median and rms of
/// all the predicted systems' offsets.
#[test]
fn each_fold_is_a_hold_out_run_and_every_system_is_predicted_once() {
    let cat = catalog();
    let none: Vec<String> = Vec::new();
    let cv = cross_validate(&inputs(&cat, &none), &config(), 2, None, &mut |_, _| {
        Control::Continue
    })
    .unwrap();
    assert_eq!(cv.totals.status, "Completed");
    assert_eq!(cv.runs.len(), 2);
    let mut predicted: Vec<&str> = cv.systems.iter().map(|s| s.report.id.as_str()).collect();
    predicted.sort();
    assert_eq!(predicted, ["1", "2", "3", "4"]);
    for run in &cv.runs {
        let alone = reconstruct(&inputs(&cat, &run.held_out), &config(), &mut quiet).unwrap();
        let expected: Vec<_> = alone.sources.iter().filter(|s| s.held_out).collect();
        let got: Vec<_> = cv
            .systems
            .iter()
            .filter(|s| s.fold == run.fold)
            .map(|s| &s.report)
            .collect();
        assert_eq!(got, expected, "fold {}", run.fold);
        assert_eq!(run.c, alone.member_factors());
        assert_eq!(
            run.einstein_radius_arcsec,
            alone.products.summary().einstein_radius_arcsec
        );
        assert_eq!(run.einstein_radius_z_source, config().products.z_source);
        assert_eq!(
            run.mass_within_arcsec,
            alone.products.summary().mass_within_arcsec
        );
        assert_eq!(run.mass_within_arcsec.len(), 3);
        assert_eq!(
            run.fit_image_offset_median_arcsec,
            alone.image_offset_median_arcsec(false)
        );
        assert_eq!(
            run.holdout_image_offset_median_arcsec,
            alone.image_offset_median_arcsec(true)
        );
    }
    let mut offsets: Vec<f64> = cv
        .systems
        .iter()
        .flat_map(|s| s.report.observed.iter().filter_map(|o| o.offset_arcsec))
        .collect();
    assert_eq!(cv.totals.holdout_images, 8);
    assert_eq!(cv.totals.holdout_images_unmatched, 8 - offsets.len());
    offsets.sort_by(f64::total_cmp);
    let n = offsets.len();
    let median = 0.5 * (offsets[(n - 1) / 2] + offsets[n / 2]);
    let rms = (offsets.iter().map(|o| o * o).sum::<f64>() / n as f64).sqrt();
    assert_eq!(cv.totals.holdout_image_offset_median_arcsec, Some(median));
    assert!((cv.totals.holdout_image_plane_rms_arcsec.unwrap() - rms).abs() < 1e-12);
    // A lens fitted to two systems reproduces them more closely than it predicts the others.
    assert!(cv.totals.fit_image_offset_median_arcsec.unwrap() < median);
}

/// Two folds of the teaching example on `threads` threads, cancelled at the second fold's
/// first report; `seen` gets the fold of every report.
fn cancelled_in_fold_two(threads: usize, seen: &mut Vec<usize>) -> wslap::CrossValidation {
    let cat = catalog();
    let none: Vec<String> = Vec::new();
    wslap::with_thread_limit(threads, || {
        cross_validate(&inputs(&cat, &none), &config(), 2, None, &mut |fold, _| {
            seen.push(fold);
            if fold == 2 {
                Control::Cancel
            } else {
                Control::Continue
            }
        })
    })
    .unwrap()
}

/// One fold after another (one thread), cancelling in the second fold keeps the first fold's
/// result and says "Cancelled".
#[test]
fn cancel_keeps_the_folds_before_it() {
    let mut seen = Vec::new();
    let cv = cancelled_in_fold_two(1, &mut seen);
    assert_eq!(cv.totals.status, "Cancelled");
    assert_eq!(cv.runs.len(), 1);
    assert!(cv.systems.iter().all(|s| s.fold == 1));
    assert_eq!(cv.systems.len(), 2);
    assert!(seen.contains(&1) && seen.contains(&2));
}

/// Side by side (two threads), the folds give exactly what they give one after another, the
/// caller sees every fold's reports, and a cancel in one fold stops the other too (it keeps
/// only a fold that had already finished).
#[test]
fn folds_side_by_side_agree_with_one_after_another_and_cancel_together() {
    let cat = catalog();
    let none: Vec<String> = Vec::new();
    let run = |threads| {
        let mut seen = Vec::new();
        let cv = wslap::with_thread_limit(threads, || {
            cross_validate(&inputs(&cat, &none), &config(), 2, None, &mut |fold, _| {
                seen.push(fold);
                Control::Continue
            })
        })
        .unwrap();
        (cv, seen)
    };
    let (one, seen_one) = run(1);
    let (two, seen_two) = run(2);
    assert_eq!(two.totals.status, "Completed");
    assert_eq!(
        serde_json::to_value(&one.systems).unwrap(),
        serde_json::to_value(&two.systems).unwrap()
    );
    assert_eq!(
        one.totals.holdout_image_offset_median_arcsec,
        two.totals.holdout_image_offset_median_arcsec
    );
    assert_eq!(
        one.runs.iter().map(|r| r.c.clone()).collect::<Vec<_>>(),
        two.runs.iter().map(|r| r.c.clone()).collect::<Vec<_>>()
    );
    let count = |seen: &[usize], f| seen.iter().filter(|&&s| s == f).count();
    for fold in [1, 2] {
        assert_eq!(
            count(&seen_one, fold),
            count(&seen_two, fold),
            "fold {fold}"
        );
    }

    let cv = cancelled_in_fold_two(2, &mut Vec::new());
    assert_eq!(cv.totals.status, "Cancelled");
    assert!(cv
        .runs
        .iter()
        .all(|r| r.fold == 1 && r.status == "Completed"));
    assert!(cv.systems.iter().all(|s| s.fold == 1));
}

/// A system without a redshift is never held out. Without an estimate it is left out of every
/// fold; given one (`constraints.z_estimates`, as a reconstruction that estimated it gives
/// them) every fold fits it there: each fold is then exactly `reconstruct` with its group held
/// out and the estimate given.
#[test]
fn systems_at_an_estimated_redshift_are_fitted_in_every_fold_and_never_held_out() {
    let mut cat = catalog();
    let z3 = cat.systems[2].z.take().unwrap();
    assert_eq!(cat.systems[2].id, "3");
    let none: Vec<String> = Vec::new();
    let mut config = config();
    config.objective.strength = wslap::Strength::Value(0.1);
    let mut estimated = config.clone();
    estimated.constraints.z_estimates = vec![("3".to_string(), z3)];
    for c in [&config, &estimated] {
        let groups = fold_groups(&inputs(&cat, &none), c, 3).unwrap();
        assert_eq!(groups, [ids(&["1"]), ids(&["2"]), ids(&["4"])]);
    }
    let without = cross_validate(&inputs(&cat, &none), &config, 3, None, &mut |_, _| {
        Control::Continue
    })
    .unwrap();
    let with = cross_validate(&inputs(&cat, &none), &estimated, 3, None, &mut |_, _| {
        Control::Continue
    })
    .unwrap();
    for cv in [&without, &with] {
        let held: Vec<&str> = cv.systems.iter().map(|s| s.report.id.as_str()).collect();
        assert_eq!(held, ["1", "2", "4"]);
    }
    assert!(without.always_fitted.is_empty());
    assert_eq!(with.always_fitted, ids(&["3"]));
    for (k, id) in ["1", "2", "4"].iter().enumerate() {
        let holdout = ids(&[id]);
        let alone = reconstruct(&inputs(&cat, &holdout), &estimated, &mut quiet).unwrap();
        let fitted: Vec<&str> = alone
            .sources
            .iter()
            .filter(|s| !s.held_out)
            .map(|s| s.id.as_str())
            .collect();
        assert!(fitted.contains(&"3"), "{fitted:?}");
        let predicted = |r: &wslap::SourceReport| {
            r.observed
                .iter()
                .map(|o| o.offset_arcsec)
                .collect::<Vec<_>>()
        };
        let report = alone.sources.iter().find(|s| s.id == *id).unwrap();
        assert_eq!(
            predicted(&with.systems[k].report),
            predicted(report),
            "system {id}"
        );
        assert_ne!(
            predicted(&without.systems[k].report),
            predicted(report),
            "system {id}"
        );
    }
}

/// The folds' convergence on a given map: at every pixel the mean and the standard deviation
/// (over the K folds, divided by K) of the folds' kappa. Checked against each fold run on its
/// own (`reconstruct` with its group held out) and its lens evaluated at every pixel, cell by
/// cell and halo by halo; the library samples the grid's own map instead, so the two agree to
/// the interpolation of the Gaussian cells (measured: 7e-4 of the largest kappa; 2e-2 with
/// bilinear interpolation, hence the bicubic one). The
/// map is wider than the folds' own maps (60 arcsec), so its edge takes the direct path, and
/// a galaxy layer with a free C is in the lens.
#[test]
fn the_folds_kappa_maps_give_their_mean_and_spread() {
    let cat = catalog();
    let none: Vec<String> = Vec::new();
    let galaxy = |x: f64, y: f64| -> Box<dyn MassComponent> {
        Box::new(TruncatedNfw::new(DVec2::new(x, y), 5e11, 8.0, 10.0, &plane()).unwrap())
    };
    let layers = [Layer::from_components(
        "two galaxies",
        vec![galaxy(6.0, 4.0), galaxy(-9.0, -5.0)],
    )];
    let with_layer = |holdout| Inputs {
        layers: LayerSource::Given(&layers),
        ..inputs(&cat, holdout)
    };
    let geometry = MapGeometry::centered(70.0, 40);
    let cv = cross_validate(
        &with_layer(&none),
        &config(),
        2,
        Some(geometry),
        &mut |_, _| Control::Continue,
    )
    .unwrap();
    let spread = cv.kappa.as_ref().expect("kappa maps were asked for");
    assert_eq!(spread.mean.geometry, geometry);
    assert_eq!(spread.spread.geometry, geometry);
    let folds: Vec<Map> = fold_groups(&with_layer(&none), &config(), 2)
        .unwrap()
        .iter()
        .map(|group| {
            let r = reconstruct(&with_layer(group), &config(), &mut quiet).unwrap();
            assert!(r.layer_factors()[0] > 0.0);
            Map::from_fn(geometry, |p| r.lens.kappa(p))
        })
        .collect();
    let kmax = folds[0].min_max().1;
    let (mut worst, mut largest_spread) = (0.0f64, 0.0f64);
    for k in 0..geometry.pixels * geometry.pixels {
        let (a, b) = (folds[0].data[k], folds[1].data[k]);
        let (mean, std) = (0.5 * (a + b), 0.5 * (a - b).abs());
        worst = worst
            .max((spread.mean.data[k] - mean).abs())
            .max((spread.spread.data[k] - std).abs());
        largest_spread = largest_spread.max(std);
    }
    println!("worst difference {:.2e} of kappa max {kmax}", worst / kmax);
    assert!(worst <= 2e-3 * kmax, "{worst} against kappa max {kmax}");
    assert!(
        largest_spread > 0.01 * kmax,
        "the folds differ: {largest_spread}"
    );
    // Without a map asked for, none is made.
    let cv = cross_validate(&inputs(&cat, &none), &config(), 2, None, &mut |_, _| {
        Control::Continue
    })
    .unwrap();
    assert!(cv.kappa.is_none());
}

/// The "auto" choice inside a fold counts only the systems it can hold out: one at an
/// estimated redshift is fitted by every inner fold too. Here each fold of 3 fits two systems
/// with a redshift and the estimated one, so its choice has 2 folds (it asked for 3 of the 3
/// fitted systems before, one more than fold_groups could make, and the fold failed).
#[test]
fn an_auto_choice_inside_a_fold_counts_only_the_systems_it_can_hold_out() {
    let mut cat = catalog();
    let z3 = cat.systems[2].z.take().unwrap();
    let none: Vec<String> = Vec::new();
    let mut config = config();
    config.objective.strength = wslap::Strength::Auto(wslap::AutoWord::Auto);
    config.objective.candidates = vec![0.1];
    config.objective.auto_regularisers = vec![wslap::Regulariser::Gradient];
    config.objective.auto_grid_scales = vec![1.0];
    config.objective.folds = 4;
    config.constraints.z_estimates = vec![("3".to_string(), z3)];
    assert_eq!(
        wslap::strength_folds(&inputs(&cat, &none), &config).unwrap(),
        3
    );
    let holdout = ids(&["1"]);
    assert_eq!(
        wslap::strength_folds(&inputs(&cat, &holdout), &config).unwrap(),
        2
    );
    let cv = cross_validate(&inputs(&cat, &none), &config, 3, None, &mut |_, _| {
        Control::Continue
    })
    .unwrap();
    assert_eq!(cv.runs.len(), 3);
    assert_eq!(cv.always_fitted, ids(&["3"]));
}

/// A system whose redshift only its own prior fixes (a `.par`'s `z_m_limit` with flag 0,
/// the catalogue's z 0) is held out and predicted at that redshift, by `--holdout` and by every
/// fold, exactly as when the catalogue gives it. Before, its held-out images were dropped
/// without a word (a Lenstool set-up whose `.par` carries the redshifts, MACS J0308's: no
/// candidate of "auto" had a held-out offset). One with no redshift at all is said.
#[test]
fn a_system_whose_own_prior_fixes_its_redshift_is_held_out_and_predicted() {
    let cat = catalog();
    let mut unknown = catalog();
    let z3 = unknown.systems[2].z.take().unwrap();
    assert_eq!(unknown.systems[2].id, "3");
    let mut config = config();
    config.objective.strength = wslap::Strength::Value(0.1);
    let mut fixed = config.clone();
    fixed
        .constraints
        .z_priors
        .insert("3".to_string(), wslap::RedshiftPrior::Fixed(z3));
    let offsets = |r: &wslap::SourceReport| -> Vec<Option<f64>> {
        r.observed.iter().map(|o| o.offset_arcsec).collect()
    };
    let three = ids(&["3"]);
    let given = reconstruct(&inputs(&cat, &three), &config, &mut quiet).unwrap();
    let by_prior = reconstruct(&inputs(&unknown, &three), &fixed, &mut quiet).unwrap();
    let report = |r: &wslap::Reconstruction| r.sources.iter().find(|s| s.id == "3").cloned();
    let (a, b) = (report(&given).unwrap(), report(&by_prior).unwrap());
    assert!(b.held_out && !b.z_assumed && b.z == z3, "{b:?}");
    assert!(offsets(&b).iter().all(Option::is_some), "{b:?}");
    assert_eq!(offsets(&a), offsets(&b));
    assert!(!by_prior.warnings.iter().any(|w| w.contains("held out")));

    let none: Vec<String> = Vec::new();
    let cv = |cat: &ImageCatalog, c: &ReconstructConfig| {
        cross_validate(&inputs(cat, &none), c, 4, None, &mut |_, _| {
            Control::Continue
        })
        .unwrap()
    };
    let (given, by_prior) = (cv(&cat, &config), cv(&unknown, &fixed));
    let held: Vec<&str> = by_prior
        .systems
        .iter()
        .map(|s| s.report.id.as_str())
        .collect();
    assert_eq!(held, ["1", "2", "3", "4"]);
    for (a, b) in given.systems.iter().zip(&by_prior.systems) {
        assert_eq!(offsets(&a.report), offsets(&b.report), "{}", a.report.id);
    }

    // Neither the catalogue nor a prior nor default_z: left out, and said.
    config.constraints.free_z_prior = None;
    let alone = reconstruct(&inputs(&unknown, &three), &config, &mut quiet).unwrap();
    assert!(report(&alone).is_none());
    assert!(
        alone.warnings.contains(
            &"images.cat: system 3 is held out but has no redshift to predict its images at \
              (none in the catalogue, no prior of its own fixes one, no default_z): it is left \
              out and not predicted"
                .to_string()
        ),
        "{:?}",
        alone.warnings
    );
}

/// An ensemble's bootstrap draws sources, as the folds hold them out: the knots of one galaxy
/// (systems 2.1 and 2.2) are fitted together or left out together, never one without the
/// other.
#[test]
fn an_ensemble_draws_the_knots_of_one_galaxy_together() {
    let mut knots = catalog();
    knots.systems[1].id = "2.1".into();
    knots.systems[2].id = "2.2".into();
    let none: Vec<String> = Vec::new();
    let inputs = inputs(&knots, &none);
    let mut c = config();
    c.objective.strength = wslap::Strength::Value(0.01);
    let main = reconstruct(&inputs, &c, &mut quiet).unwrap();
    let plan = wslap::EnsemblePlan::new(&inputs, &c, &main, 40, 7).unwrap();
    let fits = |d: &wslap::MemberDraw, id: &str| d.fitted.iter().any(|f| f == id);
    for d in &plan.draws {
        assert_eq!(fits(d, "2.1"), fits(d, "2.2"), "{:?}", d.fitted);
    }
    let together = plan.draws.iter().filter(|d| fits(d, "2.1")).count();
    assert!(
        0 < together && together < 40,
        "{together} of 40 fit the knots"
    );
}

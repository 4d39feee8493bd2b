//! The external shear of the reconstruction against lenstronomy's: `k_external_shear` of
//! tests/data/fidelity (an NFW cluster with 70 members and lenstronomy's `SHEAR` of 0.08 along
//! 60 degrees; its `truth.json` and `make_clusters.py` beside it).

use wslap::{parse_image_catalog, parse_member_catalog, reconstruct, ConstraintSource};
use wslap::{Cosmology, Inputs, LayerSource, LensPlane, ReconstructConfig, Regulariser, Strength};

fn quiet(_: &wslap::ConvergenceRecord) -> wslap::Control {
    wslap::Control::Continue
}

const DIR: &str = "tests/data/fidelity/k_external_shear";

/// The truth's lens redshift and external shear `(gamma1, gamma2)` at `D_ls/D_s = 1`.
fn truth() -> (f64, (f64, f64)) {
    let text = std::fs::read_to_string(format!("{DIR}/truth.json")).unwrap();
    let t: serde_json::Value = serde_json::from_str(&text).unwrap();
    let roles = t["component_roles"].as_array().unwrap();
    let k = roles.iter().position(|r| r == "external shear").unwrap();
    let kw = &t["kwargs_lens"][k];
    let g = |key: &str| kw[key].as_f64().unwrap();
    (t["z_lens"].as_f64().unwrap(), (g("gamma1"), g("gamma2")))
}

/// A small run of the cluster (16 x 16 cells, `regulariser` at a fixed strength, 64-pixel
/// maps) with `sigma` as `grid.external_shear_sigma`.
fn run_with(sigma: Option<f64>, regulariser: Regulariser) -> wslap::Reconstruction {
    let read = |f: &str| std::fs::read_to_string(format!("{DIR}/{f}")).unwrap();
    let (catalog, _) = parse_image_catalog(&read("images.cat"), "images.cat", None).unwrap();
    let (members, _) =
        parse_member_catalog(&read("members.cat"), "members.cat", catalog.reference).unwrap();
    let inputs = Inputs {
        images: ConstraintSource::Catalog(&catalog),
        layers: LayerSource::Members(&members),
        plane: LensPlane::new(Cosmology::default(), truth().0).unwrap(),
        reference: catalog.reference,
        holdout: &[],
        catalog: Some(&catalog),
        shear: None,
    };
    let mut config = ReconstructConfig::default();
    config.objective.strength = Strength::Value(0.1);
    config.objective.regulariser = regulariser;
    config.grid.cells = 16;
    config.grid.external_shear_sigma = sigma;
    config.products.pixels = 64;
    reconstruct(&inputs, &config, &mut quiet).unwrap()
}

/// [`run_with`] the default regulariser (gradient).
fn run(sigma: Option<f64>) -> wslap::Reconstruction {
    run_with(sigma, Regulariser::Gradient)
}

#[test]
fn the_fitted_external_shear_is_lenstronomys() {
    // On by default, with the prior width run here.
    assert_eq!(
        ReconstructConfig::default().grid.external_shear_sigma,
        Some(0.1)
    );
    let (_, (g1, g2)) = truth();
    let r = run(Some(0.1));
    let fit = r.external_shear().unwrap();
    // Within under half the truth's strength (0.08) of it, its axis within 15 degrees of
    // the truth's 60 (this small run: 0.025 and 8 degrees off).
    let err = (fit.gamma1 - g1).hypot(fit.gamma2 - g2);
    assert!(
        err < 0.035,
        "fitted ({:.4}, {:.4}) against lenstronomy's ({g1:.4}, {g2:.4})",
        fit.gamma1,
        fit.gamma2
    );
    assert!((fit.angle_deg - 60.0).abs() < 15.0, "{fit:?}");
    assert_eq!(fit.prior_sigma, 0.1);
    // The shear's four layers are not members: one member factor, and the summary says both.
    assert_eq!(r.layer_factors().len(), 5);
    assert_eq!(r.member_factors().len(), 1);
    let summary: serde_json::Value = serde_json::to_value(r.summary()).unwrap();
    assert_eq!(summary["c_per_layer"].as_array().unwrap().len(), 1);
    assert_eq!(summary["layers"][0], "members");
    let g = summary["external_shear"]["gamma"].as_f64().unwrap();
    assert!((g - fit.gamma).abs() < 1e-12, "{g}");

    // Without it the same run has no shear to give and fits the images worse.
    let none = run(None);
    assert!(none.external_shear().is_none());
    let summary: serde_json::Value = serde_json::to_value(none.summary()).unwrap();
    assert!(summary["external_shear"].is_null());
    let (with, without) = (
        r.image_offset_median_arcsec(false).unwrap(),
        none.image_offset_median_arcsec(false).unwrap(),
    );
    assert!(
        with < without,
        "fitted images' median: {with} with the shear, {without} without"
    );
}

/// The least-mass regulariser fits no shear, whatever the setting: it would trade the map's
/// mass for one (BENCHMARKS.md, MACS J1149). Its run has the members' layer alone.
#[test]
fn the_least_mass_regulariser_fits_no_external_shear() {
    let mut config = ReconstructConfig::default();
    assert_eq!(config.external_shear_fitted(), Some(0.1));
    config.objective.regulariser = Regulariser::Density;
    assert_eq!(config.external_shear_fitted(), None);
    config.objective.regulariser = Regulariser::Curvature;
    assert_eq!(config.external_shear_fitted(), Some(0.1));
    let r = run_with(Some(0.1), Regulariser::Density);
    assert!(r.external_shear().is_none());
    assert_eq!(r.layer_factors().len(), 1);
    let summary: serde_json::Value = serde_json::to_value(r.summary()).unwrap();
    assert!(summary["external_shear"].is_null());
}

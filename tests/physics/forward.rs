//! The forward path the app's worker runs (`Products::from_model` on the built-in examples),
//! natively and as WebAssembly in a browser worker.

use wslap::sis_theta_e_arcsec;
use wslap::ColorScale;
use wslap::ModelFile;
use wslap::{ProductOptions, Products, ProductsError};
use wslap::{CLUSTER_MODEL_JSON, TEACHING_MODEL_JSON};

/// The teaching example's main halo dominates: its Einstein radius is close to the SIS value
/// `f theta_E`; the satellite perturbs it by a few percent.
const TEACHING_EINSTEIN_RTOL: f64 = 0.05;

fn small_options(z_source: f64) -> ProductOptions {
    ProductOptions {
        z_source,
        size_arcsec: 160.0,
        pixels: 160,
        scale: ColorScale::Log,
        maps_only: false,
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn cluster_example_has_curves_and_a_figure() {
    let model = ModelFile::from_json_str(CLUSTER_MODEL_JSON, "example").unwrap();
    let p = Products::from_model(&model, &small_options(2.0)).unwrap();
    let s = p.summary();
    assert!(s.tangential_curves >= 1 && s.radial_curves >= 1, "{s:?}");
    assert!(
        s.einstein_radius_arcsec > 20.0 && s.einstein_radius_arcsec < 45.0,
        "{s:?}"
    );
    // Every caustic vertex maps from a curve vertex; the magnification map is finite.
    assert_eq!(
        p.curves.caustics.tangential.len(),
        p.curves.tangential.len()
    );
    assert!(p.magnification.data.iter().all(|v| v.is_finite()));
    // The enclosed mass grows outwards.
    let masses: Vec<f64> = s
        .mass_within_arcsec
        .iter()
        .map(|(_, m)| m.unwrap())
        .collect();
    assert!(masses.windows(2).all(|w| w[1] > w[0]), "{masses:?}");
    let png = p.kappa_png(ColorScale::Log).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert!(png.len() > 10_000, "figure of {} bytes", png.len());
    let fits = p.fits_files().unwrap();
    assert_eq!(fits.len(), 7);
    assert!(fits.iter().all(|(_, bytes)| bytes.len() % 2880 == 0));
    assert!(p.regions().contains("fk5"));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn teaching_example_einstein_radius_is_the_sis_value() {
    let model = ModelFile::from_json_str(TEACHING_MODEL_JSON, "teaching").unwrap();
    let p = Products::from_model(&model, &small_options(1.5)).unwrap();
    let expected = p.distance_ratio * sis_theta_e_arcsec(700.0);
    let got = p.summary().einstein_radius_arcsec;
    assert!(
        (got - expected).abs() <= TEACHING_EINSTEIN_RTOL * expected,
        "Einstein radius {got} vs SIS {expected}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_options_are_refused() {
    let model = ModelFile::from_json_str(CLUSTER_MODEL_JSON, "example").unwrap();
    let err = Products::from_model(&model, &small_options(0.3)).unwrap_err();
    assert!(matches!(err, ProductsError::Cosmology(_)), "{err}");
    assert!(err.to_string().contains("z_s = 0.3"), "{err}");
    let mut opts = small_options(2.0);
    opts.pixels = 100_000;
    let err = Products::from_model(&model, &opts).unwrap_err();
    assert!(err.to_string().contains("pixels"), "{err}");
    opts.pixels = 64;
    opts.size_arcsec = f64::NAN;
    assert!(Products::from_model(&model, &opts).is_err());
}

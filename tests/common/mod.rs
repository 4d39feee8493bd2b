//! Shared by the integration tests. Each test that checks the core is written once and runs
//! natively (`#[test]`) and in headless Chromium inside a dedicated worker
//! (`#[wasm_bindgen_test]`), by putting both attributes on it:
//!
//! ```ignore
//! #[cfg_attr(not(target_arch = "wasm32"), test)]
//! #[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
//! fn sis_einstein_radius() { ... }
//! ```
//!
//! Tests that need the file system or the CLI are `#[cfg(not(target_arch = "wasm32"))]`.
//! Reference data are read with `include_str!` so that the browser build has them too.
#![allow(dead_code)] // each test binary uses a different part of this module

pub mod rng;

#[cfg(target_arch = "wasm32")]
wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_dedicated_worker);

/// `|a - b| <= rtol * |b|`, with a message naming what was compared.
#[track_caller]
pub fn assert_rel(what: &str, a: f64, b: f64, rtol: f64) {
    assert!(
        a.is_finite() && (a - b).abs() <= rtol * b.abs(),
        "{what}: got {a:e}, expected {b:e} (relative error {:e} > {rtol:e})",
        ((a - b) / b).abs()
    );
}

/// `|a - b| <= atol`.
#[track_caller]
pub fn assert_abs(what: &str, a: f64, b: f64, atol: f64) {
    assert!(
        a.is_finite() && (a - b).abs() <= atol,
        "{what}: got {a:e}, expected {b:e} (|difference| {:e} > {atol:e})",
        (a - b).abs()
    );
}

/// The Lenstool-style catalogue of the point images (`|mu| > 0.2`) that `lens` makes of
/// `sources` (`(z, beta)` in arcsec), found by solving the lens equation on a 120 arcsec
/// grid; system `k + 1` is the `k`-th source, and sources with fewer than 2 images are left
/// out.
pub fn point_image_catalog(
    lens: &dyn wslap::MassComponent,
    plane: &wslap::LensPlane,
    sources: impl Iterator<Item = (f64, glam::DVec2)>,
) -> wslap::ImageCatalog {
    use wslap::{find_images, ImageSearch, SearchGrid};
    use wslap::{Image, ImageCatalog, ImageSystem};
    let search = SearchGrid::Lens(wslap::MapGeometry::centered(120.0, 240));
    let mut systems = Vec::new();
    for (k, (z, beta)) in sources.enumerate() {
        let f = plane.distance_ratio(z).unwrap();
        let found = find_images(lens, search, f, beta, &ImageSearch::default()).unwrap();
        let images: Vec<Image> = found
            .iter()
            .filter(|i| i.magnification.abs() > 0.2)
            .enumerate()
            .map(|(j, i)| Image {
                id: format!("{}.{}", k + 1, j + 1),
                position: i.position,
                a_arcsec: 0.1,
                b_arcsec: 0.1,
                theta_deg: 0.0,
                mag: 0.0,
                line: 0,
            })
            .collect();
        if images.len() >= 2 {
            systems.push(ImageSystem {
                id: (k + 1).to_string(),
                z: Some(z),
                images,
            });
        }
    }
    ImageCatalog {
        source_name: "synthetic".into(),
        reference: None,
        systems,
    }
}

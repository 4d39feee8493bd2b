//! File formats and figures: FITS (against astropy), DS9 regions (against the `regions`
//! package), and the kappa figure (golden PNGs and pixel checks). Reference data come from
//! tests/data/files_reference.py; regenerate our own committed outputs with MAKE_REF=1.

use glam::DVec2;
use serde_json::Value;
use wslap::SkyReference;
use wslap::{Card, FitsWriteOptions};
use wslap::{Caustics, CriticalCurves};
use wslap::{Map, MapGeometry};

const REFERENCE_JSON: &str = include_str!("../data/files.json");
const OURS_FITS: &[u8] = include_bytes!("../data/files_ours.fits");
const OURS_FK5_REG: &str = include_str!("../data/files_ours_fk5.reg");
const OURS_IMAGE_REG: &str = include_str!("../data/files_ours_image.reg");
const OURS_MARKS_FK5_REG: &str = include_str!("../data/files_ours_marks_fk5.reg");
const OURS_MARKS_IMAGE_REG: &str = include_str!("../data/files_ours_marks_image.reg");
const ASTROPY_F32: &[u8] = include_bytes!("../data/files_astropy_f32.fits");
const ASTROPY_I16: &[u8] = include_bytes!("../data/files_astropy_i16.fits");
const GOLDEN_LINEAR: &[u8] = include_bytes!("../data/golden/kappa_linear.png");
const GOLDEN_LOG: &[u8] = include_bytes!("../data/golden/kappa_log_magma.png");

/// float32 storage: relative precision 2^-24 ~ 6e-8; values here are O(1).
const F32_ATOL: f64 = 1e-6;
/// Our linear tangent-plane frame ([method §1]) vs astropy's exact TAN projection: for
/// offsets of a few arcsec the second-order difference is < 1e-4 arcsec; 1e-3 arcsec in degrees.
///
/// [method §1]: wslap::method#1-frames-and-units
const WCS_ATOL_DEG: f64 = 1e-3 / 3600.0;
/// Region coordinates written with 8 decimals in degrees.
const REGION_ATOL_DEG: f64 = 1e-7;
/// Golden PNGs: anti-aliased edges may differ by a few levels between SIMD paths (native vs
/// wasm); a channel may differ by this much ...
const GOLDEN_CHANNEL_TOL: u8 = 3;
/// ... and at most this fraction of pixels by more.
const GOLDEN_OUTLIER_FRACTION: f64 = 0.002;

fn reference() -> Value {
    serde_json::from_str(REFERENCE_JSON).expect("tests/data/files.json parses")
}

fn sky() -> SkyReference {
    SkyReference {
        ra_deg: 197.875,
        dec_deg: -1.3425,
    }
}

/// A 16 x 16 map of 0.5 arcsec pixels centred at (1.5, -2) arcsec: a smooth cored profile.
fn small_map() -> Map {
    let g = MapGeometry {
        pixels: 16,
        size_arcsec: 8.0,
        center: DVec2::new(1.5, -2.0),
    };
    Map::from_fn(g, |p| {
        let d = p - DVec2::new(2.0, -1.5);
        1.0 / (1.0 + d.length_squared() / 4.0).sqrt() + 0.01 * p.x
    })
}

fn circle(center: DVec2, r: f64, n: usize) -> Vec<DVec2> {
    (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            center + r * DVec2::new(t.cos(), t.sin())
        })
        .collect()
}

/// Curves on `small_map`: a closed tangential circle, a radial circle, an open tangential arc
/// leaving the map on the left, and caustics.
fn small_curves() -> CriticalCurves {
    let c = DVec2::new(2.0, -1.5);
    // A quarter circle from the left edge (x = -2.5) to the bottom edge (y = -6).
    let open: Vec<DVec2> = (0..=12)
        .map(|k| {
            let a = std::f64::consts::FRAC_PI_2 * (1.0 - k as f64 / 12.0);
            DVec2::new(-2.5 + 3.0 * a.cos(), -6.0 + 3.0 * a.sin())
        })
        .collect();
    CriticalCurves {
        z_source: 2.0,
        einstein_radius_arcsec: 2.0,
        main_curve_radius_arcsec: 2.0,
        tangential_leaves_map: true,
        tangential: vec![circle(c, 2.0, 24), open],
        radial: vec![circle(c, 0.6, 12)],
        caustics: Caustics {
            tangential: vec![circle(c, 0.3, 8)],
            radial: vec![circle(c, 1.0, 10)],
        },
    }
}

fn small_fits_options() -> FitsWriteOptions {
    FitsWriteOptions {
        bunit: String::new(),
        comments: vec!["WSLAP+ test map: convergence for D_ls/D_s = 1 (HFF convention)".into()],
        reference: Some(sky()),
        extra_cards: vec![
            Card::real("ZSOURCE", 2.0, "source redshift"),
            Card::text("MODEL", "test 'quoted'", ""),
        ],
    }
}

/// Writes `bytes` to tests/data/`name` when MAKE_REF=1 (native only).
fn maybe_make_ref(name: &str, bytes: &[u8]) {
    #[cfg(not(target_arch = "wasm32"))]
    if std::env::var("MAKE_REF").as_deref() == Ok("1") {
        let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("writing {path}: {e}"));
    }
    #[cfg(target_arch = "wasm32")]
    let _ = (name, bytes);
}

mod ds9;
mod fits;
mod render;

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

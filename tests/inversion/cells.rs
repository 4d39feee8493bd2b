//! The cell grid ([method §3]): its geometry and automatic field, refinement of the
//! densest cells, the smoothness of the default cell width, and the fast cell kernel.
//!
//! [method §3]: wslap::method#3-the-linear-system

use crate::common::{assert_abs, assert_rel};
use glam::DVec2;
use wslap::{cell_unit_deflection, CellGrid, GridConfig, GridError, GridMass};
use wslap::{gaussian_unit_deflection, MassComponent};

/// The fast cell kernel vs the reference Gaussian deflection (both accurate to a few ulp).
const KERNEL_RTOL: f64 = 1e-13;

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn grid_geometry_and_auto_field() {
    let g = CellGrid::regular(DVec2::new(10.0, -5.0), 40.0, 4, 0.75).unwrap();
    assert_eq!(g.len(), 16);
    assert_abs("cell 0 x", g.cells[0].center.x, -5.0, 1e-12);
    assert_abs("cell 0 y", g.cells[0].center.y, -20.0, 1e-12);
    // j = row * n + column: cell 6 is column 2, row 1.
    assert_abs("cell 6 x", g.cells[6].center.x, 15.0, 1e-12);
    assert_abs("cell 6 y", g.cells[6].center.y, -10.0, 1e-12);
    assert_abs("sigma", g.cells[5].sigma_arcsec, 7.5, 1e-12);
    assert!(g.contains(DVec2::new(29.9, 14.9), 0.0));
    assert!(!g.contains(DVec2::new(30.5, 0.0), 0.0));
    assert!(g.contains(DVec2::new(30.5, 0.0), 1.0));

    let config = GridConfig {
        cells: 8,
        ..GridConfig::default()
    };
    let wide = [DVec2::new(-40.0, 0.0), DVec2::new(60.0, 10.0)];
    let g = CellGrid::from_config(&config, &wide).unwrap();
    assert_abs("auto centre x", g.center.x, 10.0, 1e-12);
    assert_abs("auto width", g.width_arcsec, 130.0, 1e-9);
    let compact = [DVec2::new(-5.0, 0.0), DVec2::new(5.0, 2.0)];
    let g = CellGrid::from_config(&config, &compact).unwrap();
    assert_abs("minimum width", g.width_arcsec, 60.0, 1e-12);
    assert_eq!(
        CellGrid::from_config(&config, &[]).unwrap_err(),
        GridError::NoPositions
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn grid_refinement_splits_the_densest_cells() {
    let g = CellGrid::regular(DVec2::ZERO, 40.0, 4, 0.75).unwrap();
    let masses: Vec<f64> = (0..16)
        .map(|j| {
            if [5, 6, 9, 10].contains(&j) {
                10.0
            } else {
                1.0
            }
        })
        .collect();
    let r = g.refine(&masses, 0.25).unwrap();
    assert_eq!(r.len(), 12 + 16);
    let area: f64 = r.cells.iter().map(|c| c.size_arcsec * c.size_arcsec).sum();
    assert_rel("area kept", area, 1600.0, 1e-12);
    for c in &r.cells {
        let parent = &g.cells[c.parent];
        if [5, 6, 9, 10].contains(&c.parent) {
            assert_eq!(c.level, 1);
            assert_abs("child size", c.size_arcsec, 5.0, 1e-12);
            assert_abs("child sigma", c.sigma_arcsec, 3.75, 1e-12);
            assert_abs("offset x", (c.center.x - parent.center.x).abs(), 2.5, 1e-12);
            assert_abs("offset y", (c.center.y - parent.center.y).abs(), 2.5, 1e-12);
        } else {
            assert_eq!(
                c,
                &wslap::Cell {
                    parent: c.parent,
                    ..*parent
                }
            );
        }
    }
    assert!(matches!(
        g.refine(&masses[1..], 0.25),
        Err(GridError::MassCount { .. })
    ));
    assert!(matches!(
        g.refine(&masses, 0.0),
        Err(GridError::BadFieldValue(_))
    ));
}

/// The default width 0.75 cell is smooth: relative ripple of the convergence of equal masses
/// in the middle of a 16 x 16 grid below 1e-3, while 0.5 cell ripples by more than 1%.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn default_cell_width_is_smooth() {
    let ripple = |factor: f64| {
        let g = CellGrid::regular(DVec2::ZERO, 16.0, 16, factor).unwrap();
        let mass = GridMass::new(&g, vec![1.0; g.len()]).unwrap();
        let k: Vec<f64> = (0..=20)
            .flat_map(|i| (0..=20).map(move |j| DVec2::new(i as f64 * 0.1, j as f64 * 0.1)))
            .map(|p| mass.kappa(p))
            .collect();
        let (lo, hi) = k
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        hi / lo - 1.0
    };
    let default = GridConfig::default().cell_sigma_factor;
    assert!(ripple(default) < 1e-3, "ripple {}", ripple(default));
    assert!(ripple(0.5) > 1e-2, "ripple {}", ripple(0.5));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn cell_kernel_matches_gaussian_deflection() {
    let sigma = 1.7;
    let inv = 0.5 / (sigma * sigma);
    for &(dx, dy) in &[
        (0.0, 0.0),
        (1e-9, -2e-9),
        (0.3, 0.1),
        (-1.2, 2.0),
        (5.0, -3.0),
        (14.0, 0.5),
        (-300.0, 200.0),
    ] {
        let (ax, ay) = cell_unit_deflection(dx, dy, inv);
        let (rx, ry) = gaussian_unit_deflection(dx, dy, sigma);
        let scale = rx.hypot(ry).max(1e-300);
        assert_abs("ax", ax / scale, rx / scale, KERNEL_RTOL);
        assert_abs("ay", ay / scale, ry / scale, KERNEL_RTOL);
    }
}

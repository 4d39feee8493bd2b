//! The linear system ([method §4]): `Gamma X` is the lens equation of the
//! reconstructed lens, normal equations from blocks, the frame shift, the prior on C, and
//! the NumPy export.
//!
//! [method §4]: wslap::method#4-member-galaxies

use crate::common::{assert_abs, assert_rel};
use crate::fixtures::{members, plane, three_systems};
use glam::DVec2;
use wslap::gram_weighted;
use wslap::{
    build_constraints, build_member_layers, npy_header, CellGrid, ColumnInfo, ConstraintConfig,
    ConstraintSet, ConstraintSource, GridConfig, Layer, LinearSystem, MemberConfig, ObjectiveTerms,
    Regulariser, RowBlock, SystemConfig, SystemError,
};
use wslap::{Gaussian, MassComponent, Nfw, TruncatedNfw};

/// Row-by-row `Gamma X` vs the lens equation with the reconstructed lens: the same sums in a
/// different order (arcsec, for deflections of tens of arcsec).
const GAMMA_X_ATOL_ARCSEC: f64 = 1e-10;

/// Normal equations from blocks vs from the whole `Gamma`: different summation order only.
const NORMAL_RTOL: f64 = 1e-12;

/// Least-squares solutions for two frame shifts: a 24-unknown dense solve of a poorly
/// conditioned system (measured 4e-9 on values of ~6).
const SHIFT_ATOL: f64 = 1e-6;

/// A small deterministic generator in [0, 1) (no RNG dependency in the tests).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// The ellipse pixels (of `pixel_arcsec`) of the three systems and a 4 x 4 grid over them.
fn three_systems_on_4x4(pixel_arcsec: f64) -> (ConstraintSet, CellGrid) {
    let constraints = build_constraints(
        ConstraintSource::Catalog(&three_systems()),
        &ConstraintConfig {
            pixel_arcsec,
            ..ConstraintConfig::default()
        },
        &[],
    )
    .unwrap();
    let positions: Vec<DVec2> = constraints.pixels.iter().map(|p| p.position).collect();
    let grid = CellGrid::from_config(
        &GridConfig {
            cells: 4,
            ..GridConfig::default()
        },
        &positions,
    )
    .unwrap();
    (constraints, grid)
}

/// A 4 x 4 grid, one true layer (a truncated NFW and an NFW) and the member layers of
/// `split`, and the ellipse pixels of the three systems.
fn small_system(split: &str, config: &SystemConfig) -> LinearSystem {
    small_system_with_prior(split, config, None)
}

/// [`small_system`] with `c_prior_sigma` on the member layers (the true layer has none).
fn small_system_with_prior(
    split: &str,
    config: &SystemConfig,
    c_prior_sigma: Option<f64>,
) -> LinearSystem {
    let plane = plane();
    let (constraints, grid) = three_systems_on_4x4(0.25);
    let truth = Layer::from_components(
        "truth",
        vec![
            Box::new(TruncatedNfw::new(DVec2::new(2.0, 3.0), 3e12, 8.0, 8.0, &plane).unwrap()),
            Box::new(Nfw::new(DVec2::new(-10.0, 5.0), 2e13, 6.0, &plane).unwrap()),
        ],
    );
    let member_config = MemberConfig {
        layers: split.parse().unwrap(),
        mag_star: Some(19.0),
        c_prior_sigma,
        ..MemberConfig::default()
    };
    let mut layers = vec![truth];
    layers.extend(
        build_member_layers(&members(), &member_config, &plane, &grid)
            .unwrap()
            .layers,
    );
    LinearSystem::build(&grid, &layers, &constraints, &plane, config).unwrap()
}

fn random_x(sys: &LinearSystem, seed: u64) -> Vec<f64> {
    let mut state = seed;
    let mut x: Vec<f64> = (0..sys.n_columns())
        .map(|_| 0.1 + 2.0 * lcg(&mut state))
        .collect();
    for c in sys.layer_columns() {
        x[c] = 1.0;
    }
    for c in sys.beta_x_columns().chain(sys.beta_y_columns()) {
        x[c] = sys.theta_shift_arcsec + 20.0 * (lcg(&mut state) - 0.5);
    }
    x
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn gamma_x_is_the_lens_equation_of_the_reconstructed_lens() {
    let sys = small_system("bcg", &SystemConfig::default());
    let n_pix = sys.constraints.pixels.len();
    assert_eq!(sys.n_rows, 2 * n_pix);
    assert_eq!(sys.n_columns(), 16 + 3 + 2 * 3);
    let x = random_x(&sys, 7);
    let lens = sys.reconstructed_lens(&x).unwrap();
    let betas = sys.betas_arcsec(&x).unwrap();
    let mut block = RowBlock::default();
    sys.rows(0..n_pix, &mut block).unwrap();
    let n = sys.n_columns();
    let mut max_alpha: f64 = 0.0;
    for (i, pixel) in sys.constraints.pixels.iter().enumerate() {
        let f = sys.distance_ratios[pixel.system];
        let alpha = lens.deflection(pixel.position);
        max_alpha = max_alpha.max(alpha.length());
        // Lens equation: theta + S = f alpha(theta) + beta + S.
        let model = f * alpha + betas[pixel.system] + DVec2::splat(sys.theta_shift_arcsec);
        for (axis, model_axis) in [(0, model.x), (1, model.y)] {
            let row = &block.gamma[(2 * i + axis) * n..(2 * i + axis + 1) * n];
            let gx: f64 = row.iter().zip(&x).map(|(g, v)| g * v).sum();
            assert_abs("Gamma X", gx, model_axis, GAMMA_X_ATOL_ARCSEC);
        }
        assert_eq!(
            block.theta[2 * i],
            pixel.position.x + sys.theta_shift_arcsec
        );
        assert_eq!(block.weights[2 * i + 1], pixel.weight);
    }
    assert!(max_alpha > 5.0, "the test lens must deflect: {max_alpha}");
    // Cell masses in Msun and the beta shift round trip.
    let masses = sys.cell_masses_msun(&x).unwrap();
    assert_rel("cell mass", masses[3], x[3] * 1e12, 1e-15);
    assert_abs(
        "beta_y",
        betas[2].y,
        x[sys.beta_y_columns().start + 2] - sys.theta_shift_arcsec,
        1e-12,
    );
    assert!(matches!(
        sys.reconstructed_lens(&x[1..]),
        Err(SystemError::Length { .. })
    ));
    // The column list says what each unknown is.
    assert!(matches!(sys.columns[0], ColumnInfo::Cell { index: 0, .. }));
    assert!(matches!(&sys.columns[17], ColumnInfo::Layer { name, .. } if name == "bcg"));
    assert!(matches!(&sys.columns[19], ColumnInfo::BetaX { id, .. } if id == "1"));
    assert!(matches!(&sys.columns[24], ColumnInfo::BetaY { id, .. } if id == "3"));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn normal_equations_from_blocks_equal_the_whole_gamma() {
    let whole = small_system("single", &SystemConfig::default());
    let tiny = SystemConfig {
        block_mbytes: 0.002,
        threads: 3,
        ..SystemConfig::default()
    };
    let blocked = small_system("single", &tiny);
    assert!(blocked.pixels_per_block() < 10 && whole.pixels_per_block() > whole.n_rows);
    let n = whole.n_columns();
    let mut block = RowBlock::default();
    whole
        .rows(0..whole.constraints.pixels.len(), &mut block)
        .unwrap();
    let mut other = RowBlock::default();
    blocked
        .rows(0..blocked.constraints.pixels.len(), &mut other)
        .unwrap();
    assert_eq!(block, other, "rows do not depend on threads or blocks");
    let (a, b) =
        gram_weighted(&block.gamma, whole.n_rows, n, &block.weights, &block.theta).unwrap();
    for (name, sys) in [("whole", &whole), ("blocked", &blocked)] {
        for i in 0..n {
            let scale_b =
                (a[i * n + i] * block.theta.iter().map(|t| t * t).fold(0.0, f64::max)).sqrt();
            assert_abs(name, sys.b[i] / scale_b, b[i] / scale_b, NORMAL_RTOL);
            for j in 0..n {
                let scale = (a[i * n + i] * a[j * n + j]).sqrt();
                assert_abs(
                    name,
                    sys.a[i * n + j] / scale,
                    a[i * n + j] / scale,
                    NORMAL_RTOL,
                );
            }
        }
    }
    let twt: f64 = block
        .theta
        .iter()
        .zip(&block.weights)
        .map(|(t, w)| w * t * t)
        .sum();
    assert_rel("theta W theta", blocked.theta_w_theta, twt, NORMAL_RTOL);
}

/// Dense least squares `A x = -b` by Gaussian elimination with partial pivoting.
fn solve_dense(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut m: Vec<f64> = a.to_vec();
    let mut r: Vec<f64> = b.iter().map(|v| -v).collect();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| m[i * n + k].abs().total_cmp(&m[j * n + k].abs()))
            .unwrap();
        for c in 0..n {
            m.swap(k * n + c, p * n + c);
        }
        r.swap(k, p);
        for i in k + 1..n {
            let f = m[i * n + k] / m[k * n + k];
            for c in k..n {
                m[i * n + c] -= f * m[k * n + c];
            }
            r[i] -= f * r[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|c| m[k * n + c] * x[c]).sum();
        x[k] = (r[k] - s) / m[k * n + k];
    }
    x
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn frame_shift_round_trips_through_the_solution() {
    let auto = small_system("single", &SystemConfig::default());
    let reach = auto
        .constraints
        .pixels
        .iter()
        .map(|p| p.position.abs().max_element())
        .fold(0.0, f64::max);
    assert_eq!(
        auto.theta_shift_arcsec,
        (reach + auto.grid.width_arcsec).ceil()
    );
    let shifted = small_system(
        "single",
        &SystemConfig {
            theta_shift_arcsec: Some(auto.theta_shift_arcsec + 37.0),
            ..SystemConfig::default()
        },
    );
    let n = auto.n_columns();
    assert_eq!(auto.a, shifted.a, "A does not depend on the shift");
    let x1 = solve_dense(&auto.a, &auto.b, n);
    let x2 = solve_dense(&shifted.a, &shifted.b, n);
    for c in auto.cell_columns().chain(auto.layer_columns()) {
        assert_abs("mass or C", x2[c], x1[c], SHIFT_ATOL);
    }
    for (b1, b2) in auto
        .betas_arcsec(&x1)
        .unwrap()
        .iter()
        .zip(shifted.betas_arcsec(&x2).unwrap())
    {
        assert_abs("beta x", b2.x, b1.x, SHIFT_ATOL);
        assert_abs("beta y", b2.y, b1.y, SHIFT_ATOL);
    }
    let raw = x2[shifted.beta_x_columns().start] - x1[auto.beta_x_columns().start];
    assert_abs("raw beta moves by the shift", raw, 37.0, SHIFT_ATOL);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn npy_header_is_valid() {
    for shape in [vec![3usize, 25], vec![7], vec![123_456, 4_200]] {
        let h = npy_header(&shape);
        assert_eq!(&h[..8], b"\x93NUMPY\x01\x00");
        assert_eq!(h.len() % 64, 0);
        let len = u16::from_le_bytes([h[8], h[9]]) as usize;
        assert_eq!(len + 10, h.len());
        assert_eq!(*h.last().unwrap(), b'\n');
        let dict = std::str::from_utf8(&h[10..]).unwrap();
        let dims = if shape.len() == 1 {
            format!("({},)", shape[0])
        } else {
            format!("({}, {})", shape[0], shape[1])
        };
        assert!(
            dict.starts_with(&format!(
                "{{'descr': '<f8', 'fortran_order': False, 'shape': {dims}, }}"
            )),
            "{dict}"
        );
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn export_writes_gamma_theta_weights_and_columns() {
    let sys = small_system(
        "bcg",
        &SystemConfig {
            block_mbytes: 0.005,
            ..SystemConfig::default()
        },
    );
    let dir = std::env::temp_dir().join(format!("wslap-export-{}", std::process::id()));
    wslap::export_system(&sys, &dir).unwrap();
    let n = sys.n_columns();
    let gamma = std::fs::read(dir.join("gamma.npy")).unwrap();
    let header = npy_header(&[sys.n_rows, n]);
    assert_eq!(&gamma[..header.len()], &header[..]);
    assert_eq!(gamma.len(), header.len() + sys.n_rows * n * 8);
    let mut block = RowBlock::default();
    sys.rows(0..sys.constraints.pixels.len(), &mut block)
        .unwrap();
    let values: Vec<f64> = gamma[header.len()..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(values, block.gamma);
    let theta = std::fs::read(dir.join("theta.npy")).unwrap();
    let h1 = npy_header(&[sys.n_rows]).len();
    let first = f64::from_le_bytes(theta[h1..h1 + 8].try_into().unwrap());
    assert_eq!(first, block.theta[0]);
    assert_eq!(theta.len(), h1 + sys.n_rows * 8);
    assert_eq!(
        std::fs::read(dir.join("weights.npy")).unwrap().len(),
        h1 + sys.n_rows * 8
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("columns.json")).unwrap()).unwrap();
    assert_eq!(json["columns"].as_array().unwrap().len(), n);
    assert_eq!(json["columns"][0]["kind"], "cell");
    assert_eq!(json["columns"][17]["name"], "bcg");
    assert_eq!(json["columns"][24]["kind"], "beta_y");
    assert_eq!(json["mass_unit_msun"], 1e12);
    assert_eq!(json["theta_shift_arcsec"], sys.theta_shift_arcsec);
    assert_eq!(json["systems"][1]["id"], "2");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `chi^2(X) = X^T A X + 2 b^T X + Theta^T W Theta` from the normal equations.
fn chi2(sys: &LinearSystem, x: &[f64]) -> f64 {
    let n = sys.n_columns();
    let quad: f64 = (0..n)
        .map(|i| x[i] * (0..n).map(|j| sys.a[i * n + j] * x[j]).sum::<f64>())
        .sum();
    let lin: f64 = sys.b.iter().zip(x).map(|(b, x)| b * x).sum();
    quad + 2.0 * lin + sys.theta_w_theta
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_prior_on_c_adds_one_row_per_member_layer() {
    let sigma = 0.2;
    let w = 1.0 / (sigma * sigma);
    let free = small_system("bcg", &SystemConfig::default());
    let held = small_system_with_prior("bcg", &SystemConfig::default(), Some(sigma));
    let n = free.n_columns();
    // Columns: the true layer (no prior), then "bcg" and "rest".
    let member_columns: Vec<usize> = held.layer_columns().skip(1).collect();
    assert_eq!(member_columns.len(), 2);
    assert_eq!(held.n_rows, free.n_rows + 2);
    let prior = held.prior_rows();
    assert_eq!(prior.weights, vec![w, w]);
    assert_eq!(prior.theta, vec![1.0, 1.0]);
    for (k, &c) in member_columns.iter().enumerate() {
        let row = &prior.gamma[k * n..(k + 1) * n];
        assert!(row
            .iter()
            .enumerate()
            .all(|(j, &v)| v == if j == c { 1.0 } else { 0.0 }));
    }
    // The normal equations change on the prior columns' diagonal and in b, nowhere else.
    for i in 0..n {
        let on = member_columns.contains(&i);
        for j in 0..n {
            let want = if on && i == j { w } else { 0.0 };
            let d = held.a[i * n + j] - free.a[i * n + j];
            assert!(
                (d - want).abs() <= 1e-9 * (1.0 + free.a[i * n + j].abs()),
                "A[{i},{j}]"
            );
        }
        let want = if on { -w } else { 0.0 };
        let d = held.b[i] - free.b[i];
        assert!((d - want).abs() <= 1e-9 * (1.0 + free.b[i].abs()), "b[{i}]");
    }
    // chi^2 grows by ((C - 1) / sigma)^2 per member layer.
    let mut x = random_x(&held, 5);
    let (c_bcg, c_rest) = (1.5, 0.7);
    x[member_columns[0]] = c_bcg;
    x[member_columns[1]] = c_rest;
    let added = ((c_bcg - 1.0f64) / sigma).powi(2) + ((c_rest - 1.0f64) / sigma).powi(2);
    let d = chi2(&held, &x) - chi2(&free, &x);
    assert!(
        (d - added).abs() <= 1e-6 * chi2(&free, &x),
        "{d} vs {added}"
    );
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn export_ends_with_the_prior_rows() {
    let sys = small_system_with_prior("single", &SystemConfig::default(), Some(0.5));
    let dir = std::env::temp_dir().join(format!("wslap-export-prior-{}", std::process::id()));
    wslap::export_system(&sys, &dir).unwrap();
    let n = sys.n_columns();
    let read = |name: &str| -> Vec<f64> {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let header = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
        bytes[header..]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let (gamma, theta, weights) = (read("gamma.npy"), read("theta.npy"), read("weights.npy"));
    assert_eq!(sys.n_rows, 2 * sys.constraints.pixels.len() + 1);
    assert_eq!(gamma.len(), sys.n_rows * n);
    let last = &gamma[(sys.n_rows - 1) * n..];
    let c = sys.layer_columns().last().unwrap();
    assert!(last
        .iter()
        .enumerate()
        .all(|(j, &v)| v == if j == c { 1.0 } else { 0.0 }));
    assert_eq!(theta.last(), Some(&1.0));
    assert_eq!(weights.last(), Some(&4.0));
    assert_eq!(theta.len(), sys.n_rows);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Least mass charges a member layer's mass as the cells' ([method §4]): the layer's mass in
/// the cells adds up to its own (a Gaussian of known mass well inside the grid), the
/// penalty of `C = 1` equals that of the cells holding that mass, and the smoothness
/// regularisers leave the layer uncharged.
///
/// [method §4]: wslap::method#4-member-galaxies
#[test]
fn least_mass_charges_a_member_layer_as_cell_mass() {
    let plane = plane();
    let (constraints, grid) = three_systems_on_4x4(ConstraintConfig::default().pixel_arcsec);
    let mass_msun = 3e12;
    let galaxy = Gaussian::new(DVec2::new(3.0, -2.0), mass_msun, 2.0, &plane).unwrap();
    let layers = [Layer::from_components("galaxy", vec![Box::new(galaxy)])];
    let build = |regulariser| {
        let terms = ObjectiveTerms {
            regulariser,
            penalty_weight: Some(1.0),
            ..ObjectiveTerms::default()
        };
        let config = SystemConfig::default();
        LinearSystem::build_with(&grid, &layers, &constraints, &plane, &config, terms).unwrap()
    };
    let none = build(Regulariser::None);
    let p = none.member_mass_in_cells();
    assert_rel(
        "layer mass in the cells (Msun)",
        p.iter().sum::<f64>() * none.mass_unit_msun,
        mass_msun,
        1e-3,
    );
    let n = none.n_columns();
    let penalty = |sys: &LinearSystem, x: &[f64]| -> f64 {
        (0..n)
            .flat_map(|j| (0..n).map(move |k| (j, k)))
            .map(|(j, k)| x[j] * (sys.a[j * n + k] - none.a[j * n + k]) * x[k])
            .sum()
    };
    let mut as_member = vec![0.0; n];
    as_member[none.layer_columns().start] = 1.0;
    let mut as_cells = vec![0.0; n];
    as_cells[none.cell_columns()].copy_from_slice(&p);
    let density = build(Regulariser::Density);
    assert!(penalty(&density, &as_cells) > 0.0);
    assert_rel(
        "penalty of C = 1 against its mass in the cells",
        penalty(&density, &as_member),
        penalty(&density, &as_cells),
        1e-9,
    );
    let gradient = build(Regulariser::Gradient);
    assert_abs(
        "gradient's penalty of C = 1",
        penalty(&gradient, &as_member),
        0.0,
        0.0,
    );
    // The build keeps the member masses in its terms; a system built again from them (the
    // image-plane passes) has the same matrix, and masses of another grid's length are
    // computed again, not used.
    assert_eq!(density.terms.member_mass_in_cells.as_deref(), Some(&p[..]));
    let config = SystemConfig::default();
    let again = |terms| {
        LinearSystem::build_with(&grid, &layers, &constraints, &plane, &config, terms).unwrap()
    };
    assert_eq!(again(density.terms.clone()).a, density.a);
    let wrong = ObjectiveTerms {
        member_mass_in_cells: Some(vec![1.0; p.len() + 1].into()),
        ..density.terms.clone()
    };
    assert_eq!(again(wrong).a, density.a);
    assert_eq!(gradient.terms.member_mass_in_cells, None);
}

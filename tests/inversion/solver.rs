//! The solvers: QADP against the exact active-set solver on random problems, analytic
//! non-negative quadratic programs, the run protocol (reports, cancel, positivity, monotone
//! objective), the normal-equations accumulator against a naive product, and bad inputs.

use crate::common;

use common::assert_rel;
use wslap::{
    accelerated_gradient, gram_weighted, iterate_schedule, minimise_exact, nnqp_exact,
    quadratic_objective as objective, Control, NormalEquations, Progress, QadpProblem,
    SolveOutcome, SolveStatus, SolverError, SolverSettings, MAX_KEPT_ITERATES,
    NNQP_EXACT_MAX_UNKNOWNS,
};

/// QADP after enough iterations against the exact optimum: `phi - phi* <= 1e-6 |phi*|` is the
/// requirement of the solver (measured: <= 8.3e-10).
const QADP_OBJECTIVE_RTOL: f64 = 1e-6;
/// The exact solver on problems with a closed-form optimum: rounding only.
const EXACT_RTOL: f64 = 1e-12;
/// The objective reported during a run comes from the f32 pass: ~1e-7 of `x^T |A| x`, which
/// here is about `|phi|` (measured: <= 3e-8).
const REPORTED_OBJECTIVE_RTOL: f64 = 1e-7;
/// QADP is monotone: the f64 objective of the reported iterates may rise only by the rounding
/// of its own sum (measured: <= 2e-15).
const MONOTONE_RTOL: f64 = 1e-13;
/// Bands of rows change how the f32 column sums are grouped: runs with different thread counts
/// agree to the f32 rounding of the sums (measured: ~1e-9 of max x after 700 iterations).
const THREADS_RTOL: f64 = 1e-6;
/// Another storage order groups the f32 sums differently too; on the ill-conditioned lens
/// problem the iterates drift further apart than on the random ones (measured: 1.1e-6 of
/// max x after 1500 iterations).
const ORDER_RTOL: f64 = 1e-5;
/// The accelerated projected gradient against the exact optimum, after enough iterations
/// (measured: <= 3e-16 after 3000: rounding).
const ACCELERATED_OBJECTIVE_RTOL: f64 = 1e-10;
/// `G^T W G` blocked and threaded vs a naive triple loop (different summation order).
const GRAM_RTOL: f64 = 1e-12;

use common::rng::Rng;

/// The reference minimiser: [`nnqp_exact`]'s answer, which must have converged.
fn exact_minimiser(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let outcome = nnqp_exact(a, b, n).expect("exact solver");
    assert_eq!(outcome.status, SolveStatus::Converged, "{outcome:?}");
    outcome.x
}

/// `A = G^T G`, `b = -G^T y` with `G` (2n x n) Gaussian and `y = G x_true + noise`, where
/// about a third of `x_true` is negative, so that the optimum has components at 0.
fn random_problem(rng: &mut Rng, n: usize) -> (Vec<f64>, Vec<f64>) {
    let m = 2 * n;
    let g: Vec<f64> = (0..m * n).map(|_| rng.normal()).collect();
    let x_true: Vec<f64> = (0..n).map(|_| rng.uniform() * 3.0 - 1.0).collect();
    let y: Vec<f64> = (0..m)
        .map(|r| (0..n).map(|j| g[r * n + j] * x_true[j]).sum::<f64>() + 0.1 * rng.normal())
        .collect();
    gram_weighted(&g, m, n, &vec![1.0; m], &y).expect("valid random system")
}

/// One report: iteration, reported objective, f64 objective of the reported x, min x.
type Report = (usize, f64, f64, f64);

/// Runs QADP on `(a, b)` and returns the outcome and every report.
fn run_recorded(
    (a, b): (&[f64], &[f64]),
    problem: &QadpProblem,
    x0: &[f64],
    settings: &SolverSettings,
) -> (wslap::SolveOutcome, Vec<Report>) {
    let mut reports = Vec::new();
    let outcome = problem
        .run(x0, settings, &mut |p| {
            assert!(
                p.x.iter().all(|v| v.is_finite()),
                "x finite at {}",
                p.iteration
            );
            let min_x = p.x.iter().fold(f64::INFINITY, |m, &v| m.min(v));
            reports.push((p.iteration, p.objective, objective(a, b, p.x), min_x));
            Control::Continue
        })
        .expect("valid run");
    (outcome, reports)
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn qadp_matches_exact_on_random_problems() {
    let mut rng = Rng(20020);
    for case in 0..20 {
        let n = 5 + case * 55 / 19;
        let (a, b) = random_problem(&mut rng, n);
        let exact = exact_minimiser(&a, &b, n);
        let phi_star = objective(&a, &b, &exact);
        assert!(exact.contains(&0.0), "case {case}: some optimal x_i = 0");
        let problem = QadpProblem::new(&a, &b, n).expect("valid problem");
        let settings = SolverSettings {
            iterations: 6000,
            report_every: 200,
            threads: 0,
            keep_iterates: 0,
        };
        let (outcome, reports) = run_recorded((&a, &b), &problem, &vec![0.1; n], &settings);
        assert_eq!(outcome.status, SolveStatus::Completed);
        assert_eq!(outcome.iterations, 6000);
        let phi = objective(&a, &b, &outcome.x);
        assert!(
            phi - phi_star <= QADP_OBJECTIVE_RTOL * phi_star.abs(),
            "case {case} (n = {n}): QADP phi = {phi:e}, exact phi* = {phi_star:e}"
        );
        for &(t, reported, exact, min_x) in &reports {
            assert!(min_x >= 0.0, "case {case}: x >= 0 at iteration {t}");
            assert_rel(
                "reported objective",
                reported,
                exact,
                REPORTED_OBJECTIVE_RTOL,
            );
        }
        for pair in reports.windows(2) {
            let ((_, _, phi0, _), (t1, _, phi1, _)) = (pair[0], pair[1]);
            assert!(
                phi1 <= phi0 + MONOTONE_RTOL * phi0.abs(),
                "case {case}: objective rose from {phi0:e} to {phi1:e} at iteration {t1}"
            );
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn diagonal_problem_has_closed_form_optimum() {
    // min sum_i (d_i x_i^2 / 2 + b_i x_i), x >= 0: x_i = max(-b_i / d_i, 0).
    let d: [f64; 5] = [2.0, 0.5, 4.0, 1.0, 3.0];
    let b = [-1.0, 2.0, -8.0, 0.5, -0.3];
    let n = d.len();
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        a[i * n + i] = d[i];
    }
    let expected: Vec<f64> = (0..n).map(|i| (-b[i] / d[i]).max(0.0)).collect();
    let exact = exact_minimiser(&a, &b, n);
    let problem = QadpProblem::new(&a, &b, n).expect("valid problem");
    let settings = SolverSettings {
        iterations: 50,
        ..SolverSettings::default()
    };
    let outcome = problem
        .run(&[1.0; 5], &settings, &mut |_| Control::Continue)
        .expect("valid run");
    for i in 0..n {
        common::assert_abs("exact x_i", exact[i], expected[i], EXACT_RTOL);
        common::assert_abs("QADP x_i", outcome.x[i], expected[i], 1e-12);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn two_by_two_with_active_bound() {
    // A = [[2, 1], [1, 2]], b = (-1, 1): the unconstrained optimum (1, -1) is infeasible; the
    // constrained one is (1/2, 0) with phi = -1/4 (gradient of x_2 there: 1/2 + 1 > 0).
    let a = [2.0, 1.0, 1.0, 2.0];
    let b = [-1.0, 1.0];
    let exact = exact_minimiser(&a, &b, 2);
    common::assert_abs("exact x_1", exact[0], 0.5, EXACT_RTOL);
    common::assert_abs("exact x_2", exact[1], 0.0, EXACT_RTOL);
    let problem = QadpProblem::new(&a, &b, 2).expect("valid problem");
    let outcome = problem
        .run(&[1.0, 1.0], &SolverSettings::default(), &mut |_| {
            Control::Continue
        })
        .expect("valid run");
    assert_rel("QADP phi", outcome.objective, -0.25, 1e-9);
    common::assert_abs("QADP x_1", outcome.x[0], 0.5, 1e-6);
    common::assert_abs("QADP x_2", outcome.x[1], 0.0, 1e-6);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn cancel_stops_at_the_reported_state() {
    let (a, b) = random_problem(&mut Rng(7), 30);
    let problem = QadpProblem::new(&a, &b, 30).expect("valid problem");
    let mut seen = Vec::new();
    let outcome = problem
        .run(&[0.1; 30], &SolverSettings::default(), &mut |p| {
            seen.push(p.iteration);
            if p.iteration == 300 {
                assert_rel(
                    "objective shown",
                    p.objective,
                    objective(&a, &b, p.x),
                    REPORTED_OBJECTIVE_RTOL,
                );
                Control::Cancel
            } else {
                Control::Continue
            }
        })
        .expect("valid run");
    assert_eq!(outcome.status, SolveStatus::Cancelled);
    assert_eq!(outcome.iterations, 300);
    assert_eq!(seen, vec![0, 100, 200, 300]);
    let exact = objective(&a, &b, &outcome.x);
    assert_rel(
        "objective",
        outcome.objective,
        exact,
        REPORTED_OBJECTIVE_RTOL,
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn reports_at_start_every_k_and_at_the_end() {
    let (a, b) = random_problem(&mut Rng(8), 12);
    let problem = QadpProblem::new(&a, &b, 12).expect("valid problem");
    let settings = SolverSettings {
        iterations: 250,
        report_every: 100,
        threads: 0,
        keep_iterates: 0,
    };
    let (outcome, reports) = run_recorded((&a, &b), &problem, &[0.1; 12], &settings);
    let iterations: Vec<usize> = reports.iter().map(|r| r.0).collect();
    assert_eq!(iterations, vec![0, 100, 200, 250]);
    assert_eq!(outcome.iterations, 250);
    let none = SolverSettings {
        iterations: 0,
        ..settings
    };
    let (outcome, reports) = run_recorded((&a, &b), &problem, &[0.1; 12], &none);
    assert_eq!((outcome.iterations, reports.len()), (0, 1));
    assert_eq!(outcome.x, vec![0.1; 12]);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn zero_start_component_stays_zero() {
    let n = 20;
    let (a, b) = random_problem(&mut Rng(9), n);
    let exact = exact_minimiser(&a, &b, n);
    let k = exact
        .iter()
        .position(|&v| v > 0.1)
        .expect("a clearly positive optimal component");
    let mut x0 = vec![0.1; n];
    x0[k] = 0.0;
    let problem = QadpProblem::new(&a, &b, n).expect("valid problem");
    let outcome = problem
        .run(&x0, &SolverSettings::default(), &mut |p| {
            assert_eq!(p.x[k], 0.0, "x_{k} at iteration {}", p.iteration);
            Control::Continue
        })
        .expect("valid run");
    assert_eq!(outcome.x[k], 0.0);
}

/// Unknown 1 has a zero row: `b_1 > 0` sends it to 0; unknown 3 (zero row, `b_3 = 0`) keeps
/// its start. Unknowns 0 and 2 solve the 2x2 problem of `two_by_two_with_active_bound`
/// (`x = (0.5, 0)`).
fn zero_row_problem() -> (Vec<f64>, [f64; 4]) {
    let n = 4;
    let mut a = vec![0.0; n * n];
    a[0] = 2.0;
    a[2] = 1.0;
    a[2 * n] = 1.0;
    a[2 * n + 2] = 2.0;
    (a, [-1.0, 3.0, 1.0, 0.0])
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn zero_rows_go_to_zero_or_stay() {
    let n = 4;
    let (a, b) = zero_row_problem();
    let problem = QadpProblem::new(&a, &b, n).expect("valid problem");
    let outcome = problem
        .run(
            &[1.0, 1.0, 1.0, 0.7],
            &SolverSettings::default(),
            &mut |_| Control::Continue,
        )
        .expect("valid run");
    common::assert_abs("x_0", outcome.x[0], 0.5, 1e-6);
    assert_eq!(outcome.x[1], 0.0);
    assert_eq!(outcome.x[3], 0.7);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn units_do_not_matter() {
    // phi scaled by s: same minimiser. Extreme s checks that the f32 copy is rescaled.
    let n = 15;
    let (a, b) = random_problem(&mut Rng(10), n);
    let settings = SolverSettings {
        iterations: 500,
        ..SolverSettings::default()
    };
    let base = QadpProblem::new(&a, &b, n)
        .expect("valid problem")
        .run(&[0.1; 15], &settings, &mut |_| Control::Continue)
        .expect("valid run");
    for s in [1e-30, 1e30] {
        let a_s: Vec<f64> = a.iter().map(|v| v * s).collect();
        let b_s: Vec<f64> = b.iter().map(|v| v * s).collect();
        let scaled = QadpProblem::new(&a_s, &b_s, n)
            .expect("valid problem")
            .run(&[0.1; 15], &settings, &mut |_| Control::Continue)
            .expect("valid run");
        for (x, x_ref) in scaled.x.iter().zip(&base.x) {
            common::assert_abs("x scaled problem", *x, *x_ref, 1e-12 * (1.0 + x_ref));
        }
        assert_rel("objective", scaled.objective, base.objective * s, 1e-12);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn threads_agree_to_rounding() {
    // Odd: the last band ends with a lone row.
    let n = 61;
    let (a, b) = random_problem(&mut Rng(11), n);
    let problem = QadpProblem::new(&a, &b, n).expect("valid problem");
    let run = |threads| {
        let settings = SolverSettings {
            iterations: 700,
            report_every: 100,
            threads,
            keep_iterates: 0,
        };
        problem
            .run(&[0.1; 61], &settings, &mut |_| Control::Continue)
            .expect("valid run")
    };
    let serial = run(1);
    let x_max = serial.x.iter().fold(0.0f64, |m, &v| m.max(v));
    for threads in [2, 3] {
        let parallel = run(threads);
        for (x, x_ref) in parallel.x.iter().zip(&serial.x) {
            common::assert_abs("x with threads", *x, *x_ref, THREADS_RTOL * x_max);
        }
        assert_rel(
            "objective",
            parallel.objective,
            serial.objective,
            THREADS_RTOL,
        );
    }
}

/// A lens-shaped problem: the deflections of a 12 x 12 grid of Gaussian cells at 300 pixels,
/// plus a ridge. Its matrix has long stretches of one sign, which the solver's pass handles
/// apart from stretches of both signs.
fn lens_problem(rng: &mut Rng) -> (Vec<f64>, Vec<f64>, Vec<[f64; 2]>) {
    let (side, pixels) = (12, 300);
    let n = side * side;
    let centres: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            [
                (k % side) as f64 * 10.0 - 55.0,
                (k / side) as f64 * 10.0 - 55.0,
            ]
        })
        .collect();
    let rows = 2 * pixels + n;
    let mut g = vec![0.0; rows * n];
    let mut y = vec![0.0; rows];
    for p in 0..pixels {
        let (px, py) = (rng.uniform() * 80.0 - 40.0, rng.uniform() * 80.0 - 40.0);
        for (k, c) in centres.iter().enumerate() {
            let (dx, dy) = (px - c[0], py - c[1]);
            let r2 = dx * dx + dy * dy + 1e-9;
            let f = (1.0 - (-r2 / 50.0).exp()) / r2;
            g[p * n + k] = f * dx;
            g[(pixels + p) * n + k] = f * dy;
        }
        // An NFW-like pull towards the centre.
        y[p] = 0.3 * px / (1.0 + (px * px + py * py).sqrt() / 20.0);
        y[pixels + p] = 0.3 * py / (1.0 + (px * px + py * py).sqrt() / 20.0);
    }
    for k in 0..n {
        g[(2 * pixels + k) * n + k] = 0.05;
    }
    let (a, b) = gram_weighted(&g, rows, n, &vec![1.0; rows], &y).expect("valid lens system");
    (a, b, centres)
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_storage_order_changes_only_the_rounding() {
    let (a, b, centres) = lens_problem(&mut Rng(14));
    let n = centres.len();
    let settings = SolverSettings {
        iterations: 1500,
        report_every: 500,
        threads: 1,
        keep_iterates: 0,
    };
    let x0 = vec![0.01; n];
    let plain = QadpProblem::new(&a, &b, n).expect("valid problem");
    let (reference, reports) = run_recorded((&a, &b), &plain, &x0, &settings);
    let x_max = reference.x.iter().fold(0.0f64, |m, &v| m.max(v));
    let reversed: Vec<usize> = (0..n).rev().collect();
    for (name, order) in [
        ("along the Hilbert curve", wslap::locality_order(&centres)),
        ("reversed", reversed),
    ] {
        let problem = QadpProblem::with_order(&a, &b, n, order).expect("valid order");
        for threads in [1, 2] {
            let settings = SolverSettings {
                threads,
                ..settings
            };
            let (outcome, ordered_reports) = run_recorded((&a, &b), &problem, &x0, &settings);
            for (x, x_ref) in outcome.x.iter().zip(&reference.x) {
                common::assert_abs(name, *x, *x_ref, ORDER_RTOL * x_max);
            }
            for (&(_, reported, exact, _), &(_, reported_ref, _, _)) in
                ordered_reports.iter().zip(&reports)
            {
                assert_rel(name, reported, exact, REPORTED_OBJECTIVE_RTOL);
                assert_rel(name, reported, reported_ref, THREADS_RTOL);
            }
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_bad_storage_order_is_named() {
    let (a, b) = random_problem(&mut Rng(15), 4);
    for (order, says) in [
        (vec![0, 1, 2], "it has 3 entries"),
        (vec![0, 1, 2, 4], "entry 3 is 4"),
        (vec![0, 2, 1, 2], "2 appears twice (again at entry 3)"),
    ] {
        let err = QadpProblem::with_order(&a, &b, 4, order).expect_err("bad order");
        assert!(matches!(err, SolverError::BadOrder { n: 4, .. }), "{err:?}");
        assert!(err.to_string().contains(says), "{err}");
    }
}

/// The threads of a run live as long as the run: every report sees the state all bands agree
/// on, and a cancel (as any other end) lets them go.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn threaded_runs_report_every_chunk_and_end_on_cancel() {
    let n = 61;
    let (a, b) = random_problem(&mut Rng(13), n);
    let problem = QadpProblem::new(&a, &b, n).expect("valid problem");
    let record = |threads| {
        let mut reports = Vec::new();
        let settings = SolverSettings {
            iterations: 400,
            report_every: 30,
            threads,
            keep_iterates: 0,
        };
        let outcome = problem
            .run(&[0.1; 61], &settings, &mut |p| {
                reports.push((p.iteration, p.objective, objective(&a, &b, p.x)));
                if p.iteration >= 150 {
                    Control::Cancel
                } else {
                    Control::Continue
                }
            })
            .expect("valid run");
        (outcome, reports)
    };
    let (serial, serial_reports) = record(1);
    for threads in [2, 3] {
        let (outcome, reports) = record(threads);
        assert_eq!(outcome.status, SolveStatus::Cancelled);
        assert_eq!(outcome.iterations, 150);
        assert_eq!(reports.len(), serial_reports.len());
        for (&(k, reported, exact), &(k_ref, reported_ref, _)) in
            reports.iter().zip(&serial_reports)
        {
            assert_eq!(k, k_ref);
            assert_rel(
                "reported objective",
                reported,
                exact,
                REPORTED_OBJECTIVE_RTOL,
            );
            assert_rel(
                "objective against one thread",
                reported,
                reported_ref,
                THREADS_RTOL,
            );
        }
        assert_rel(
            "final objective",
            outcome.objective,
            serial.objective,
            THREADS_RTOL,
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn normal_equations_match_naive_product() {
    let mut rng = Rng(12);
    // 37 unknowns: not a multiple of the tile sizes; 300: large enough to be threaded.
    for (n, n_rows) in [(37, 300), (300, 40)] {
        let g: Vec<f64> = (0..n_rows * n).map(|_| rng.normal()).collect();
        let w: Vec<f64> = (0..n_rows).map(|_| rng.uniform() * 2.0).collect();
        let theta: Vec<f64> = (0..n_rows).map(|_| rng.normal() * 50.0).collect();
        let mut normal = NormalEquations::new(n).expect("n > 0");
        // Uneven blocks, one longer than the internal block of rows.
        let cuts = [0, n_rows / 3, n_rows / 3 + 1, n_rows];
        for pair in cuts.windows(2) {
            let (r0, r1) = (pair[0], pair[1]);
            normal
                .add_rows(&g[r0 * n..r1 * n], &w[r0..r1], &theta[r0..r1])
                .expect("valid rows");
        }
        assert_eq!(normal.rows_added(), n_rows);
        let (a, b) = normal.finish();
        for i in 0..n {
            let b_ref: f64 = (0..n_rows).map(|r| -w[r] * theta[r] * g[r * n + i]).sum();
            let scale_b: f64 = (0..n_rows)
                .map(|r| (w[r] * theta[r] * g[r * n + i]).abs())
                .sum();
            common::assert_abs("b_i", b[i], b_ref, GRAM_RTOL * scale_b);
            for j in 0..n {
                let terms = (0..n_rows).map(|r| w[r] * g[r * n + i] * g[r * n + j]);
                let a_ref: f64 = terms.clone().sum();
                let scale: f64 = terms.map(f64::abs).sum();
                common::assert_abs("A_ij", a[i * n + j], a_ref, GRAM_RTOL * scale);
            }
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_inputs_are_named() {
    let a = [2.0, 1.0, 1.0, 2.0];
    let b = [-1.0, 1.0];
    let new = |a: &[f64], b: &[f64], n| QadpProblem::new(a, b, n).map(|_| ());
    assert_eq!(new(&[], &[], 0), Err(SolverError::Empty));
    assert!(matches!(
        new(&a[..3], &b, 2),
        Err(SolverError::DimensionMismatch {
            what: "A",
            expected: 4,
            got: 3
        })
    ));
    assert!(matches!(
        new(&a, &[1.0], 2),
        Err(SolverError::DimensionMismatch { what: "b", .. })
    ));
    assert!(matches!(
        new(&[2.0, f64::NAN, 1.0, 2.0], &b, 2),
        Err(SolverError::NonFinite {
            what: "A",
            index: 1,
            ..
        })
    ));
    assert!(matches!(
        new(&a, &[f64::INFINITY, 0.0], 2),
        Err(SolverError::NonFinite {
            what: "b",
            index: 0,
            ..
        })
    ));
    assert!(matches!(
        new(&[2.0, 1.0, 0.5, 2.0], &b, 2),
        Err(SolverError::NotSymmetric { row: 0, col: 1, .. })
    ));
    assert!(matches!(
        new(&[-1.0, 0.0, 0.0, 2.0], &b, 2),
        Err(SolverError::NotPositiveSemidefinite { row: 0, col: 0, .. })
    ));
    assert!(matches!(
        new(&[1.0, 3.0, 3.0, 1.0], &b, 2),
        Err(SolverError::NotPositiveSemidefinite { row: 0, col: 1, .. })
    ));
    assert_eq!(
        new(&[2.0, 0.0, 0.0, 0.0], &[1.0, -2.0], 2),
        Err(SolverError::Unbounded { index: 1, b: -2.0 })
    );

    let problem = QadpProblem::new(&a, &b, 2).expect("valid problem");
    let settings = SolverSettings::default();
    let mut go = |_: &Progress| Control::Continue;
    assert!(matches!(
        problem.run(&[1.0], &settings, &mut go),
        Err(SolverError::DimensionMismatch { what: "x0", .. })
    ));
    assert!(matches!(
        problem.run(&[1.0, f64::NAN], &settings, &mut go),
        Err(SolverError::NonFinite {
            what: "x0",
            index: 1,
            ..
        })
    ));
    assert_eq!(
        problem.run(&[1.0, -0.5], &settings, &mut go),
        Err(SolverError::NegativeStart {
            index: 1,
            value: -0.5
        })
    );
    let no_reports = SolverSettings {
        report_every: 0,
        ..settings
    };
    assert!(matches!(
        problem.run(&[1.0, 1.0], &no_reports, &mut go),
        Err(SolverError::BadFieldValue(ref e)) if e.field == "solver.report_every"
    ));

    let big = NNQP_EXACT_MAX_UNKNOWNS + 1;
    let mut identity = vec![0.0; big * big];
    for i in 0..big {
        identity[i * big + i] = 1.0;
    }
    assert!(matches!(
        nnqp_exact(&identity, &vec![-1.0; big], big),
        Err(SolverError::TooLarge { .. })
    ));

    let mut normal = NormalEquations::new(2).expect("n > 0");
    assert_eq!(NormalEquations::new(0).err(), Some(SolverError::Empty));
    assert!(matches!(
        normal.add_rows(&[1.0, 2.0, 3.0], &[1.0], &[0.0]),
        Err(SolverError::DimensionMismatch { what: "rows", .. })
    ));
    assert!(matches!(
        normal.add_rows(&[1.0, 2.0], &[-1.0], &[0.0]),
        Err(SolverError::NegativeWeight { index: 0, .. })
    ));
    assert!(matches!(
        normal.add_rows(&[1.0, 2.0], &[1.0], &[f64::NAN]),
        Err(SolverError::NonFinite { what: "theta", .. })
    ));
    assert!(matches!(
        gram_weighted(&[1.0, 2.0], 1, 2, &[], &[0.0]),
        Err(SolverError::DimensionMismatch { what: "w", .. })
    ));
    assert_eq!(normal.rows_added(), 0, "failed calls add nothing");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn accelerated_gradient_matches_exact_on_random_problems() {
    let mut rng = Rng(20150);
    for case in 0..20 {
        let n = 5 + case * 55 / 19;
        let (a, b) = random_problem(&mut rng, n);
        let exact = exact_minimiser(&a, &b, n);
        let phi_star = objective(&a, &b, &exact);
        let settings = SolverSettings {
            iterations: 3000,
            report_every: 500,
            threads: 0,
            keep_iterates: 0,
        };
        let mut reports = Vec::new();
        // A start at 0 is allowed here (unlike QADP, nothing stays where it starts).
        let outcome = accelerated_gradient(&a, &b, n, &vec![0.0; n], &settings, &mut |p| {
            assert!(p.x.iter().all(|&v| v >= 0.0), "x >= 0 at {}", p.iteration);
            assert_rel(
                "reported objective",
                p.objective,
                objective(&a, &b, p.x),
                1e-12,
            );
            reports.push(p.iteration);
            Control::Continue
        })
        .expect("valid run");
        assert_eq!(reports, vec![0, 500, 1000, 1500, 2000, 2500, 3000]);
        assert_eq!(outcome.status, SolveStatus::Completed);
        let phi = objective(&a, &b, &outcome.x);
        assert!(
            phi - phi_star <= ACCELERATED_OBJECTIVE_RTOL * phi_star.abs(),
            "case {case} (n = {n}): phi = {phi:e}, exact phi* = {phi_star:e}"
        );
    }
}

/// Far fewer iterations than QADP for the same accuracy: after 300 each, the accelerated
/// gradient is within 1e-8 of the optimum where QADP is not (this is what lets `wslap paper`
/// find the data's best fit of its 1000-unknown system in a few thousand iterations).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn accelerated_gradient_goes_further_than_qadp_per_iteration() {
    let n = 60;
    let (a, b) = random_problem(&mut Rng(31), n);
    let phi_star = objective(&a, &b, &exact_minimiser(&a, &b, n));
    let settings = SolverSettings {
        iterations: 300,
        report_every: 300,
        threads: 1,
        keep_iterates: 0,
    };
    let quiet = &mut |_: &Progress| Control::Continue;
    let fast = accelerated_gradient(&a, &b, n, &vec![0.1; n], &settings, quiet).expect("run");
    let qadp = QadpProblem::new(&a, &b, n)
        .expect("valid problem")
        .run(&vec![0.1; n], &settings, quiet)
        .expect("run");
    let gap = |x: &[f64]| (objective(&a, &b, x) - phi_star) / phi_star.abs();
    let (gap_fast, gap_qadp) = (gap(&fast.x), gap(&qadp.x));
    println!("after 300 iterations: accelerated {gap_fast:e}, QADP {gap_qadp:e}");
    assert!(gap_fast <= 1e-8, "accelerated gap {gap_fast:e}");
    assert!(
        gap_qadp > 100.0 * gap_fast.max(1e-16),
        "QADP gap {gap_qadp:e}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn accelerated_gradient_cancels_and_handles_zero_rows() {
    let n = 4;
    let (a, b) = zero_row_problem();
    let settings = SolverSettings::default();
    let outcome = accelerated_gradient(&a, &b, n, &[1.0, 1.0, 1.0, 0.7], &settings, &mut |_| {
        Control::Continue
    })
    .expect("valid run");
    common::assert_abs("x_0", outcome.x[0], 0.5, 1e-12);
    assert_eq!(outcome.x[1], 0.0);
    assert_eq!(outcome.x[2], 0.0);
    assert_eq!(outcome.x[3], 0.7);
    let mut seen = Vec::new();
    let cancelled = accelerated_gradient(&a, &b, n, &[1.0; 4], &settings, &mut |p| {
        seen.push(p.iteration);
        if p.iteration == 200 {
            Control::Cancel
        } else {
            Control::Continue
        }
    })
    .expect("valid run");
    assert_eq!(cancelled.status, SolveStatus::Cancelled);
    assert_eq!((cancelled.iterations, seen), (200, vec![0, 100, 200]));
    let err = accelerated_gradient(&a, &b, n, &[1.0, -1.0, 1.0, 1.0], &settings, &mut |_| {
        Control::Continue
    })
    .unwrap_err();
    assert!(
        matches!(err, SolverError::NegativeStart { index: 1, .. }),
        "{err}"
    );
}

/// The iterates a run kept: at the scheduled counts (increasing), at most `keep`, the last one
/// the outcome itself, and each with its own objective.
fn check_kept(outcome: &SolveOutcome, keep: usize, (a, b): (&[f64], &[f64]), what: &str) {
    let kept = &outcome.iterates;
    assert!(
        !kept.is_empty() && kept.len() <= keep,
        "{what}: {} kept",
        kept.len()
    );
    let counts: Vec<usize> = kept.iter().map(|i| i.iteration).collect();
    assert!(counts.windows(2).all(|w| w[0] < w[1]), "{what}: {counts:?}");
    let last = kept.last().expect("one kept");
    assert_eq!(last.iteration, outcome.iterations, "{what}");
    assert_eq!(
        last.x, outcome.x,
        "{what}: the last iterate is the solution"
    );
    for i in kept {
        let phi = objective(a, b, &i.x);
        assert_rel(what, i.objective, phi, REPORTED_OBJECTIVE_RTOL.max(1e-6));
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn kept_iterates_follow_the_schedule_and_change_nothing() {
    let n = 30;
    let (a, b) = random_problem(&mut Rng(2302), n);
    let problem = QadpProblem::new(&a, &b, n).expect("valid problem");
    let plain = SolverSettings {
        iterations: 3000,
        report_every: 100,
        threads: 1,
        keep_iterates: 0,
    };
    let keep = 41;
    let keeping = SolverSettings {
        keep_iterates: keep,
        ..plain
    };
    let x0 = vec![0.1; n];
    let (without, reports_without) = run_recorded((&a, &b), &problem, &x0, &plain);
    let (with, reports_with) = run_recorded((&a, &b), &problem, &x0, &keeping);
    assert!(without.iterates.is_empty());
    // Stopping at the kept counts changes neither the iterates nor the reports.
    assert_eq!(with.x, without.x);
    assert_eq!(reports_with, reports_without);
    check_kept(&with, keep, (&a, &b), "QADP");
    let counts: Vec<usize> = with.iterates.iter().map(|i| i.iteration).collect();
    assert_eq!(counts, iterate_schedule(3000, keep));
    assert_eq!(with.iterates[0].x, x0, "the start is kept");
    // QADP lowers the objective along the kept iterates, and an early one is not the end.
    let phi: Vec<f64> = with
        .iterates
        .iter()
        .map(|i| objective(&a, &b, &i.x))
        .collect();
    for w in phi.windows(2) {
        assert!(w[1] <= w[0] + MONOTONE_RTOL * w[0].abs(), "{phi:?}");
    }
    assert_ne!(with.iterates[10].x, with.x);

    // A cancelled run ends its iterates with the state it stopped at.
    let cancelled = problem
        .run(&x0, &keeping, &mut |p| match p.iteration {
            500 => Control::Cancel,
            _ => Control::Continue,
        })
        .expect("valid run");
    assert_eq!(cancelled.status, SolveStatus::Cancelled);
    check_kept(&cancelled, keep, (&a, &b), "QADP cancelled");

    // The accelerated gradient keeps its iterates the same way.
    let fast = accelerated_gradient(&a, &b, n, &x0, &keeping, &mut |_| Control::Continue)
        .expect("valid run");
    check_kept(&fast, keep, (&a, &b), "accelerated gradient");
    let fast_plain = accelerated_gradient(&a, &b, n, &x0, &plain, &mut |_| Control::Continue)
        .expect("valid run");
    assert_eq!(fast.x, fast_plain.x);

    // The exact solver keeps every step of its few tens.
    let mut ridge = a.clone();
    for i in 0..n {
        ridge[i * n + i] += 1e-3 * a[i * n + i];
    }
    let exact =
        minimise_exact(&ridge, &b, n, 500, keep, &mut |_| Control::Continue).expect("valid run");
    assert_eq!(exact.status, SolveStatus::Converged);
    check_kept(&exact, keep, (&ridge, &b), "exact");
    assert_eq!(
        exact.iterates.len(),
        exact.iterations + 1,
        "start and every step"
    );

    // The bound is a setting's, checked.
    let too_many = SolverSettings {
        keep_iterates: MAX_KEPT_ITERATES + 1,
        ..plain
    };
    let err = problem.run(&x0, &too_many, &mut |_| Control::Continue);
    assert!(
        matches!(&err, Err(SolverError::BadFieldValue(e)) if e.to_string().contains("keep_iterates")),
        "{err:?}"
    );
}

//! An exact solver for small non-negative quadratic programs, the reference for the QADP tests:
//! the active-set method of Lawson & Hanson (1974, "Solving Least Squares Problems", ch. 23) in
//! the normal-equations form of Bro & de Jong (1997, J. Chemometrics 11, 393):
//! `min 1/2 x^T A x + b^T x` subject to `x >= 0`, `A` symmetric positive definite on every
//! free set the method visits.
//!
//! Free unknowns (the passive set `P`) solve `A_PP x_P = -b_P` by Cholesky; the unknown with the
//! most negative gradient `A x + b` enters `P`; when the unconstrained solution leaves the
//! feasible region the step is cut at the first boundary and those unknowns leave `P`. It
//! stops when the gradient is `>= -tol` on every fixed unknown (the KKT conditions).

use super::{objective, validate_system, SolveOutcome, SolveStatus, SolverError};

/// Largest problem [`nnqp_exact`] accepts: each active-set change refactorises `A_PP`
/// (`|P|^3 / 3` operations), which is meant for test problems.
pub const NNQP_EXACT_MAX_UNKNOWNS: usize = 256;

/// KKT tolerance relative to the size of the gradient's terms, `max_i (|b_i| + (|A| x)_i)`:
/// a fixed unknown may enter only if its gradient is below `-KKT_RTOL` times that.
const KKT_RTOL: f64 = 1e-12;
/// A Cholesky pivot below `PIVOT_RTOL * max_i A_ii` (over the free set) means `A_PP` is
/// numerically singular.
const PIVOT_RTOL: f64 = 1e-13;

/// The exact minimiser of `1/2 x^T A x + b^T x` over `x >= 0` for `A` row-major `n * n`
/// (symmetric positive definite on the free sets visited, e.g. `A = G^T G` with `G` of full
/// column rank) and `n <= NNQP_EXACT_MAX_UNKNOWNS`. The status says how it ended:
/// [`SolveStatus::Converged`] (every optimality condition holds), [`SolveStatus::Completed`]
/// (the limit of `10 n + 100` active-set changes was reached first) or
/// [`SolveStatus::Singular`] (`A` is singular on a free set); `iterations` counts the changes.
pub fn nnqp_exact(a: &[f64], b: &[f64], n: usize) -> Result<SolveOutcome, SolverError> {
    validate_system(a, b, n)?;
    if n > NNQP_EXACT_MAX_UNKNOWNS {
        return Err(SolverError::TooLarge {
            n,
            max: NNQP_EXACT_MAX_UNKNOWNS,
        });
    }
    let max_changes = 10 * n + 100;
    let mut x = vec![0.0; n];
    let mut free = vec![false; n];
    // An unknown that could not enter because of rounding is skipped until the next change.
    let mut skipped = vec![false; n];
    let mut changes = 0;
    loop {
        let (gradient, scale) = gradient_and_scale(a, b, &x, n);
        let tol = KKT_RTOL * scale;
        let entering = (0..n)
            .filter(|&j| !free[j] && !skipped[j] && gradient[j] < -tol)
            .min_by(|&i, &j| gradient[i].total_cmp(&gradient[j]));
        let Some(j) = entering else {
            return Ok(outcome(a, b, x, changes, SolveStatus::Converged));
        };
        if changes == max_changes {
            return Ok(outcome(a, b, x, changes, SolveStatus::Completed));
        }
        changes += 1;
        free[j] = true;
        let mut first = true;
        loop {
            let set: Vec<usize> = (0..n).filter(|&i| free[i]).collect();
            let Some(s) = solve_free(a, b, n, &set) else {
                return Ok(outcome(a, b, x, changes, SolveStatus::Singular));
            };
            if s.iter().all(|&v| v > 0.0) {
                for (&i, &v) in set.iter().zip(&s) {
                    x[i] = v;
                }
                skipped.fill(false);
                break;
            }
            if first && s[set.iter().position(|&i| i == j).unwrap_or(0)] <= 0.0 {
                free[j] = false;
                skipped[j] = true;
                break;
            }
            first = false;
            // Step from x towards s up to the first free unknown that reaches 0.
            let to_boundary =
                |x_i: f64, v: f64| (v <= 0.0).then(|| if x_i > v { x_i / (x_i - v) } else { 0.0 });
            let alpha = set
                .iter()
                .zip(&s)
                .filter_map(|(&i, &v)| to_boundary(x[i], v))
                .fold(f64::INFINITY, f64::min);
            for (&i, &v) in set.iter().zip(&s) {
                let hits = to_boundary(x[i], v).is_some_and(|t| t <= alpha);
                x[i] += alpha * (v - x[i]);
                if hits || x[i] <= 0.0 {
                    x[i] = 0.0;
                    free[i] = false;
                }
            }
        }
    }
}

fn outcome(a: &[f64], b: &[f64], x: Vec<f64>, changes: usize, status: SolveStatus) -> SolveOutcome {
    SolveOutcome {
        objective: objective(a, b, &x),
        x,
        iterations: changes,
        status,
        iterates: Vec::new(),
    }
}

/// The gradient `A x + b` and `max_i (|b_i| + sum_j |A_ij| x_j)`.
fn gradient_and_scale(a: &[f64], b: &[f64], x: &[f64], n: usize) -> (Vec<f64>, f64) {
    let mut scale = 0.0f64;
    let gradient = (0..n)
        .map(|i| {
            let row = &a[i * n..(i + 1) * n];
            let (g, s) = row
                .iter()
                .zip(x)
                .fold((b[i], b[i].abs()), |(g, s), (a_ij, x_j)| {
                    (g + a_ij * x_j, s + (a_ij * x_j).abs())
                });
            scale = scale.max(s);
            g
        })
        .collect();
    (gradient, scale)
}

/// `x_P = -A_PP^{-1} b_P` by Cholesky, for the free set `set`; `None` when a pivot is too small
/// (`A_PP` numerically singular).
fn solve_free(a: &[f64], b: &[f64], n: usize, set: &[usize]) -> Option<Vec<f64>> {
    let m = set.len();
    let max_diag = set.iter().map(|&i| a[i * n + i]).fold(0.0, f64::max);
    let mut l = vec![0.0; m * m];
    for r in 0..m {
        for c in 0..=r {
            let dot: f64 = (0..c).map(|k| l[r * m + k] * l[c * m + k]).sum();
            let v = a[set[r] * n + set[c]] - dot;
            if r == c {
                if v <= PIVOT_RTOL * max_diag {
                    return None;
                }
                l[r * m + r] = v.sqrt();
            } else {
                l[r * m + c] = v / l[c * m + c];
            }
        }
    }
    // L y = -b_P, then L^T x = y.
    let mut y = vec![0.0; m];
    for r in 0..m {
        let dot: f64 = (0..r).map(|k| l[r * m + k] * y[k]).sum();
        y[r] = (-b[set[r]] - dot) / l[r * m + r];
    }
    for r in (0..m).rev() {
        let dot: f64 = ((r + 1)..m).map(|k| l[k * m + r] * y[k]).sum();
        y[r] = (y[r] - dot) / l[r * m + r];
    }
    Some(y)
}

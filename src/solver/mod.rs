//! Non-negative quadratic programming for the WSLAP+ linear system ([method §5]).
//!
//! The inversion minimises `phi(X) = 1/2 X^T A X + b^T X` subject to `X >= 0`, with
//! `A = Gamma^T W Gamma` (symmetric positive semi-definite, dense) and `b = -Gamma^T W Theta`.
//!
//! - [`NormalEquations`] accumulates `A` and `b` from blocks of rows of `Gamma` (blocked,
//!   multi-threaded natively), [`gram_weighted`] does it in one call.
//! - [`QadpProblem`] runs the multiplicative update of Sha, Saul & Lee (2002) (QADP), the
//!   paper's solver; the number of iterations is the regulariser.
//! - [`accelerated_gradient`] is an accelerated projected gradient for the same problem: it
//!   approaches the minimiser itself, which QADP's early stop avoids (for reports, and as a
//!   solver option).
//! - [`minimise_exact`] finds the minimiser of a positive definite (regularised) problem
//!   exactly by block principal pivoting: the default, whose answer depends on the objective
//!   alone, not on a start or an iteration count.
//! - [`nnqp_exact`] is an exact active-set solver (Lawson–Hanson in QP form) for small problems,
//!   the reference the tests compare QADP with.
//! - [`column_independence`] says how much of some unknowns' effect the other unknowns cannot
//!   reproduce: whether the data measure them at all.
//!
//! All matrices are dense, row-major `&[f64]` of `n * n` values.
//!
//! [method §5]: crate::method#5-the-solver-qadp

mod accelerated;
mod gram;
mod independence;
mod kernel;
mod nnls;
mod pivoting;
mod qadp;
mod run;
mod settings;
mod status;
mod sweep;
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod wasm_simd;

use thiserror::Error;

pub use accelerated::accelerated_gradient;
pub use gram::{gram_weighted, NormalEquations};
pub use independence::{column_independence, INDEPENDENCE_MAX_UNKNOWNS};
pub use nnls::{nnqp_exact, NNQP_EXACT_MAX_UNKNOWNS};
pub use pivoting::minimise_exact;
pub use qadp::QadpProblem;
pub use run::iterate_schedule;
pub use settings::{SolverSettings, MAX_ITERATIONS, MAX_KEPT_ITERATES};
pub use status::{Control, Iterate, Progress, SolveOutcome, SolveStatus};

/// What can be wrong with a quadratic program, its start or the solver settings.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SolverError {
    #[error("solver: the problem has no unknowns (n = 0)")]
    Empty,
    #[error("solver: {what} has {got} values, expected {expected}")]
    DimensionMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("solver: {what}[{index}] = {value} is not finite")]
    NonFinite {
        what: &'static str,
        index: usize,
        value: f64,
    },
    #[error("solver: A is not symmetric: A[{row}][{col}] = {a_row_col:e} but A[{col}][{row}] = {a_col_row:e}")]
    NotSymmetric {
        row: usize,
        col: usize,
        a_row_col: f64,
        a_col_row: f64,
    },
    #[error("solver: A is not positive semi-definite: {reason} (row {row}, column {col}, value {value:e})")]
    NotPositiveSemidefinite {
        row: usize,
        col: usize,
        value: f64,
        reason: &'static str,
    },
    #[error("solver: the objective is unbounded below along unknown {index}: its row of A is zero and b[{index}] = {b:e} < 0")]
    Unbounded { index: usize, b: f64 },
    #[error("solver: start x0[{index}] = {value} is negative (every start value must be >= 0)")]
    NegativeStart { index: usize, value: f64 },
    #[error("solver: {what}[{index}] = {value} must be >= 0")]
    NegativeWeight {
        what: &'static str,
        index: usize,
        value: f64,
    },
    #[error("solver: the order of the unknowns is not a permutation of 0..{n}: {reason}")]
    BadOrder { n: usize, reason: String },
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error("solver: the exact solver handles at most {max} unknowns, got {n}")]
    TooLarge { n: usize, max: usize },
}

/// Relative tolerance of the symmetry check: `|A_ij - A_ji| <= SYMMETRY_RTOL * sqrt(A_ii A_jj)`.
/// Matrices formed as `G^T W G` in floating point are symmetric to ~1e-15; 1e-9 leaves room for
/// matrices assembled in other orders while catching transposition mistakes.
const SYMMETRY_RTOL: f64 = 1e-9;

/// Checks sizes, finiteness, symmetry and the cheap necessary conditions for `A` to be positive
/// semi-definite (`A_ii >= 0`; every 2x2 principal minor `A_ii A_jj - A_ij^2 >= 0`, so a zero
/// diagonal entry needs a zero row), and that no zero row has `b_i < 0` (unbounded objective).
/// A full PSD test would cost a Cholesky factorisation (`n^3 / 3`) and is not done.
pub(crate) fn validate_system(a: &[f64], b: &[f64], n: usize) -> Result<(), SolverError> {
    if n == 0 {
        return Err(SolverError::Empty);
    }
    let expected = n.checked_mul(n).ok_or(SolverError::DimensionMismatch {
        what: "A",
        expected: usize::MAX,
        got: a.len(),
    })?;
    check_len("A", a, expected)?;
    check_len("b", b, n)?;
    check_finite("A", a)?;
    check_finite("b", b)?;
    for i in 0..n {
        let a_ii = a[i * n + i];
        if a_ii < 0.0 {
            return Err(SolverError::NotPositiveSemidefinite {
                row: i,
                col: i,
                value: a_ii,
                reason: "negative diagonal entry",
            });
        }
        for j in (i + 1)..n {
            let (a_ij, a_ji) = (a[i * n + j], a[j * n + i]);
            let bound = (a_ii * a[j * n + j]).sqrt();
            if (a_ij - a_ji).abs() > SYMMETRY_RTOL * bound {
                return Err(SolverError::NotSymmetric {
                    row: i,
                    col: j,
                    a_row_col: a_ij,
                    a_col_row: a_ji,
                });
            }
            if a_ij.abs() > bound * (1.0 + SYMMETRY_RTOL) {
                return Err(SolverError::NotPositiveSemidefinite {
                    row: i,
                    col: j,
                    value: a_ij,
                    reason: "|A_ij| > sqrt(A_ii A_jj)",
                });
            }
        }
        if a_ii == 0.0 && b[i] < 0.0 {
            return Err(SolverError::Unbounded { index: i, b: b[i] });
        }
    }
    Ok(())
}

pub(crate) fn check_len(what: &'static str, v: &[f64], expected: usize) -> Result<(), SolverError> {
    if v.len() != expected {
        return Err(SolverError::DimensionMismatch {
            what,
            expected,
            got: v.len(),
        });
    }
    Ok(())
}

pub(crate) fn check_permutation(order: &[usize], n: usize) -> Result<(), SolverError> {
    let bad = |reason: String| Err(SolverError::BadOrder { n, reason });
    if order.len() != n {
        return bad(format!("it has {} entries", order.len()));
    }
    let mut seen = vec![false; n];
    for (r, &u) in order.iter().enumerate() {
        if u >= n {
            return bad(format!("entry {r} is {u}"));
        }
        if std::mem::replace(&mut seen[u], true) {
            return bad(format!("{u} appears twice (again at entry {r})"));
        }
    }
    Ok(())
}

/// An order of points (e.g. grid-cell centres) along a Hilbert curve over their bounding box,
/// so that points next to each other in the order are next to each other on the sky, for
/// [`QadpProblem::with_order`]. `result[r]` is the index of the `r`-th point; points that are
/// not finite go last, in their own order.
pub fn locality_order(points: &[[f64; 2]]) -> Vec<usize> {
    /// Cells of the curve per side: 2^16, far finer than any grid.
    const BITS: u32 = 16;
    let finite = |p: &[f64; 2]| p[0].is_finite() && p[1].is_finite();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points.iter().filter(|p| finite(p)) {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let side = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let cells = f64::from(1u32 << BITS);
    let key = |p: &[f64; 2]| -> u64 {
        if !finite(p) {
            return u64::MAX;
        }
        let cell = |k: usize| {
            let t = if side > 0.0 {
                (p[k] - lo[k]) / side
            } else {
                0.0
            };
            ((t * cells) as u32).min((1 << BITS) - 1)
        };
        hilbert_index(BITS, cell(0), cell(1))
    };
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| (key(&points[i]), i));
    order
}

/// Position of cell `(x, y)` along the Hilbert curve over `2^bits x 2^bits` cells.
fn hilbert_index(bits: u32, mut x: u32, mut y: u32) -> u64 {
    let mask = (1u32 << bits) - 1;
    let mut d = 0u64;
    let mut s = 1u32 << (bits - 1);
    while s > 0 {
        let rx = u32::from(x & s != 0);
        let ry = u32::from(y & s != 0);
        d += u64::from(s) * u64::from(s) * u64::from((3 * rx) ^ ry);
        // Turn the quadrant so that the curve inside it runs the standard way.
        if ry == 0 {
            if rx == 1 {
                (x, y) = (mask ^ x, mask ^ y);
            }
            (x, y) = (y, x);
        }
        s /= 2;
    }
    d
}

pub(crate) fn check_finite(what: &'static str, v: &[f64]) -> Result<(), SolverError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(SolverError::NonFinite {
            what,
            index,
            value: v[index],
        }),
        None => Ok(()),
    }
}

/// `phi(X) = 1/2 X^T A X + b^T X` in f64 (row-major `A`, `n * n`); for tests and reports.
pub fn objective(a: &[f64], b: &[f64], x: &[f64]) -> f64 {
    let n = b.len();
    let mut phi = 0.0;
    for i in 0..n {
        let row = &a[i * n..(i + 1) * n];
        let ax_i: f64 = row.iter().zip(x).map(|(a_ij, x_j)| a_ij * x_j).sum();
        phi += x[i] * (0.5 * ax_i + b[i]);
    }
    phi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_curve_visits_every_cell_once_in_unit_steps() {
        let bits = 4;
        let side = 1u32 << bits;
        let mut cell_at = vec![None; (side * side) as usize];
        for x in 0..side {
            for y in 0..side {
                let d = hilbert_index(bits, x, y) as usize;
                assert!(cell_at[d].replace((x, y)).is_none(), "index {d} twice");
            }
        }
        let cells: Vec<(u32, u32)> = cell_at.into_iter().map(|c| c.expect("all")).collect();
        for w in cells.windows(2) {
            let step = w[0].0.abs_diff(w[1].0) + w[0].1.abs_diff(w[1].1);
            assert_eq!(step, 1, "{:?} -> {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn locality_order_is_a_permutation_with_bad_points_last() {
        let mut points: Vec<[f64; 2]> = (0..64)
            .map(|k| [f64::from(k % 8) * 3.0 - 10.0, f64::from(k / 8) * 3.0 + 5.0])
            .collect();
        points.insert(5, [f64::NAN, 0.0]);
        let order = locality_order(&points);
        assert!(check_permutation(&order, 65).is_ok());
        assert_eq!(order[64], 5);
        // Neighbours along the order are neighbours on the 8 x 8 lattice.
        for w in order[..64].windows(2) {
            let (p, q) = (points[w[0]], points[w[1]]);
            let step = (p[0] - q[0]).abs() + (p[1] - q[1]).abs();
            assert!((step - 3.0).abs() < 1e-12, "{p:?} -> {q:?}");
        }
    }
}

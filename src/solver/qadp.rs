//! QADP: the multiplicative update of Sha, Saul & Lee (2002, "Multiplicative updates for
//! nonnegative quadratic programming in support vector machines", NIPS 15) for
//! `min phi(X) = 1/2 X^T A X + b^T X` subject to `X >= 0` ([method §5]):
//!
//! ```text
//! a = A+ X,  c = A- X,  X_i <- X_i * (-b_i + sqrt(b_i^2 + 4 a_i c_i)) / (2 a_i)
//! ```
//!
//! with `A+ = max(A, 0)`, `A- = max(-A, 0)` elementwise. Every step lowers `phi` (for a PSD `A`)
//! and keeps `X >= 0`; a component that is 0 stays 0, so the start must be strictly positive
//! wherever the solution may be positive.
//!
//! How it is made fast (see `kernel.rs` and `sweep.rs`):
//! - The update is invariant under the diagonal rescaling `X = D Y` (`a`, `c`, `b` of unknown
//!   `i` all scale by `d_i`) and under scaling `(a, c, b)` together, so the problem is stored as
//!   `M = D A D` with `D = diag(1 / sqrt(A_ii))` (unit diagonal, `|M_ij| <= 1`) and iterated
//!   on `Z = X sqrt(A_ii) / mu` with `mu = max_i |b_i| / sqrt(A_ii)`. This keeps every number
//!   near 1, which makes single precision storage safe for any units of `A` and `b`.
//! - Only the strict upper triangle of `M` is stored, in f32 (2 bytes per entry of `A`), and
//!   `a`, `c` come from one pass over it (each entry serves its row and its column); the
//!   diagonal is added exactly. The pass is bound by arithmetic: stretches of a row pair whose
//!   entries have one sign cost half, and [`QadpProblem::with_order`] stores neighbouring grid
//!   cells next to each other to make them long. Natively the rows are split into bands, one
//!   per thread, with two barriers per iteration.
//!
//! [method §5]: crate::method#5-the-solver-qadp

use super::sweep::{run_chunks, ScaledProblem};
use super::{
    check_finite, check_len, check_permutation, validate_system, Control, Progress, SolveOutcome,
    SolverError, SolverSettings,
};

/// A non-negative quadratic program prepared for QADP: build once, run from any start.
#[derive(Debug, Clone)]
pub struct QadpProblem {
    scaled: ScaledProblem,
}

impl QadpProblem {
    /// Prepares `min 1/2 x^T A x + b^T x, x >= 0` for `A` row-major `n * n` (symmetric PSD) and
    /// `b` of length `n`. Checks sizes, finiteness, symmetry and the cheap PSD conditions (see
    /// [`SolverError`]). Memory: about `2 n^2` bytes (the f32 upper triangle of the rescaled
    /// `A`).
    pub fn new(a: &[f64], b: &[f64], n: usize) -> Result<Self, SolverError> {
        Self::with_order(a, b, n, (0..n).collect())
    }

    /// As [`QadpProblem::new`], with the unknowns stored in the order `order` (a permutation of
    /// `0..n`): position `r` holds unknown `order[r]`. Inputs and results stay in the caller's
    /// order, and the iterates are the same up to the grouping of single-precision sums
    /// (~1e-7 relative). The order only sets the speed: an update costs less where
    /// neighbouring stored unknowns have entries of one sign, as neighbouring grid cells do
    /// (see [`locality_order`](super::locality_order)).
    pub fn with_order(
        a: &[f64],
        b: &[f64],
        n: usize,
        order: Vec<usize>,
    ) -> Result<Self, SolverError> {
        validate_system(a, b, n)?;
        check_permutation(&order, n)?;
        Ok(Self {
            scaled: ScaledProblem::new(a, b, n, order),
        })
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.scaled.n
    }

    /// Always false: a problem has at least one unknown.
    pub fn is_empty(&self) -> bool {
        self.scaled.n == 0
    }

    /// Runs `settings.iterations` QADP updates from `x0` (`>= 0`; entries that are 0 stay 0, so
    /// start strictly positive wherever the solution may be positive). `callback` is called on
    /// this thread at iteration 0, every `settings.report_every` updates and after the last
    /// one, and may cancel. Unknowns whose row of `A` is zero go to 0 if `b_i > 0` and keep
    /// their start value if `b_i = 0` (`b_i < 0` is rejected by [`QadpProblem::new`]).
    pub fn run(
        &self,
        x0: &[f64],
        settings: &SolverSettings,
        callback: &mut dyn FnMut(&Progress) -> Control,
    ) -> Result<SolveOutcome, SolverError> {
        settings.validate()?;
        check_len("x0", x0, self.scaled.n)?;
        check_finite("x0", x0)?;
        if let Some(index) = x0.iter().position(|&v| v < 0.0) {
            return Err(SolverError::NegativeStart {
                index,
                value: x0[index],
            });
        }
        run_chunks(&self.scaled, x0, settings, callback)
    }
}

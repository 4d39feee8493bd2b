//! QADP: the multiplicative update of Sha, Saul & Lee (2002, "Multiplicative updates for
//! nonnegative quadratic programming in support vector machines", NIPS 15) for
//! `min phi(X) = 1/2 X^T A X + b^T X` subject to `X >= 0` (METHOD.md section 5):
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

use super::sweep::{run_chunks, ScaledProblem};
use super::{check_finite, check_len, check_permutation, validate_system, SolverError};

/// Settings of a QADP run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QadpSettings {
    /// Number of multiplicative updates (default 8000, the paper's best; the iteration count is
    /// the regulariser: ~50000 over-fits towards the "point-source solution").
    pub iterations: usize,
    /// The callback sees the state every this many updates (default 100; must be >= 1).
    pub report_every: usize,
    /// Threads for the matrix passes; 0 (default) = automatic (all available natively, at
    /// least 128 rows per thread; always 1 on wasm32). A given count gives reproducible results;
    /// different counts group the single-precision sums differently, so their iterates agree
    /// to ~1e-7 relative.
    pub threads: usize,
}

impl Default for QadpSettings {
    fn default() -> Self {
        Self {
            iterations: 8000,
            report_every: 100,
            threads: 0,
        }
    }
}

impl QadpSettings {
    /// Checks `report_every >= 1`.
    pub fn validate(&self) -> Result<(), SolverError> {
        if self.report_every == 0 {
            return Err(SolverError::BadSetting {
                name: "report_every",
                value: 0,
                reason: "must be at least 1",
            });
        }
        Ok(())
    }
}

/// The state shown to the callback: `x` after `iteration` updates and `phi(x)`.
#[derive(Debug, Clone, Copy)]
pub struct Progress<'a> {
    /// Number of updates done so far.
    pub iteration: usize,
    /// `phi(x) = 1/2 x^T A x + b^T x`, from the sums of the single-precision pass (relative
    /// accuracy ~1e-7 of `x^T |A| x`).
    pub objective: f64,
    /// The current solution, in the units of the problem.
    pub x: &'a [f64],
}

/// What the callback asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    Continue,
    Cancel,
}

/// How a run ended (a run is not an error).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolveStatus {
    /// All requested iterations were done.
    Completed,
    /// The exact solver ([`super::minimise_exact`]) found the minimiser: every optimality
    /// condition holds.
    Converged,
    /// The callback returned [`Control::Cancel`]; the outcome is the state it was shown.
    Cancelled,
    /// The objective stopped being finite (only possible when `A` is not positive
    /// semi-definite or the objective is unbounded); the outcome is the last finite state.
    Diverged,
}

/// The result of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOutcome {
    /// The solution after `iterations` updates (all `>= 0`).
    pub x: Vec<f64>,
    /// Number of updates done.
    pub iterations: usize,
    /// `phi(x)` (see [`Progress::objective`]).
    pub objective: f64,
    pub status: SolveStatus,
}

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
        settings: &QadpSettings,
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

/// The run protocol the solvers share: the callback sees `x0` (iteration 0), the state every
/// `settings.report_every` steps and after the last one, and may cancel;
/// `advance(done, steps)` does `steps` more steps after `done` and returns the new `x` and
/// objective, or `None` when they stopped being finite (the run then ends as
/// [`SolveStatus::Diverged`] with the last finite state).
pub(crate) fn drive(
    x0: Vec<f64>,
    objective0: f64,
    settings: &QadpSettings,
    callback: &mut dyn FnMut(&Progress) -> Control,
    advance: &mut dyn FnMut(usize, usize) -> Option<(Vec<f64>, f64)>,
) -> Result<SolveOutcome, SolverError> {
    if !objective0.is_finite() {
        return Err(SolverError::NonFinite {
            what: "objective at x0",
            index: 0,
            value: objective0,
        });
    }
    let mut outcome = SolveOutcome {
        x: x0,
        iterations: 0,
        objective: objective0,
        status: SolveStatus::Completed,
    };
    loop {
        let progress = Progress {
            iteration: outcome.iterations,
            objective: outcome.objective,
            x: &outcome.x,
        };
        if callback(&progress) == Control::Cancel {
            outcome.status = SolveStatus::Cancelled;
            return Ok(outcome);
        }
        let done = outcome.iterations;
        if done >= settings.iterations {
            return Ok(outcome);
        }
        let steps = settings.report_every.min(settings.iterations - done);
        match advance(done, steps) {
            Some((x, objective)) if objective.is_finite() && x.iter().all(|v| v.is_finite()) => {
                outcome.x = x;
                outcome.objective = objective;
                outcome.iterations = done + steps;
            }
            _ => {
                outcome.status = SolveStatus::Diverged;
                return Ok(outcome);
            }
        }
    }
}

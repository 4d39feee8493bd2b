//! The settings every solver run takes: how far to go, how often to report, how many threads.

use super::SolverError;
use crate::error::BadFieldValue;

/// Settings of an iterative run, shared by every method (QADP, the accelerated gradient, the
/// exact solver's exchanges); `wslap reconstruct`'s `solver` block takes its defaults from here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolverSettings {
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
    /// Iterates kept in the outcome ([`super::SolveOutcome::iterates`]): at most this many, at
    /// iteration counts spaced evenly in log from the start to the last
    /// ([`iterate_schedule`](super::iterate_schedule)); default 0, none. Each costs `8 n`
    /// bytes; keeping them does not change the iterates (QADP and the accelerated gradient
    /// stop at each kept count, which costs one objective evaluation there). At most
    /// [`MAX_KEPT_ITERATES`].
    pub keep_iterates: usize,
}

/// Most iterations (and the largest report interval) of a run: 10^6, over 100 times the
/// paper's 8000 (50000 already over-fits), about a minute of QADP on the paper's system (1085
/// unknowns) and far more exchanges than the exact solver makes (tens). A larger count is a
/// typing mistake that would run for hours.
pub const MAX_ITERATIONS: usize = 1_000_000;

/// Most iterates a run keeps ([`SolverSettings::keep_iterates`]): 1000, about 8.7 MB for the
/// paper's 1085 unknowns.
pub const MAX_KEPT_ITERATES: usize = 1000;

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            iterations: 8000,
            report_every: 100,
            threads: 0,
            keep_iterates: 0,
        }
    }
}

impl SolverSettings {
    /// Checks `iterations <= MAX_ITERATIONS`, `1 <= report_every <= MAX_ITERATIONS` and
    /// `keep_iterates <= MAX_KEPT_ITERATES`.
    pub fn validate(&self) -> Result<(), SolverError> {
        if self.iterations > MAX_ITERATIONS {
            return Err(BadFieldValue::new(
                "solver.iterations",
                self.iterations as f64,
                "at most 10^6: the paper's QADP stops at 8000, the exact solver needs tens",
            )
            .into());
        }
        if !(1..=MAX_ITERATIONS).contains(&self.report_every) {
            return Err(BadFieldValue::new(
                "solver.report_every",
                self.report_every as f64,
                "must be 1 to 10^6",
            )
            .into());
        }
        if self.keep_iterates > MAX_KEPT_ITERATES {
            return Err(BadFieldValue::new(
                "solver.keep_iterates",
                self.keep_iterates as f64,
                "at most 1000",
            )
            .into());
        }
        Ok(())
    }
}

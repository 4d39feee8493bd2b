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
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            iterations: 8000,
            report_every: 100,
            threads: 0,
        }
    }
}

impl SolverSettings {
    /// Checks `report_every >= 1`.
    pub fn validate(&self) -> Result<(), SolverError> {
        if self.report_every == 0 {
            return Err(
                BadFieldValue::new("solver.report_every", 0.0, "must be at least 1").into(),
            );
        }
        Ok(())
    }
}

//! The run loop the iterative solvers share: reports to the caller, cancelling, and a stop
//! when the objective stops being finite.

use super::{Control, Progress, SolveOutcome, SolveStatus, SolverError, SolverSettings};

/// The run protocol the solvers share: the callback sees `x0` (iteration 0), the state every
/// `settings.report_every` steps and after the last one, and may cancel;
/// `advance(done, steps)` does `steps` more steps after `done` and returns the new `x` and
/// objective, or `None` when they stopped being finite (the run then ends as
/// [`SolveStatus::Diverged`] with the last finite state).
pub(crate) fn drive(
    x0: Vec<f64>,
    objective0: f64,
    settings: &SolverSettings,
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

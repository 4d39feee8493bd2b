//! The run loop the iterative solvers share: reports to the caller, cancelling, the iterates
//! kept on the way, and a stop when the objective stops being finite.

use super::{Control, Iterate, Progress, SolveOutcome, SolveStatus, SolverError, SolverSettings};

/// The iteration counts at which a run of `iterations` keeps its iterate when asked for `keep`
/// of them ([`SolverSettings::keep_iterates`]): the start (0), then counts spaced evenly in
/// log from 1 to `iterations`, each at least one after the one before, `iterations` last.
/// Increasing, at most `keep` of them (fewer when `iterations` is small); empty for `keep = 0`.
pub fn iterate_schedule(iterations: usize, keep: usize) -> Vec<usize> {
    let mut counts = match keep {
        0 => return Vec::new(),
        1 => return vec![iterations],
        _ => vec![0],
    };
    // `keep - 1` counts after the start, the first at 1 and the last at `iterations`.
    let m = keep - 1;
    let top = iterations as f64;
    for k in 0..m {
        let t = if m == 1 {
            top
        } else {
            top.powf(k as f64 / (m - 1) as f64)
        };
        let prev = counts.last().copied().unwrap_or(0);
        let c = (t.round() as usize).max(prev + 1).min(iterations);
        if c > prev {
            counts.push(c);
        }
    }
    if counts.last() != Some(&iterations) {
        // Only when the rounding ran short of the end: it replaces the last count.
        counts.pop();
        counts.push(iterations);
    }
    counts
}

/// Keeps the iterates of a run at the counts of [`iterate_schedule`].
pub(crate) struct Recorder {
    schedule: Vec<usize>,
    kept: Vec<Iterate>,
}

impl Recorder {
    pub(crate) fn new(iterations: usize, keep: usize) -> Self {
        Self {
            schedule: iterate_schedule(iterations, keep),
            kept: Vec::new(),
        }
    }

    /// The first count of the schedule after `done`, if any.
    pub(crate) fn next_after(&self, done: usize) -> Option<usize> {
        self.schedule.iter().copied().find(|&c| c > done)
    }

    /// Keeps `x` if `iteration` is a count of the schedule.
    pub(crate) fn offer(&mut self, iteration: usize, objective: f64, x: &[f64]) {
        if self.schedule.binary_search(&iteration).is_ok() {
            self.kept.push(Iterate {
                iteration,
                objective,
                x: x.to_vec(),
            });
        }
    }

    /// The iterates kept, ending with `outcome`'s (added if the run ended off the schedule:
    /// cancelled or diverged; it then stands in for the scheduled counts not reached).
    pub(crate) fn finish(mut self, outcome: &SolveOutcome) -> Vec<Iterate> {
        if self.schedule.is_empty() {
            return Vec::new();
        }
        if self.kept.last().map(|i| i.iteration) != Some(outcome.iterations) {
            self.kept.push(Iterate {
                iteration: outcome.iterations,
                objective: outcome.objective,
                x: outcome.x.clone(),
            });
        }
        self.kept
    }
}

/// The run protocol the solvers share: the callback sees `x0` (iteration 0), the state every
/// `settings.report_every` steps and after the last one, and may cancel;
/// `advance(done, steps)` does `steps` more steps after `done` and returns the new `x` and
/// objective, or `None` when they stopped being finite (the run then ends as
/// [`SolveStatus::Diverged`] with the last finite state). The iterates at the counts of
/// [`iterate_schedule`] are kept: the steps are split there, which changes no iterate.
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
    let mut recorder = Recorder::new(settings.iterations, settings.keep_iterates);
    let mut outcome = SolveOutcome {
        x: x0,
        iterations: 0,
        objective: objective0,
        status: SolveStatus::Completed,
        iterates: Vec::new(),
    };
    let every = settings.report_every;
    let end = |mut outcome: SolveOutcome, recorder: Recorder| {
        outcome.iterates = recorder.finish(&outcome);
        Ok(outcome)
    };
    loop {
        let done = outcome.iterations;
        recorder.offer(done, outcome.objective, &outcome.x);
        if done % every == 0 || done >= settings.iterations {
            let progress = Progress {
                iteration: done,
                objective: outcome.objective,
                x: &outcome.x,
            };
            if callback(&progress) == Control::Cancel {
                outcome.status = SolveStatus::Cancelled;
                return end(outcome, recorder);
            }
        }
        if done >= settings.iterations {
            return end(outcome, recorder);
        }
        let report = ((done / every + 1) * every).min(settings.iterations);
        let stop = recorder.next_after(done).map_or(report, |c| c.min(report));
        let steps = stop - done;
        match advance(done, steps) {
            Some((x, objective)) if objective.is_finite() && x.iter().all(|v| v.is_finite()) => {
                outcome.x = x;
                outcome.objective = objective;
                outcome.iterations = stop;
            }
            _ => {
                outcome.status = SolveStatus::Diverged;
                return end(outcome, recorder);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_is_increasing_bounded_and_ends_at_the_last_iteration() {
        for (iterations, keep) in [(3000, 41), (8000, 40), (10, 40), (0, 5), (1, 3), (100, 2)] {
            let s = iterate_schedule(iterations, keep);
            assert!(s.len() <= keep, "{iterations}, {keep}: {s:?}");
            assert_eq!(s.last(), Some(&iterations), "{s:?}");
            assert!(s.windows(2).all(|w| w[0] < w[1]), "{s:?}");
        }
        assert_eq!(iterate_schedule(10, 40), (0..=10).collect::<Vec<_>>());
        assert!(iterate_schedule(5, 0).is_empty());
        let s = iterate_schedule(3000, 41);
        assert_eq!((s.len(), s[0], s[1]), (41, 0, 1));
        // Log-spaced: the middle of the list is near sqrt(3000) ~ 55, not 1500.
        assert!((30..120).contains(&s[20]), "{s:?}");
    }
}

//! What a run shows its caller while it goes (progress, and the caller's answer) and how it
//! ended.

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

/// `Cancel` is a break: the standard library's way of saying "stop" to a loop, used by code
/// that does not know the solver (`threads::map_reporting`).
impl From<std::ops::ControlFlow<()>> for Control {
    fn from(flow: std::ops::ControlFlow<()>) -> Self {
        match flow {
            std::ops::ControlFlow::Continue(()) => Control::Continue,
            std::ops::ControlFlow::Break(()) => Control::Cancel,
        }
    }
}

impl From<Control> for std::ops::ControlFlow<()> {
    fn from(control: Control) -> Self {
        match control {
            Control::Continue => std::ops::ControlFlow::Continue(()),
            Control::Cancel => std::ops::ControlFlow::Break(()),
        }
    }
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
    /// The exact reference solver ([`super::nnqp_exact`]) met a free set on which `A` is
    /// numerically singular and cannot go on; the outcome is the last feasible state.
    Singular,
}

impl SolveStatus {
    /// The status as `summary.json` and the app write it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Completed => "Completed",
            Self::Converged => "Converged",
            Self::Cancelled => "Cancelled",
            Self::Diverged => "Diverged",
            Self::Singular => "Singular",
        }
    }
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
    /// The iterates kept on the way ([`super::SolverSettings::keep_iterates`]), at increasing
    /// iteration counts; the last is the outcome itself. Empty when none were asked for.
    pub iterates: Vec<Iterate>,
}

/// The solution at one iteration of a run, kept for showing how the run went.
#[derive(Debug, Clone, PartialEq)]
pub struct Iterate {
    /// Number of updates done.
    pub iteration: usize,
    /// `phi(x)` there (see [`Progress::objective`]).
    pub objective: f64,
    /// The solution there, in the units of the problem.
    pub x: Vec<f64>,
}

//! The exact minimiser of `phi(X) = 1/2 X^T A X + b^T X` subject to `X >= 0` for a positive
//! definite `A`, by block principal pivoting (Júdice & Pires 1994, Comput. Oper. Res. 21, 587;
//! the form of Kim & Park 2011, SIAM J. Sci. Comput. 33, 3261).
//!
//! The minimiser is the one point that satisfies the Karush–Kuhn–Tucker conditions
//!
//! ```text
//! y = A X + b,   X >= 0,   y >= 0,   X_i y_i = 0 for every i,
//! ```
//!
//! so it is fixed by which unknowns are free (`y_i = 0`) and which sit at zero (`X_i = 0`).
//! Each step guesses that partition, solves `A_FF X_F = -b_F` on the free set `F` exactly
//! (Cholesky), and moves every unknown that breaks a condition (`X_i < 0` on `F`, `y_i < 0`
//! off it) to the other side. When a full exchange does not shrink the number of broken
//! conditions three times running, one unknown at a time is moved (the largest index), which
//! makes the method finite. There is no step size and no start: the answer is the minimiser,
//! whatever the start, to the accuracy of the factorisation.
//!
//! Used with a regularised system (the regulariser makes `A` positive definite). The problem
//! is solved Jacobi-scaled (`D A D` with unit diagonal) with [`RIDGE`] on the diagonal, which
//! keeps every factorisation defined when the data leave directions unconstrained; unknowns
//! whose row of `A` is zero are fixed as in QADP.

use super::independence::cholesky_in_place;
use super::run::Recorder;
use super::{check_len, validate_system, SolverError};
use super::{Control, Progress, SolveOutcome, SolveStatus};

/// Added to the unit diagonal of the scaled matrix.
pub const RIDGE: f64 = 1e-12;
/// A scaled condition is broken when it is below `-BREAK_TOL` (the scaled `b` is at most 1).
const BREAK_TOL: f64 = 1e-10;
/// Full exchanges allowed without progress before single exchanges (Kim & Park's `p`).
const FULL_EXCHANGE_TRIES: usize = 3;

/// Minimises `phi` over `X >= 0` exactly (module documentation), at most `max_steps`
/// factorisations. `callback` sees the start `X = 0`, then each step's iterate (its infeasible entries clipped to 0)
/// and may cancel. The status is [`SolveStatus::Converged`] when every condition holds,
/// [`SolveStatus::Completed`] when `max_steps` ran out first (the outcome is then the last
/// step, clipped). Up to `keep_iterates` of the steps' iterates are kept in the outcome, as
/// [`SolverSettings::keep_iterates`](super::SolverSettings::keep_iterates) says (the schedule
/// is over `max_steps`, so all of a run of a few tens of steps are kept when it allows).
pub fn minimise_exact(
    a: &[f64],
    b: &[f64],
    n: usize,
    max_steps: usize,
    keep_iterates: usize,
    callback: &mut dyn FnMut(&Progress) -> Control,
) -> Result<SolveOutcome, SolverError> {
    let mut recorder = Recorder::new(max_steps, keep_iterates);
    let mut outcome = exact_steps(a, b, n, max_steps, &mut recorder, callback)?;
    outcome.iterates = recorder.finish(&outcome);
    Ok(outcome)
}

/// [`minimise_exact`] without the final iterate kept.
fn exact_steps(
    a: &[f64],
    b: &[f64],
    n: usize,
    max_steps: usize,
    recorder: &mut Recorder,
    callback: &mut dyn FnMut(&Progress) -> Control,
) -> Result<SolveOutcome, SolverError> {
    validate_system(a, b, n)?;
    check_len("b", b, n)?;
    let d: Vec<f64> = (0..n)
        .map(|i| match a[i * n + i] {
            v if v > 0.0 => 1.0 / v.sqrt(),
            _ => 0.0,
        })
        .collect();
    // Scaled right-hand side c = D b / mu, so that max |c_i| = 1.
    let mu = (0..n)
        .map(|i| (d[i] * b[i]).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let c: Vec<f64> = (0..n).map(|i| d[i] * b[i] / mu).collect();
    let m = |i: usize, j: usize| a[i * n + j] * d[i] * d[j];
    // Unknowns with a zero row stay at 0 (their b_i >= 0 is checked by validate_system).
    let active: Vec<usize> = (0..n).filter(|&i| d[i] > 0.0).collect();
    let mut free = vec![false; n];
    for &i in &active {
        free[i] = true;
    }
    let mut z = vec![0.0; n];
    let mut y = vec![0.0; n];
    let mut best_broken = usize::MAX;
    let mut tries = FULL_EXCHANGE_TRIES;
    let mut status = SolveStatus::Completed;
    let mut steps = 0;
    let to_x = |z: &[f64]| -> Vec<f64> { (0..n).map(|i| z[i].max(0.0) * d[i] * mu).collect() };
    // The run protocol of the other solvers: the callback sees the start (here X = 0) first.
    let zero = vec![0.0; n];
    let start = Progress {
        iteration: 0,
        objective: 0.0,
        x: &zero,
    };
    recorder.offer(0, 0.0, &zero);
    if callback(&start) == Control::Cancel {
        return Ok(SolveOutcome {
            x: zero,
            iterations: 0,
            objective: 0.0,
            status: SolveStatus::Cancelled,
            iterates: Vec::new(),
        });
    }
    while steps < max_steps {
        steps += 1;
        let f: Vec<usize> = active.iter().copied().filter(|&i| free[i]).collect();
        solve_free(&f, &m, &c, &mut z)?;
        for &i in &active {
            if !free[i] {
                z[i] = 0.0;
            }
        }
        // y = M z + c off the free set (0 on it, up to rounding).
        for &i in &active {
            y[i] = if free[i] {
                0.0
            } else {
                f.iter().map(|&j| m(i, j) * z[j]).sum::<f64>() + c[i]
            };
        }
        let broken: Vec<usize> = active
            .iter()
            .copied()
            .filter(|&i| {
                if free[i] {
                    z[i] < -BREAK_TOL
                } else {
                    y[i] < -BREAK_TOL
                }
            })
            .collect();
        let x = to_x(&z);
        let progress = Progress {
            iteration: steps,
            objective: super::objective(a, b, &x),
            x: &x,
        };
        recorder.offer(steps, progress.objective, &x);
        if callback(&progress) == Control::Cancel {
            return Ok(SolveOutcome {
                objective: progress.objective,
                x,
                iterations: steps,
                status: SolveStatus::Cancelled,
                iterates: Vec::new(),
            });
        }
        if broken.is_empty() {
            status = SolveStatus::Converged;
            break;
        }
        if broken.len() < best_broken {
            best_broken = broken.len();
            tries = FULL_EXCHANGE_TRIES;
            broken.iter().for_each(|&i| free[i] = !free[i]);
        } else if tries > 0 {
            tries -= 1;
            broken.iter().for_each(|&i| free[i] = !free[i]);
        } else if let Some(&i) = broken.last() {
            free[i] = !free[i];
        }
    }
    let x = to_x(&z);
    Ok(SolveOutcome {
        objective: super::objective(a, b, &x),
        x,
        iterations: steps,
        status,
        iterates: Vec::new(),
    })
}

/// `z_F = -M_FF^-1 c_F` (with [`RIDGE`] on the diagonal) into `z` at the indices `f`.
fn solve_free(
    f: &[usize],
    m: &dyn Fn(usize, usize) -> f64,
    c: &[f64],
    z: &mut [f64],
) -> Result<(), SolverError> {
    let k = f.len();
    if k == 0 {
        return Ok(());
    }
    let mut l = vec![0.0; k * k];
    for r in 0..k {
        for s in 0..=r {
            l[r * k + s] = m(f[r], f[s]) + if r == s { RIDGE } else { 0.0 };
        }
    }
    if !cholesky_in_place(&mut l, k) {
        return Err(SolverError::NotPositiveSemidefinite {
            row: f[0],
            col: f[0],
            value: 0.0,
            reason: "a Cholesky pivot of the free set is not positive",
        });
    }
    // L u = -c_F, then L^T z = u.
    let mut u: Vec<f64> = f.iter().map(|&i| -c[i]).collect();
    for r in 0..k {
        let row = &l[r * k..r * k + r];
        let s: f64 = row.iter().zip(&u[..r]).map(|(a, b)| a * b).sum();
        u[r] = (u[r] - s) / l[r * k + r];
    }
    for r in (0..k).rev() {
        let mut s = u[r];
        for q in r + 1..k {
            s -= l[q * k + r] * u[q];
        }
        u[r] = s / l[r * k + r];
    }
    for (&i, v) in f.iter().zip(u) {
        z[i] = v;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::nnqp_exact;

    fn never(_: &Progress) -> Control {
        Control::Continue
    }

    /// A random positive definite system with a minimiser that has several zeros.
    fn system(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut s = seed;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let rows = n + 3;
        let g: Vec<f64> = (0..rows * n).map(|_| rnd()).collect();
        let t: Vec<f64> = (0..rows).map(|_| rnd()).collect();
        let mut a = vec![0.0; n * n];
        let mut b = vec![0.0; n];
        for r in 0..rows {
            for i in 0..n {
                b[i] -= g[r * n + i] * t[r];
                for j in 0..n {
                    a[i * n + j] += g[r * n + i] * g[r * n + j];
                }
            }
        }
        (a, b)
    }

    #[test]
    fn agrees_with_the_active_set_reference() {
        for seed in 1..6 {
            let n = 40;
            let (a, b) = system(n, seed);
            let exact = nnqp_exact(&a, &b, n).unwrap().x;
            let out = minimise_exact(&a, &b, n, 500, 0, &mut never).unwrap();
            assert_eq!(out.status, SolveStatus::Converged);
            let zeros = exact.iter().filter(|&&v| v == 0.0).count();
            assert!(zeros > 3, "the test needs active bounds ({zeros})");
            for (p, q) in out.x.iter().zip(&exact) {
                assert!((p - q).abs() < 1e-7 * (1.0 + q.abs()), "{p} vs {q}");
            }
        }
    }

    #[test]
    fn a_zero_row_stays_at_zero() {
        let a = vec![2.0, 0.0, 0.0, 0.0];
        let b = vec![-2.0, 0.0];
        let out = minimise_exact(&a, &b, 2, 10, 0, &mut never).unwrap();
        assert_eq!(out.status, SolveStatus::Converged);
        assert!((out.x[0] - 1.0).abs() < 1e-9 && out.x[1] == 0.0);
    }
}

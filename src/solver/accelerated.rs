//! An accelerated projected gradient for the same problem as QADP,
//! `min phi(X) = 1/2 X^T A X + b^T X` subject to `X >= 0`: FISTA (Beck & Teboulle 2009, SIAM
//! J. Imaging Sci. 2, 183) with the gradient restart of O'Donoghue & Candès (2015, Found.
//! Comput. Math. 15, 715), on the Jacobi-scaled problem.
//!
//! QADP (the paper's solver) is stopped early on purpose: its iteration count is the
//! regulariser. This solver is for the other question, what the data's best fit is: it goes
//! much further per iteration (on the paper's simulated cluster it reaches in 2000 iterations
//! a chi2 that QADP has not reached after 50000), so its answer approaches the minimiser of the
//! objective itself, the over-fitting "point-source solution" of the paper, which `wslap paper`
//! uses to show how far the early-stopped answer is from it.
//!
//! - Scaling: `X = D Y` with `D = diag(1 / sqrt(A_ii))` makes the Hessian `M = D A D` unit on the
//!   diagonal, which shrinks its spread of curvatures (the step is `1 / L`, `L` the largest
//!   eigenvalue of `M`, from power iteration). `M` is never formed: `M y = D (A (D y))`.
//! - Step: `Y+ = max(0, V - (M V + D b) / L)`, `V` the extrapolated point; the momentum restarts
//!   when the step goes against the previous one (`(V - Y+) . (Y+ - Y) > 0`).
//! - Unknowns whose row of `A` is zero do not move the objective: they go to 0 if `b_i > 0` and
//!   keep their start value if `b_i = 0`, as in QADP.
//!
//! One product with `A` (f64, the whole matrix) per iteration; natively its rows are shared
//! between threads, on wasm32 it runs on one.

use super::run::drive;
use super::{check_finite, check_len, validate_system, SolverError};
use super::{Control, Progress, SolveOutcome, SolverSettings};

/// Power-iteration steps for the largest eigenvalue of the scaled Hessian.
const POWER_STEPS: usize = 60;
/// The step is `1 / (L * STEP_SAFETY)`: power iteration approaches `L` from below.
const STEP_SAFETY: f64 = 1.02;
/// Below this many rows per thread a product with `A` stays on one thread.
const MIN_ROWS_PER_THREAD: usize = 128;

/// Runs `settings.iterations` steps of the accelerated projected gradient from `x0 >= 0` (see
/// the module documentation), with the same reports, cancelling and outcome as
/// [`super::QadpProblem::run`]. The objective shown is exact (f64).
pub fn accelerated_gradient(
    a: &[f64],
    b: &[f64],
    n: usize,
    x0: &[f64],
    settings: &SolverSettings,
    callback: &mut dyn FnMut(&Progress) -> Control,
) -> Result<SolveOutcome, SolverError> {
    validate_system(a, b, n)?;
    settings.validate()?;
    check_len("x0", x0, n)?;
    check_finite("x0", x0)?;
    if let Some(index) = x0.iter().position(|&v| v < 0.0) {
        return Err(SolverError::NegativeStart {
            index,
            value: x0[index],
        });
    }
    let threads = crate::threads::count(settings.threads, n, MIN_ROWS_PER_THREAD);
    // d_i = 1 / sqrt(A_ii); 0 marks an unknown with a zero row (fixed).
    let d: Vec<f64> = (0..n)
        .map(|i| {
            let a_ii = a[i * n + i];
            if a_ii > 0.0 {
                1.0 / a_ii.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let fixed: Vec<Option<f64>> = (0..n)
        .map(|i| (d[i] == 0.0).then(|| if b[i] > 0.0 { 0.0 } else { x0[i] }))
        .collect();
    let db: Vec<f64> = d.iter().zip(b).map(|(d, b)| d * b).collect();
    let mut scratch = vec![0.0; n];
    // M y = D A D y (entries of fixed unknowns are 0 in y and in the result).
    let mut m_times = |y: &[f64], out: &mut [f64]| {
        for ((s, y), d) in scratch.iter_mut().zip(y).zip(&d) {
            *s = d * y;
        }
        mat_vec(a, n, &scratch, out, threads);
        for (o, d) in out.iter_mut().zip(&d) {
            *o *= d;
        }
    };
    let l = largest_eigenvalue(n, &d, &mut m_times) * STEP_SAFETY;
    let to_x = |y: &[f64], x: &mut [f64]| {
        for i in 0..n {
            x[i] = fixed[i].unwrap_or(y[i] * d[i]);
        }
    };
    let objective_at = |x: &[f64]| super::objective(a, b, x);

    // Y of the free unknowns; fixed ones carry 0 here and their value in X.
    let mut y: Vec<f64> = (0..n)
        .map(|i| if d[i] > 0.0 { x0[i] / d[i] } else { 0.0 })
        .collect();
    let mut v = y.clone();
    let mut y_next = vec![0.0; n];
    let mut grad = vec![0.0; n];
    let mut t = 1.0f64;
    let mut x_start = vec![0.0; n];
    to_x(&y, &mut x_start);
    let objective0 = objective_at(&x_start);
    drive(x_start, objective0, settings, callback, &mut |_, steps| {
        for _ in 0..steps {
            m_times(&v, &mut grad);
            let mut against = 0.0;
            for i in 0..n {
                y_next[i] = if d[i] > 0.0 {
                    (v[i] - (grad[i] + db[i]) / l).max(0.0)
                } else {
                    0.0
                };
                against += (v[i] - y_next[i]) * (y_next[i] - y[i]);
            }
            let t_next = if against > 0.0 {
                1.0
            } else {
                0.5 * (1.0 + (1.0 + 4.0 * t * t).sqrt())
            };
            let beta = if against > 0.0 {
                0.0
            } else {
                (t - 1.0) / t_next
            };
            for i in 0..n {
                v[i] = y_next[i] + beta * (y_next[i] - y[i]);
            }
            std::mem::swap(&mut y, &mut y_next);
            t = t_next;
        }
        let mut x = vec![0.0; n];
        to_x(&y, &mut x);
        let objective = objective_at(&x);
        Some((x, objective))
    })
}

/// `out = A x` for `A` row-major `n x n`, the rows shared between `threads` threads.
fn mat_vec(a: &[f64], n: usize, x: &[f64], out: &mut [f64], threads: usize) {
    let rows = |first: usize, out: &mut [f64]| {
        for (k, o) in out.iter_mut().enumerate() {
            let row = &a[(first + k) * n..(first + k + 1) * n];
            *o = dot(row, x);
        }
    };
    let per = n.div_ceil(threads.max(1)).max(1);
    let chunks: Vec<(usize, &mut [f64])> = out.chunks_mut(per).enumerate().collect();
    crate::threads::for_each(chunks, threads, |(k, chunk)| rows(k * per, chunk));
}

/// `sum_j a_j x_j` with eight running sums (so that it vectorises).
fn dot(a: &[f64], x: &[f64]) -> f64 {
    let mut sums = [0.0; 8];
    let (a8, a_rest) = a.split_at(a.len() - a.len() % 8);
    let (x8, x_rest) = x.split_at(a8.len());
    for (ac, xc) in a8.chunks_exact(8).zip(x8.chunks_exact(8)) {
        for k in 0..8 {
            sums[k] += ac[k] * xc[k];
        }
    }
    let rest: f64 = a_rest.iter().zip(x_rest).map(|(a, x)| a * x).sum();
    sums.iter().sum::<f64>() + rest
}

/// The largest eigenvalue of the (PSD) scaled Hessian by power iteration from the free
/// unknowns' all-ones vector; at least a tiny positive number.
fn largest_eigenvalue(n: usize, d: &[f64], m_times: &mut dyn FnMut(&[f64], &mut [f64])) -> f64 {
    let mut u: Vec<f64> = d.iter().map(|&d| if d > 0.0 { 1.0 } else { 0.0 }).collect();
    let mut mu = vec![0.0; n];
    let mut lambda = 0.0;
    for _ in 0..POWER_STEPS {
        let norm = u.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 {
            break;
        }
        u.iter_mut().for_each(|v| *v /= norm);
        m_times(&u, &mut mu);
        lambda = u.iter().zip(&mu).map(|(u, m)| u * m).sum::<f64>();
        std::mem::swap(&mut u, &mut mu);
    }
    lambda.max(f64::MIN_POSITIVE)
}

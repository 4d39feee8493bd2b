//! Benchmark of the solver stage against `qadp_numpy.py` (BENCHMARKS.md): the same synthetic
//! WSLAP-shaped system (a grid of cells, one galaxy-scaling column, 2 x 30 beta columns), the
//! same stages and the same start.
//!
//! ```text
//! cargo bench --bench qadp_bench -- [GRID_N] [N_PIXELS] [ITERATIONS] [THREADS]
//! ```
//! (defaults 32 4000 8000 0; THREADS 0 = automatic). The values come from a different random
//! generator than NumPy's, which does not change the timings. The solver stores the cells
//! along a Hilbert curve, as `wslap reconstruct` does; `QADP_NO_ORDER=1` keeps the generator's
//! row-major order instead (slower: shorter stretches of one sign in the matrix).

use std::time::Instant;

use wslap::{gram_weighted, locality_order, Control, QadpProblem, SolverSettings};

#[path = "../tests/common/rng.rs"]
mod rng;
use rng::Rng;

/// Side of the cell grid in arcsec, as in qadp_numpy.py.
const FOV: f64 = 200.0;

/// Centres of the `n_grid x n_grid` cells over [`FOV`], row-major (cell `row * n_grid + column`).
fn cell_centres(n_grid: usize) -> Vec<[f64; 2]> {
    let g = |k: usize| (k as f64 + 0.5) / n_grid as f64 * FOV - FOV / 2.0;
    (0..n_grid * n_grid)
        .map(|cell| [g(cell % n_grid), g(cell / n_grid)])
        .collect()
}

/// `(Gamma, Theta, W)` as in `synthetic()` of qadp_numpy.py (fov 200 arcsec, Gaussian-smoothed
/// point-mass deflection per cell, pixels uniform in +-60 arcsec, 30 sources).
fn synthetic(n_grid: usize, n_pix: usize, n_src: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = Rng(1);
    let centres = cell_centres(n_grid);
    let nc = n_grid * n_grid;
    let sigma = FOV / n_grid as f64;
    let cols = nc + 1 + 2 * n_src;
    let px: Vec<f64> = (0..n_pix).map(|_| rng.uniform() * 120.0 - 60.0).collect();
    let py: Vec<f64> = (0..n_pix).map(|_| rng.uniform() * 120.0 - 60.0).collect();
    let mut gamma = vec![0.0; 2 * n_pix * cols];
    for p in 0..n_pix {
        let src = (rng.next_u64() % n_src as u64) as usize;
        for (cell, [cx, cy]) in centres.iter().enumerate() {
            let (dx, dy) = (px[p] - cx, py[p] - cy);
            let r2 = dx * dx + dy * dy + 1e-12;
            let f = (1.0 - (-r2 / (2.0 * sigma * sigma)).exp()) / r2;
            gamma[p * cols + cell] = f * dx;
            gamma[(n_pix + p) * cols + cell] = f * dy;
        }
        gamma[p * cols + nc] = rng.normal();
        gamma[(n_pix + p) * cols + nc] = rng.normal();
        gamma[p * cols + nc + 1 + src] = 1.0;
        gamma[(n_pix + p) * cols + nc + 1 + n_src + src] = 1.0;
    }
    let theta: Vec<f64> = px.iter().chain(&py).map(|v| v + 100.0).collect();
    (gamma, theta, vec![1.0; 2 * n_pix])
}

fn main() {
    // `cargo bench` adds `--bench` to the arguments: skip flags.
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .map(|a| {
            a.parse()
                .expect("arguments are GRID_N N_PIXELS ITERATIONS THREADS")
        })
        .collect();
    let arg = |k: usize, default: usize| args.get(k).copied().unwrap_or(default);
    let (n_grid, n_pix, iterations, threads) = (arg(0, 32), arg(1, 4000), arg(2, 8000), arg(3, 0));
    // THREADS holds for every stage, the normal matrix included.
    wslap::with_thread_limit(threads, || run(n_grid, n_pix, iterations, threads));
}

fn run(n_grid: usize, n_pix: usize, iterations: usize, threads: usize) {
    let t0 = Instant::now();
    let (gamma, theta, w) = synthetic(n_grid, n_pix, 30);
    let t1 = Instant::now();
    let n = gamma.len() / w.len();
    let (a, b) = gram_weighted(&gamma, w.len(), n, &w, &theta).expect("valid system");
    let t_gram = t1.elapsed();
    let problem = if std::env::var_os("QADP_NO_ORDER").is_some() {
        QadpProblem::new(&a, &b, n)
    } else {
        // As `wslap reconstruct` does: the cells along a Hilbert curve, the other columns after.
        let mut order = locality_order(&cell_centres(n_grid));
        order.extend(n_grid * n_grid..n);
        QadpProblem::with_order(&a, &b, n, order)
    }
    .expect("valid problem");
    let t2 = Instant::now();
    let settings = SolverSettings {
        iterations,
        report_every: 100,
        threads,
        keep_iterates: 0,
    };
    let outcome = problem
        .run(&vec![1e-3; n], &settings, &mut |_| Control::Continue)
        .expect("valid start");
    let t3 = Instant::now();
    let exact = wslap::quadratic_objective(&a, &b, &outcome.x);
    println!(
        "unknowns={n} rows={} load_or_build={:.3}s normal_matrix={:.3}s (gram {:.3}s) \
         qadp_{iterations}={:.3}s per_iteration={:.1}us objective={:.9e} (f64 recomputed {:.9e}) \
         total={:.3}s",
        w.len(),
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
        t_gram.as_secs_f64(),
        (t3 - t2).as_secs_f64(),
        (t3 - t2).as_secs_f64() / iterations.max(1) as f64 * 1e6,
        outcome.objective,
        exact,
        (t3 - t0).as_secs_f64(),
    );
}

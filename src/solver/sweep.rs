//! The QADP iteration on the rescaled problem, split into bands of rows (one per thread).
//!
//! Each iteration: every band loads the whole iterate `Z`, makes one pass over its rows of the
//! stored upper triangle (row sums for its rows, column sums for the rows below), publishes the
//! column sums that belong to later bands, and waits (barrier 1); it then completes `a`, `c` of
//! its rows with the earlier bands' column sums and the diagonal, writes its rows of the next
//! `Z`, and waits (barrier 2). `Z` lives in two buffers (version `k` in buffer `k % 2`), so a
//! buffer is written only after everyone has read it. The callback runs on the calling thread
//! between chunks of `report_every` updates, when no other thread is running.

use std::ops::Range;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use super::kernel::{band_pass, PassSums, UpperTriangle};
use super::qadp::{drive, Control, Progress, QadpSettings, SolveOutcome};
use super::SolverError;

/// Entries of the unit-diagonal matrix below this are stored as 0: they change a sum by less
/// than `1e-15 sum_j x_j`, far below f32 rounding, and could give subnormal (slow) products.
const MATRIX_FLUSH: f64 = 1e-15;
/// Components of `Z` below this fraction of `max Z` enter the f32 pass as 0 (same reason; the
/// diagonal term, the one that matters for such a component, is added exactly in f64).
const VECTOR_FLUSH: f64 = 1e-20;
/// Fewer rows than this per thread are not worth a thread.
const MIN_ROWS_PER_THREAD: usize = 128;
/// Upper bound on automatic threads (memory bandwidth saturates beyond this).
const MAX_THREADS: usize = 8;

/// `M = D A D` (strict upper triangle in f32; the diagonal, 1 or 0, apart), `b_hat = D b / mu`
/// and the maps between `X` and `Z = X sqrt(A_ii) / mu`; `phi(X) = mu^2 phi_M(Z)`.
#[derive(Debug, Clone)]
pub(crate) struct ScaledProblem {
    pub(crate) n: usize,
    upper: UpperTriangle,
    diag: Vec<f64>,
    b_hat: Vec<f64>,
    /// `Z_i = X_i * to_scaled[i]`.
    to_scaled: Vec<f64>,
    /// `mu^2`.
    objective_scale: f64,
}

impl ScaledProblem {
    /// Assumes [`super::validate_system`] passed.
    pub(crate) fn new(a: &[f64], b: &[f64], n: usize) -> Self {
        let a_ii = |i: usize| a[i * n + i];
        let d: Vec<f64> = (0..n)
            .map(|i| {
                if a_ii(i) > 0.0 {
                    1.0 / a_ii(i).sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        let mu = b
            .iter()
            .zip(&d)
            .map(|(b_i, d_i)| (b_i * d_i).abs())
            .fold(0.0, f64::max);
        let mu = if mu > 0.0 { mu } else { 1.0 };
        let upper = UpperTriangle::new(n, |i, j| {
            let v = a[i * n + j] * d[i] * d[j];
            if v.abs() < MATRIX_FLUSH {
                0.0
            } else {
                v as f32
            }
        });
        Self {
            n,
            upper,
            diag: (0..n)
                .map(|i| if a_ii(i) > 0.0 { 1.0 } else { 0.0 })
                .collect(),
            b_hat: b.iter().zip(&d).map(|(b_i, d_i)| b_i * d_i / mu).collect(),
            to_scaled: d.iter().map(|d_i| 1.0 / (d_i * mu)).collect(),
            objective_scale: mu * mu,
        }
    }
}

/// What the threads share: the two versions of `Z` and each band's published column sums.
struct Shared {
    z: [Vec<AtomicU64>; 2],
    col_a: Vec<Vec<AtomicU64>>,
    col_c: Vec<Vec<AtomicU64>>,
}

/// One band of rows and its private buffers.
struct Band {
    index: usize,
    rows: Range<usize>,
    sums: PassSums,
    /// Complete `a_i`, `c_i` of the band's rows for the current `Z`.
    a: Vec<f64>,
    c: Vec<f64>,
    /// This band's share of `phi_M(Z)`.
    partial_objective: f64,
    z: Vec<f64>,
    z_f32: Vec<f32>,
}

fn thread_count(requested: usize, n: usize) -> usize {
    if cfg!(target_arch = "wasm32") {
        return 1;
    }
    if requested > 0 {
        return requested.min(n.div_ceil(2));
    }
    let available = crate::threads::available();
    available
        .min(MAX_THREADS)
        .min(n / MIN_ROWS_PER_THREAD)
        .max(1)
}

/// Cuts `0..n` into `threads` bands of about equal stored entries, each starting at an even row.
fn band_rows(n: usize, padded: usize, threads: usize) -> Vec<Range<usize>> {
    let work = |i: usize| padded - UpperTriangle::start(i);
    let total: usize = (0..n).map(work).sum();
    let mut cuts = vec![0];
    let mut done = 0;
    for i in (0..n).step_by(2) {
        done += work(i) + if i + 1 < n { work(i + 1) } else { 0 };
        if done * threads >= total * cuts.len() && cuts.len() < threads && i + 2 < n {
            cuts.push(i + 2);
        }
    }
    cuts.push(n);
    cuts.windows(2).map(|w| w[0]..w[1]).collect()
}

/// The whole run: chunks of updates with a report after each (see [`super::QadpProblem::run`]).
pub(crate) fn run_chunks(
    p: &ScaledProblem,
    x0: &[f64],
    settings: &QadpSettings,
    callback: &mut dyn FnMut(&Progress) -> Control,
) -> Result<SolveOutcome, SolverError> {
    let n = p.n;
    let padded = p.upper.padded;
    let ranges = band_rows(n, padded, thread_count(settings.threads, n));
    let atomics = |len: usize| (0..len).map(|_| AtomicU64::new(0)).collect::<Vec<_>>();
    let shared = Shared {
        z: [
            x0.iter()
                .zip(&p.to_scaled)
                .map(|(x, s)| AtomicU64::new((x * s).to_bits()))
                .collect(),
            atomics(n),
        ],
        col_a: ranges.iter().map(|_| atomics(n)).collect(),
        col_c: ranges.iter().map(|_| atomics(n)).collect(),
    };
    let mut bands: Vec<Band> = ranges
        .into_iter()
        .enumerate()
        .map(|(index, rows)| Band {
            index,
            sums: PassSums::new(rows.len(), padded),
            a: vec![0.0; rows.len()],
            c: vec![0.0; rows.len()],
            rows,
            partial_objective: 0.0,
            z: vec![0.0; n],
            z_f32: vec![0.0; padded],
        })
        .collect();
    run_chunk(p, &shared, &mut bands, true, 0, 0);
    let objective_of =
        |bands: &[Band]| p.objective_scale * bands.iter().map(|b| b.partial_objective).sum::<f64>();
    let objective0 = objective_of(&bands);
    drive(
        x0.to_vec(),
        objective0,
        settings,
        callback,
        &mut |done, steps| {
            run_chunk(p, &shared, &mut bands, false, steps, done % 2);
            let x = shared.z[(done + steps) % 2]
                .iter()
                .zip(&p.to_scaled)
                .map(|(z, s)| f64::from_bits(z.load(Ordering::Relaxed)) / s)
                .collect();
            Some((x, objective_of(&bands)))
        },
    )
}

/// `steps` updates starting from version `parity` of `Z` (preceded by a pass if `initial`),
/// every band on its own thread natively.
fn run_chunk(
    p: &ScaledProblem,
    shared: &Shared,
    bands: &mut [Band],
    initial: bool,
    steps: usize,
    parity: usize,
) {
    let barrier = SpinBarrier::new(bands.len());
    #[cfg(not(target_arch = "wasm32"))]
    if let Some((first, rest)) = bands.split_first_mut() {
        if !rest.is_empty() {
            std::thread::scope(|s| {
                for band in rest {
                    let barrier = &barrier;
                    s.spawn(move || sweep_band(p, shared, band, barrier, initial, steps, parity));
                }
                sweep_band(p, shared, first, &barrier, initial, steps, parity);
            });
            return;
        }
    }
    for band in bands {
        sweep_band(p, shared, band, &barrier, initial, steps, parity);
    }
}

fn sweep_band(
    p: &ScaledProblem,
    shared: &Shared,
    band: &mut Band,
    barrier: &SpinBarrier,
    initial: bool,
    steps: usize,
    mut parity: usize,
) {
    if initial {
        compute_sums(p, shared, parity, band, barrier);
    }
    for _ in 0..steps {
        update_rows(p, &shared.z[1 - parity], band);
        barrier.wait();
        parity = 1 - parity;
        compute_sums(p, shared, parity, band, barrier);
    }
    band.partial_objective = band
        .rows
        .clone()
        .zip(band.a.iter().zip(&band.c))
        .map(|(i, (a, c))| band.z[i] * (0.5 * (a - c) + p.b_hat[i]))
        .sum();
}

/// Loads version `parity` of `Z`, makes the band's pass, exchanges column sums with the other
/// bands (one barrier) and completes `a`, `c` of the band's rows.
fn compute_sums(
    p: &ScaledProblem,
    shared: &Shared,
    parity: usize,
    band: &mut Band,
    barrier: &SpinBarrier,
) {
    let mut z_max = 0.0f64;
    for (dst, src) in band.z.iter_mut().zip(&shared.z[parity]) {
        *dst = f64::from_bits(src.load(Ordering::Relaxed));
        z_max = z_max.max(*dst);
    }
    let inv = if z_max > 0.0 { 1.0 / z_max } else { 0.0 };
    for (dst, &src) in band.z_f32.iter_mut().zip(&band.z) {
        let v = src * inv;
        *dst = if v < VECTOR_FLUSH { 0.0 } else { v as f32 };
    }
    band_pass(&p.upper, band.rows.clone(), &band.z_f32, &mut band.sums);
    let end = band.rows.end;
    for (src, dst) in [
        (&band.sums.col_a, &shared.col_a[band.index]),
        (&band.sums.col_c, &shared.col_c[band.index]),
    ] {
        for (s, d) in src[end..p.n].iter().zip(&dst[end..]) {
            d.store(s.to_bits(), Ordering::Relaxed);
        }
    }
    barrier.wait();
    for (k, i) in band.rows.clone().enumerate() {
        let (mut a, mut c) = (
            band.sums.row_a[k] + band.sums.col_a[i],
            band.sums.row_c[k] + band.sums.col_c[i],
        );
        for earlier in 0..band.index {
            a += f64::from_bits(shared.col_a[earlier][i].load(Ordering::Relaxed));
            c += f64::from_bits(shared.col_c[earlier][i].load(Ordering::Relaxed));
        }
        band.a[k] = a * z_max + p.diag[i] * band.z[i];
        band.c[k] = c * z_max;
    }
}

/// `Z_i <- Z_i * ratio(a_i, c_i, b_i)` for the band's rows, into buffer `next`.
fn update_rows(p: &ScaledProblem, next: &[AtomicU64], band: &Band) {
    for (k, i) in band.rows.clone().enumerate() {
        let z_new = band.z[i] * qadp_ratio(band.a[k], band.c[k], p.b_hat[i]);
        next[i].store(z_new.to_bits(), Ordering::Relaxed);
    }
}

/// `(-b + sqrt(b^2 + 4 a c)) / (2 a)`, evaluated without cancellation: for `b > 0` as
/// `2 c / (b + sqrt(b^2 + 4 a c))` (finite even for `a = 0`: the limit `c / b`); for `b <= 0`
/// directly. With `a = 0` and `b <= 0` (a zero row with `b = 0`, or `Z_i = 0`) the component
/// does not move (ratio 1). Since `M_ii = 1` is added exactly, `a_i >= Z_i`, which bounds the
/// step of a component that is tiny compared with the others.
fn qadp_ratio(a: f64, c: f64, b: f64) -> f64 {
    let root = (b * b + 4.0 * a * c).sqrt();
    if b > 0.0 {
        2.0 * c / (b + root)
    } else if a > 0.0 {
        (root - b) / (2.0 * a)
    } else {
        1.0
    }
}

/// A barrier for a fixed number of threads that spins briefly and then yields, so that a
/// short wait (the usual case: the bands take about the same time) costs well under a
/// microsecond, and a long one (the machine is busy) does not burn the time slice the other
/// thread needs. Generation counting makes it reusable.
struct SpinBarrier {
    threads: usize,
    arrived: AtomicUsize,
    generation: AtomicUsize,
}

/// Spins before yielding to the scheduler while waiting at a [`SpinBarrier`].
const SPINS_BEFORE_YIELD: u32 = 200;

impl SpinBarrier {
    fn new(threads: usize) -> Self {
        Self {
            threads,
            arrived: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
        }
    }

    /// Blocks until all `threads` threads have called `wait`.
    fn wait(&self) {
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.threads {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
            return;
        }
        let mut spins = 0;
        while self.generation.load(Ordering::Acquire) == generation {
            if spins < SPINS_BEFORE_YIELD {
                spins += 1;
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    }
}

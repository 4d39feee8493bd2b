//! The QADP iteration on the rescaled problem, split into bands of rows (one per thread).
//!
//! Each iteration: every band loads the whole iterate `Z`, makes one pass over its rows of the
//! stored upper triangle (row sums for its rows, column sums for the rows below), publishes the
//! column sums that belong to later bands, and waits (barrier 1); it then completes `a`, `c` of
//! its rows with the earlier bands' column sums and the diagonal, writes its rows of the next
//! `Z`, and waits (barrier 2). `Z` lives in two buffers (version `k` in buffer `k % 2`), so a
//! buffer is written only after everyone has read it. The threads are started once per run;
//! the callback runs on the calling thread between chunks of `report_every` updates, while the
//! others wait for the next chunk.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

use super::kernel::{band_pass, PassSums, UpperTriangle};
use super::run::drive;
use super::SolverError;
use super::{Control, Progress, SolveOutcome, SolverSettings};

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
/// and the maps between `X` and `Z = X sqrt(A_ii) / mu`; `phi(X) = mu^2 phi_M(Z)`. Stored with
/// the unknowns in the order `order` (position `r` holds unknown `order[r]`; see
/// [`super::QadpProblem::with_order`]): everything indexed by position.
#[derive(Debug, Clone)]
pub(crate) struct ScaledProblem {
    pub(crate) n: usize,
    upper: UpperTriangle,
    order: Vec<usize>,
    diag: Vec<f64>,
    b_hat: Vec<f64>,
    /// `Z_r = X_order[r] * to_scaled[r]`.
    to_scaled: Vec<f64>,
    /// `mu^2`.
    objective_scale: f64,
    /// Tests: the band whose pass panics (a stand-in for a bug in the pass).
    #[cfg(test)]
    panic_in_band: Option<usize>,
}

impl ScaledProblem {
    /// Assumes [`super::validate_system`] passed and `order` is a permutation of `0..n`.
    pub(crate) fn new(a: &[f64], b: &[f64], n: usize, order: Vec<usize>) -> Self {
        let a_ii = |r: usize| a[order[r] * n + order[r]];
        let d: Vec<f64> = (0..n)
            .map(|r| {
                if a_ii(r) > 0.0 {
                    1.0 / a_ii(r).sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        let b: Vec<f64> = order.iter().map(|&u| b[u]).collect();
        let mu = b
            .iter()
            .zip(&d)
            .map(|(b_r, d_r)| (b_r * d_r).abs())
            .fold(0.0, f64::max);
        let mu = if mu > 0.0 { mu } else { 1.0 };
        let upper = UpperTriangle::new(n, |r, s| {
            let v = a[order[r] * n + order[s]] * d[r] * d[s];
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
                .map(|r| if a_ii(r) > 0.0 { 1.0 } else { 0.0 })
                .collect(),
            b_hat: b.iter().zip(&d).map(|(b_r, d_r)| b_r * d_r / mu).collect(),
            to_scaled: d.iter().map(|d_r| 1.0 / (d_r * mu)).collect(),
            objective_scale: mu * mu,
            order,
            #[cfg(test)]
            panic_in_band: None,
        }
    }

    /// `X` in the caller's order from `Z` in stored order.
    fn unscaled(&self, z: &[AtomicU64]) -> Vec<f64> {
        let mut x = vec![0.0; self.n];
        for ((z, s), &u) in z.iter().zip(&self.to_scaled).zip(&self.order) {
            x[u] = f64::from_bits(z.load(Ordering::Relaxed)) / s;
        }
        x
    }
}

/// What the threads share: the two versions of `Z`, each band's published column sums and
/// share of the objective, and the means to keep in step.
struct Shared {
    z: [Vec<AtomicU64>; 2],
    col_a: Vec<Vec<AtomicU64>>,
    col_c: Vec<Vec<AtomicU64>>,
    objective: Vec<AtomicU64>,
    /// Between the halves of an update, and at the end of a chunk.
    barrier: SpinBarrier,
    orders: Orders,
}

/// One band of rows and its private buffers.
struct Band {
    index: usize,
    rows: Range<usize>,
    sums: PassSums,
    /// Complete `a_i`, `c_i` of the band's rows for the current `Z`.
    a: Vec<f64>,
    c: Vec<f64>,
    z: Vec<f64>,
    z_f32: Vec<f32>,
}

/// Bands of the sweep: `requested` (at most one per two rows), or every available thread up to
/// [`MAX_THREADS`] with at least [`MIN_ROWS_PER_THREAD`] rows each.
fn thread_count(requested: usize, n: usize) -> usize {
    if requested > 0 {
        // At most ceil(n / 2): `n + 1` items of two each.
        return crate::threads::count(requested, n + 1, 2);
    }
    crate::threads::count(0, n, MIN_ROWS_PER_THREAD).min(MAX_THREADS)
}

/// Cuts `0..n` into `threads` bands of about equal work ([`UpperTriangle::pair_cost`]), each
/// starting at an even row.
fn band_rows(upper: &UpperTriangle, threads: usize) -> Vec<Range<usize>> {
    let n = upper.n;
    let total: usize = (0..n).step_by(2).map(|i| upper.pair_cost(i)).sum();
    let mut cuts = vec![0];
    let mut done = 0;
    for i in (0..n).step_by(2) {
        done += upper.pair_cost(i);
        if done * threads >= total * cuts.len() && cuts.len() < threads && i + 2 < n {
            cuts.push(i + 2);
        }
    }
    cuts.push(n);
    cuts.windows(2).map(|w| w[0]..w[1]).collect()
}

/// The whole run: chunks of updates with a report after each (see [`super::QadpProblem::run`]).
/// Natively with more than one band, each further band gets a thread for the whole run; the
/// calling thread takes the first band and runs the callback between chunks, while the others
/// wait (blocked, not spinning) for the next chunk.
pub(crate) fn run_chunks(
    p: &ScaledProblem,
    x0: &[f64],
    settings: &SolverSettings,
    callback: &mut dyn FnMut(&Progress) -> Control,
) -> Result<SolveOutcome, SolverError> {
    let n = p.n;
    let padded = p.upper.padded;
    let ranges = band_rows(&p.upper, thread_count(settings.threads, n));
    let atomics = |len: usize| (0..len).map(|_| AtomicU64::new(0)).collect::<Vec<_>>();
    let shared = Shared {
        z: [
            p.order
                .iter()
                .zip(&p.to_scaled)
                .map(|(&u, s)| AtomicU64::new((x0[u] * s).to_bits()))
                .collect(),
            atomics(n),
        ],
        col_a: ranges.iter().map(|_| atomics(n)).collect(),
        col_c: ranges.iter().map(|_| atomics(n)).collect(),
        objective: atomics(ranges.len()),
        barrier: SpinBarrier::new(ranges.len()),
        orders: Orders::new(ranges.len()),
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
            z: vec![0.0; n],
            z_f32: vec![0.0; padded],
        })
        .collect();
    let (first, rest) = bands
        .split_first_mut()
        .expect("band_rows makes at least one band");
    #[cfg(not(target_arch = "wasm32"))]
    if !rest.is_empty() {
        return std::thread::scope(|s| {
            for band in rest {
                let shared = &shared;
                s.spawn(move || follow(p, shared, band));
            }
            // Releases the other threads however the run ends.
            let _release = Release(&shared);
            lead(p, x0, &shared, first, settings, callback)
        });
    }
    debug_assert!(rest.is_empty(), "wasm32 runs one band");
    lead(p, x0, &shared, first, settings, callback)
}

/// The calling thread's part: the first band, the chunks and the callback.
fn lead(
    p: &ScaledProblem,
    x0: &[f64],
    shared: &Shared,
    band: &mut Band,
    settings: &SolverSettings,
    callback: &mut dyn FnMut(&Progress) -> Control,
) -> Result<SolveOutcome, SolverError> {
    let objective = |shared: &Shared| {
        p.objective_scale
            * shared
                .objective
                .iter()
                .map(|o| f64::from_bits(o.load(Ordering::Relaxed)))
                .sum::<f64>()
    };
    let mut chunk = |initial: bool, steps: usize, parity: usize| {
        shared.orders.give(Chunk {
            initial,
            steps,
            parity,
        });
        let _poison = PoisonOnPanic(&shared.barrier);
        sweep_band(p, shared, band, initial, steps, parity);
        shared.barrier.wait();
    };
    chunk(true, 0, 0);
    let objective0 = objective(shared);
    drive(
        x0.to_vec(),
        objective0,
        settings,
        callback,
        &mut |done, steps| {
            chunk(false, steps, done % 2);
            Some((p.unscaled(&shared.z[(done + steps) % 2]), objective(shared)))
        },
    )
}

/// Another thread's part: its band in every chunk, until the run ends.
#[cfg(not(target_arch = "wasm32"))]
fn follow(p: &ScaledProblem, shared: &Shared, band: &mut Band) {
    while let Some(chunk) = shared.orders.take() {
        let _poison = PoisonOnPanic(&shared.barrier);
        sweep_band(p, shared, band, chunk.initial, chunk.steps, chunk.parity);
        shared.barrier.wait();
    }
}

/// `steps` updates starting from version `parity` of `Z` (preceded by a pass if `initial`);
/// the band's share of the objective at the end goes to `shared.objective`.
fn sweep_band(
    p: &ScaledProblem,
    shared: &Shared,
    band: &mut Band,
    initial: bool,
    steps: usize,
    mut parity: usize,
) {
    if initial {
        compute_sums(p, shared, parity, band);
    }
    #[cfg(test)]
    if p.panic_in_band == Some(band.index) && steps > 0 {
        panic!("band {} fails (test)", band.index);
    }
    for _ in 0..steps {
        update_rows(p, &shared.z[1 - parity], band);
        shared.barrier.wait();
        parity = 1 - parity;
        compute_sums(p, shared, parity, band);
    }
    let objective: f64 = band
        .rows
        .clone()
        .zip(band.a.iter().zip(&band.c))
        .map(|(i, (a, c))| band.z[i] * (0.5 * (a - c) + p.b_hat[i]))
        .sum();
    shared.objective[band.index].store(objective.to_bits(), Ordering::Relaxed);
}

/// Loads version `parity` of `Z`, makes the band's pass, exchanges column sums with the other
/// bands (one barrier) and completes `a`, `c` of the band's rows.
fn compute_sums(p: &ScaledProblem, shared: &Shared, parity: usize, band: &mut Band) {
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
    shared.barrier.wait();
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

/// One chunk of updates, as the first band's thread orders it.
#[derive(Debug, Clone, Copy)]
struct Chunk {
    initial: bool,
    steps: usize,
    parity: usize,
}

/// Hands each chunk from the calling thread to the other bands' threads, which wait for it at
/// a blocking barrier: between chunks the callback may take its time without their spinning.
struct Orders {
    start: std::sync::Barrier,
    /// Steps of the next chunk, or [`Orders::STOP`] when the run is over.
    steps: AtomicUsize,
    /// Bit 0: parity; bit 1: initial pass.
    flags: AtomicUsize,
}

impl Orders {
    #[cfg(not(target_arch = "wasm32"))]
    const STOP: usize = usize::MAX;

    fn new(threads: usize) -> Self {
        Self {
            start: std::sync::Barrier::new(threads),
            steps: AtomicUsize::new(0),
            flags: AtomicUsize::new(0),
        }
    }

    /// The calling thread: publishes `chunk` and releases the others. (The barrier orders
    /// these stores before the others' loads; the others cannot be reading the previous chunk
    /// any more: they have passed the end-of-chunk barrier.)
    fn give(&self, chunk: Chunk) {
        self.steps.store(chunk.steps, Ordering::Relaxed);
        self.flags.store(
            chunk.parity | usize::from(chunk.initial) << 1,
            Ordering::Relaxed,
        );
        self.start.wait();
    }

    /// Another thread: waits for the next chunk; `None` when the run is over.
    #[cfg(not(target_arch = "wasm32"))]
    fn take(&self) -> Option<Chunk> {
        self.start.wait();
        let steps = self.steps.load(Ordering::Relaxed);
        let flags = self.flags.load(Ordering::Relaxed);
        (steps != Self::STOP).then_some(Chunk {
            initial: flags & 2 != 0,
            steps,
            parity: flags & 1,
        })
    }
}

/// Tells the other threads that the run is over when dropped: after the last chunk, on an
/// error, on a cancel, on a panic in the callback. Not after a panic during a chunk: the
/// others have then panicked at the poisoned barrier and wait for nothing.
#[cfg(not(target_arch = "wasm32"))]
struct Release<'a>(&'a Shared);

#[cfg(not(target_arch = "wasm32"))]
impl Drop for Release<'_> {
    fn drop(&mut self) {
        if self.0.barrier.poisoned.load(Ordering::Acquire) {
            return;
        }
        let orders = &self.0.orders;
        orders.steps.store(Orders::STOP, Ordering::Relaxed);
        orders.start.wait();
    }
}

/// A barrier for a fixed number of threads that spins for a while and then yields, with the
/// time it spins set by how waits have ended so far.
///
/// Every thread of a run has a core of its own in the usual case, and the bands take about the
/// same time, so a wait is a few microseconds and spinning answers it at once. A thread that
/// gave up its core at every wait (as an earlier version did after 200 spins) let the scheduler
/// put both bands on one core, where they took turns: no faster than one thread. But when the
/// machine has more threads to run than cores (two runs at once, or other programs), the thread
/// waited for is often not running, and spinning takes the core it needs (two runs of two
/// threads on two cores were several times slower than one thread each with a fixed spin:
/// BENCHMARKS.md). So the spin time falls to a quarter whenever a wait outlasts it, down to
/// [`SPIN_MIN`], and grows by [`SPIN_STEP`] after each wait that it answered, up to
/// [`SPIN_MAX`]. Generation counting makes the barrier reusable.
///
/// A thread that panics during a chunk poisons the barrier ([`PoisonOnPanic`]): the threads
/// waiting for it, and any that come to wait later, panic too instead of waiting forever, so
/// the run ends with the panic rather than hanging.
struct SpinBarrier {
    threads: usize,
    arrived: AtomicUsize,
    generation: AtomicUsize,
    /// The current spin time in ns.
    spin_ns: AtomicU64,
    poisoned: AtomicBool,
}

/// Spin time at the start and at most: about one update of the largest systems, ten of the
/// usual ones.
const SPIN_MAX: std::time::Duration = std::time::Duration::from_micros(200);
/// Spin time at least: about what an earlier version spun (200 spins).
const SPIN_MIN: std::time::Duration = std::time::Duration::from_micros(1);
/// Growth of the spin time after a wait that spinning answered.
const SPIN_STEP: std::time::Duration = std::time::Duration::from_micros(2);
/// Spins between looks at the clock.
const SPINS_PER_CLOCK: u32 = 64;

impl SpinBarrier {
    fn new(threads: usize) -> Self {
        Self {
            threads,
            arrived: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
            spin_ns: AtomicU64::new(SPIN_MAX.as_nanos() as u64),
            poisoned: AtomicBool::new(false),
        }
    }

    /// Blocks until all `threads` threads have called `wait`. Panics if another thread has
    /// panicked during a chunk (and so will never come).
    fn wait(&self) {
        if self.threads == 1 {
            // Also keeps the clock (absent on wasm32) out of single-threaded runs.
            return;
        }
        self.check_poison();
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.threads {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
            return;
        }
        let spin = self.spin_ns.load(Ordering::Relaxed);
        let limit = std::time::Duration::from_nanos(spin);
        let began = std::time::Instant::now();
        let mut yielded = false;
        while self.generation.load(Ordering::Acquire) == generation {
            if !yielded && began.elapsed() < limit {
                for _ in 0..SPINS_PER_CLOCK {
                    std::hint::spin_loop();
                }
            } else {
                yielded = true;
                std::thread::yield_now();
            }
            self.check_poison();
        }
        self.spin_ns
            .store(next_spin_ns(spin, yielded), Ordering::Relaxed);
    }

    fn check_poison(&self) {
        if self.poisoned.load(Ordering::Acquire) {
            panic!("another QADP thread panicked");
        }
    }
}

/// Poisons `barrier` if dropped while its thread unwinds from a panic: held by every thread
/// around its part of a chunk.
struct PoisonOnPanic<'a>(&'a SpinBarrier);

impl Drop for PoisonOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.poisoned.store(true, Ordering::Release);
        }
    }
}

/// The spin time after a wait that spun `spin_ns` and ended spinning or (`yielded`) not.
fn next_spin_ns(spin_ns: u64, yielded: bool) -> u64 {
    let ns = |d: std::time::Duration| d.as_nanos() as u64;
    if yielded {
        (spin_ns / 4).max(ns(SPIN_MIN))
    } else {
        (spin_ns + ns(SPIN_STEP)).min(ns(SPIN_MAX))
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    /// A small dense problem `A = G^T G + I`, `b = -G^T t`, in the given order.
    fn problem(n: usize) -> ScaledProblem {
        let rows = 2 * n;
        let g = |r: usize, c: usize| (((r * 31 + c * 17) % 23) as f64 - 9.0) / 23.0;
        let mut a = vec![0.0; n * n];
        let mut b = vec![0.0; n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..rows).map(|r| g(r, i) * g(r, j)).sum::<f64>()
                    + if i == j { 1.0 } else { 0.0 };
            }
            b[i] = -(0..rows)
                .map(|r| g(r, i) * (1.0 + r as f64 % 3.0))
                .sum::<f64>();
        }
        ScaledProblem::new(&a, &b, n, (0..n).collect())
    }

    /// Runs `p` on `threads` threads in a thread of its own (so that a hang is seen as one),
    /// and returns whether it panicked, or `None` if it had not ended after 60 s.
    fn panics(p: ScaledProblem, threads: usize, panic_in_callback: bool) -> Option<bool> {
        let (done, ended) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let settings = SolverSettings {
                iterations: 400,
                report_every: 100,
                threads,
                keep_iterates: 0,
            };
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let x0 = vec![0.1; p.n];
                run_chunks(&p, &x0, &settings, &mut |progress| {
                    assert!(
                        !(panic_in_callback && progress.iteration == 200),
                        "callback fails (test)"
                    );
                    Control::Continue
                })
            }));
            let _ = done.send(result.is_err());
        });
        ended.recv_timeout(std::time::Duration::from_secs(60)).ok()
    }

    #[test]
    fn a_panic_in_any_band_or_in_the_callback_ends_the_run_instead_of_hanging() {
        assert_eq!(panics(problem(64), 3, false), Some(false), "no panic");
        for band in 0..3 {
            let mut p = problem(64);
            p.panic_in_band = Some(band);
            assert_eq!(panics(p, 3, false), Some(true), "band {band} panics");
        }
        assert_eq!(panics(problem(64), 3, true), Some(true), "callback panics");
    }

    #[test]
    fn a_wait_that_outlasts_the_spin_shortens_it() {
        let barrier = SpinBarrier::new(2);
        let spin = || std::time::Duration::from_nanos(barrier.spin_ns.load(Ordering::Relaxed));
        assert_eq!(spin(), SPIN_MAX);
        std::thread::scope(|s| {
            s.spawn(|| {
                // 100 times the spin: whichever thread waits, its wait outlasts the spin.
                std::thread::sleep(SPIN_MAX * 100);
                barrier.wait();
            });
            barrier.wait();
        });
        assert_eq!(spin(), SPIN_MAX / 4);
    }

    #[test]
    fn the_spin_falls_fast_and_recovers_slowly_within_its_bounds() {
        let ns = |d: std::time::Duration| d.as_nanos() as u64;
        let mut spin = ns(SPIN_MAX);
        let mut falls = 0;
        while spin > ns(SPIN_MIN) {
            spin = next_spin_ns(spin, true);
            falls += 1;
        }
        assert_eq!((spin, falls), (ns(SPIN_MIN), 4));
        let mut rises = 0;
        while spin < ns(SPIN_MAX) {
            spin = next_spin_ns(spin, false);
            rises += 1;
        }
        assert_eq!((spin, rises), (ns(SPIN_MAX), 100));
        assert_eq!(next_spin_ns(spin, false), ns(SPIN_MAX));
    }
}

//! The inner loop of QADP: the two sums `a = M+ x` and `c = M- x` (`M+ = max(M, 0)`,
//! `M- = max(-M, 0)`) for a symmetric matrix `M` with unit or zero diagonal, stored as its
//! strict upper triangle in single precision, and a vector `x >= 0`.
//!
//! Each stored entry `M_ij` (`j > i`) is read once and used twice: for row `i` (`M_ij x_j`) and
//! for row `j` (`M_ij x_i`, accumulated column-wise), so a pass reads `n^2 / 2` values of 4
//! bytes. Rows are taken in pairs that share their column range, so the column sums are loaded
//! and stored once per pair. The products are exact splits of `M_ij x_j` (`max(M, 0) - M` is
//! exact in floating point) summed in f32 over short stretches (at most [`ROW_BLOCK`] columns
//! of a row, [`FLUSH_ROWS`] rows of a column) and then in f64, so the sums keep a relative
//! accuracy of ~1e-7, the same order as rounding `M` to f32.
//!
//! The pass is bound by arithmetic, not memory: a general entry costs four multiply-adds (two
//! sums, row and column). Where a whole chunk of a row pair has one sign, one of the two sums
//! gets nothing from it, so the chunk costs half: the pair's chunks are sorted once into
//! [`Run`]s of one kind, and each kind has its own loop. How much this saves depends on the
//! order of the unknowns (neighbouring grid cells have similar rows), hence
//! [`super::QadpProblem::with_order`]. Natively the results are the same to the bit as with
//! every chunk taken as mixed; the wasm loops of one sign keep two sums per row (one would wait
//! on the latency of each multiply-add), which changes only the rounding.
//!
//! On x86-64 with AVX2 and FMA (checked at run time) the loop is compiled for those
//! instructions; elsewhere (including wasm32) the same code is compiled for the baseline target.

use std::ops::Range;

/// Columns per step: two 256-bit registers of f32 per sum.
pub(crate) const CHUNK: usize = 16;
// The final reduction in `pair_sums` is written for 16 lanes.
const _: () = assert!(CHUNK == 16);
/// Row sums go from f32 to f64 every this many columns (runs do not straddle these blocks).
/// On wasm32 one 4-lane sum per row (not the 16 lanes of the generic code) keeps 32 terms per
/// lane with a quarter of the columns.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
const ROW_BLOCK: usize = 512;
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
const ROW_BLOCK: usize = 128;
const _: () = assert!(ROW_BLOCK % CHUNK == 0);
/// Column sums go from f32 to f64 every this many rows.
const FLUSH_ROWS: usize = 32;

/// How the entries of a stretch of a row pair compare with 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Signs {
    /// Both signs: both sums get a share of each entry.
    Mixed,
    /// No negative entry: only `a` gets anything.
    NonNegative,
    /// No positive entry: only `c` gets anything.
    NonPositive,
}

/// Columns `start..end` (whole chunks, counted from the pair's first stored column, within one
/// [`ROW_BLOCK`]) of a row pair, all of one kind. All-zero chunks are in no run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    start: u32,
    end: u32,
    signs: Signs,
}

/// The strict upper triangle of an `n x n` matrix: row `i` holds columns
/// `start(i) = CHUNK floor(i / CHUNK)` to `padded` (a multiple of [`CHUNK`]), with zeros at
/// `j <= i` and `j >= n`. Rows `2k` and `2k + 1` share their start, and their [`Run`]s.
#[derive(Debug, Clone)]
pub(crate) struct UpperTriangle {
    pub(crate) n: usize,
    pub(crate) padded: usize,
    data: Vec<f32>,
    offsets: Vec<usize>,
    runs: Vec<Run>,
    /// Runs of pair `k` (rows `2k`, `2k + 1`): `runs[run_offsets[k]..run_offsets[k + 1]]`.
    run_offsets: Vec<usize>,
}

impl UpperTriangle {
    /// Fills entry `(i, j)`, `j > i`, with `entry(i, j)`.
    pub(crate) fn new(n: usize, entry: impl Fn(usize, usize) -> f32) -> Self {
        let padded = n.div_ceil(CHUNK) * CHUNK;
        let mut offsets = Vec::with_capacity(n);
        let mut data = Vec::new();
        for i in 0..n {
            offsets.push(data.len());
            data.extend((Self::start(i)..padded).map(|j| {
                if j > i && j < n {
                    entry(i, j)
                } else {
                    0.0
                }
            }));
        }
        let mut m = Self {
            n,
            padded,
            data,
            offsets,
            runs: Vec::new(),
            run_offsets: vec![0],
        };
        for i in (0..n).step_by(2) {
            let rows = [m.row(i), m.row((i + 1).min(n - 1))];
            let pair_runs = runs_of(rows);
            m.runs.extend(pair_runs);
            m.run_offsets.push(m.runs.len());
        }
        m
    }

    /// First stored column of row `i`.
    fn start(i: usize) -> usize {
        i / CHUNK * CHUNK
    }

    fn row(&self, i: usize) -> &[f32] {
        &self.data[self.offsets[i]..self.offsets[i] + self.padded - Self::start(i)]
    }

    /// The runs of the pair that holds row `i`.
    fn pair_runs(&self, i: usize) -> &[Run] {
        &self.runs[self.run_offsets[i / 2]..self.run_offsets[i / 2 + 1]]
    }

    /// What a pass over the pair that holds row `i` costs, in multiply-adds of one lane, with
    /// a fixed cost per pair and per run: for cutting the rows into bands of equal work.
    pub(crate) fn pair_cost(&self, i: usize) -> usize {
        // Chosen so that the two bands' passes of the #4 benchmark (n = 1085) take about the
        // same time (47 - 53 us each); the order of magnitude is what matters.
        const PER_PAIR: usize = 512;
        const PER_RUN: usize = 64;
        PER_PAIR
            + self
                .pair_runs(i)
                .iter()
                .map(|r| {
                    let per_column = if r.signs == Signs::Mixed { 8 } else { 4 };
                    PER_RUN + per_column * (r.end - r.start) as usize
                })
                .sum::<usize>()
    }
}

/// The runs of a row pair (the same row twice for a lone last row).
fn runs_of(rows: [&[f32]; 2]) -> Vec<Run> {
    let mut runs: Vec<Run> = Vec::new();
    for start in (0..rows[0].len()).step_by(CHUNK) {
        let entries = rows[0][start..start + CHUNK]
            .iter()
            .chain(&rows[1][start..start + CHUNK]);
        let (mut positive, mut negative) = (false, false);
        for &v in entries {
            positive |= v > 0.0;
            negative |= v < 0.0;
        }
        let signs = match (positive, negative) {
            (false, false) => continue,
            (true, false) => Signs::NonNegative,
            (false, true) => Signs::NonPositive,
            (true, true) => Signs::Mixed,
        };
        let end = (start + CHUNK) as u32;
        match runs.last_mut() {
            Some(last)
                if last.signs == signs && last.end as usize == start && start % ROW_BLOCK != 0 =>
            {
                last.end = end;
            }
            _ => runs.push(Run {
                start: start as u32,
                end,
                signs,
            }),
        }
    }
    runs
}

/// The sums of one band of rows: `row_*[k]` for row `rows.start + k` from its own stored
/// entries, `col_*[j]` for every column `j` from the band's rows `i < j`.
#[derive(Debug, Clone)]
pub(crate) struct PassSums {
    pub(crate) row_a: Vec<f64>,
    pub(crate) row_c: Vec<f64>,
    pub(crate) col_a: Vec<f64>,
    pub(crate) col_c: Vec<f64>,
    col_a32: Vec<f32>,
    col_c32: Vec<f32>,
}

impl PassSums {
    pub(crate) fn new(rows: usize, padded: usize) -> Self {
        Self {
            row_a: vec![0.0; rows],
            row_c: vec![0.0; rows],
            col_a: vec![0.0; padded],
            col_c: vec![0.0; padded],
            col_a32: vec![0.0; padded],
            col_c32: vec![0.0; padded],
        }
    }
}

/// One pass over the rows `rows` (starting at an even row) of `m` with `x` (`m.padded`
/// entries, `>= 0`, zero beyond `n`), into `sums`.
pub(crate) fn band_pass(m: &UpperTriangle, rows: Range<usize>, x: &[f32], sums: &mut PassSums) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above), the only requirement
            // of a `#[target_feature]` function; the function itself is safe code.
            unsafe { band_pass_avx2(m, rows, x, sums) };
            return;
        }
    }
    band_pass_body::<false>(m, rows, x, sums);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn band_pass_avx2(m: &UpperTriangle, rows: Range<usize>, x: &[f32], sums: &mut PassSums) {
    band_pass_body::<true>(m, rows, x, sums);
}

#[inline(always)]
fn band_pass_body<const FUSED: bool>(
    m: &UpperTriangle,
    rows: Range<usize>,
    x: &[f32],
    sums: &mut PassSums,
) {
    let first = UpperTriangle::start(rows.start);
    sums.col_a[first..].fill(0.0);
    sums.col_c[first..].fill(0.0);
    let mut flush_from = first;
    let mut i = rows.start;
    while i < rows.end {
        let s = UpperTriangle::start(i);
        let pair = i + 1 < rows.end;
        let row0 = m.row(i);
        // A lone last row is paired with itself at weight 0.
        let (row1, x1) = if pair {
            (m.row(i + 1), x[i + 1])
        } else {
            (row0, 0.0)
        };
        let [a0, c0, a1, c1] = pair_sums::<FUSED>(
            [row0, row1],
            m.pair_runs(i),
            &x[s..m.padded],
            [x[i], x1],
            &mut sums.col_a32[s..],
            &mut sums.col_c32[s..],
        );
        let k = i - rows.start;
        (sums.row_a[k], sums.row_c[k]) = (a0, c0);
        if pair {
            (sums.row_a[k + 1], sums.row_c[k + 1]) = (a1, c1);
        }
        i += 2;
        if (i - rows.start) % FLUSH_ROWS == 0 || i >= rows.end {
            flush(
                &mut sums.col_a32[flush_from..],
                &mut sums.col_a[flush_from..],
            );
            flush(
                &mut sums.col_c32[flush_from..],
                &mut sums.col_c[flush_from..],
            );
            flush_from = UpperTriangle::start(i.min(m.n - 1));
        }
    }
}

/// `dst += src; src = 0`.
#[inline(always)]
fn flush(src: &mut [f32], dst: &mut [f64]) {
    for (s, d) in src.iter_mut().zip(dst.iter_mut()) {
        *d += f64::from(*s);
        *s = 0.0;
    }
}

/// A chunk of [`CHUNK`] values by value.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn chunk(s: &[f32]) -> [f32; CHUNK] {
    let mut v = [0.0; CHUNK];
    v.copy_from_slice(s);
    v
}

/// `acc + p * q`, fused when the caller is compiled with FMA (otherwise a library call).
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn madd<const FUSED: bool>(p: f32, q: f32, acc: f32) -> f32 {
    if FUSED {
        p.mul_add(q, acc)
    } else {
        p * q + acc
    }
}

/// Row sums `[a_0, c_0, a_1, c_1]` of two rows over their common columns, and their
/// contributions `M_ij x_i` to the column sums, run by run.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn pair_sums<const FUSED: bool>(
    rows: [&[f32]; 2],
    runs: &[Run],
    x: &[f32],
    [x0, x1]: [f32; 2],
    col_a: &mut [f32],
    col_c: &mut [f32],
) -> [f64; 4] {
    let mut total = [[0.0f64; CHUNK]; 4];
    // Separate arrays (not one 2-D array, no references to them) so that they live in
    // registers across the runs.
    let (mut a0, mut c0) = ([0.0f32; CHUNK], [0.0f32; CHUNK]);
    let (mut a1, mut c1) = ([0.0f32; CHUNK], [0.0f32; CHUNK]);
    let mut block = 0;
    for run in runs {
        let (b, e) = (run.start as usize, run.end as usize);
        if b / ROW_BLOCK != block {
            block = b / ROW_BLOCK;
            add_f32(&mut total, [a0, c0, a1, c1]);
            (a0, c0, a1, c1) = ([0.0; CHUNK], [0.0; CHUNK], [0.0; CHUNK], [0.0; CHUNK]);
        }
        let (m0, m1, x) = (&rows[0][b..e], &rows[1][b..e], &x[b..e]);
        match run.signs {
            Signs::Mixed => {
                [a0, c0, a1, c1] = mixed_steps::<FUSED>(
                    [m0, m1],
                    x,
                    [x0, x1],
                    [&mut col_a[b..e], &mut col_c[b..e]],
                    [a0, c0, a1, c1],
                );
            }
            Signs::NonNegative => {
                [a0, a1] = one_sign_steps::<FUSED, false>(
                    [m0, m1],
                    x,
                    [x0, x1],
                    &mut col_a[b..e],
                    [a0, a1],
                );
            }
            Signs::NonPositive => {
                [c0, c1] = one_sign_steps::<FUSED, true>(
                    [m0, m1],
                    x,
                    [x0, x1],
                    &mut col_c[b..e],
                    [c0, c1],
                );
            }
        }
    }
    add_f32(&mut total, [a0, c0, a1, c1]);
    total.map(|t| {
        let mut s4 = [0.0f64; 4];
        for (k, s) in s4.iter_mut().enumerate() {
            *s = (t[k] + t[k + 4]) + (t[k + 8] + t[k + 12]);
        }
        (s4[0] + s4[2]) + (s4[1] + s4[3])
    })
}

/// `total += sums`, lane by lane.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn add_f32(total: &mut [[f64; CHUNK]; 4], sums: [[f32; CHUNK]; 4]) {
    for (t, s) in total.iter_mut().zip(sums) {
        for k in 0..CHUNK {
            t[k] += f64::from(s[k]);
        }
    }
}

/// A run of both signs: `a`, `c` of both rows and both column sums.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn mixed_steps<const FUSED: bool>(
    [m0, m1]: [&[f32]; 2],
    x: &[f32],
    [x0, x1]: [f32; 2],
    [col_a, col_c]: [&mut [f32]; 2],
    [mut a0, mut c0, mut a1, mut c1]: [[f32; CHUNK]; 4],
) -> [[f32; CHUNK]; 4] {
    let steps = m0
        .chunks_exact(CHUNK)
        .zip(m1.chunks_exact(CHUNK))
        .zip(x.chunks_exact(CHUNK))
        .zip(col_a.chunks_exact_mut(CHUNK))
        .zip(col_c.chunks_exact_mut(CHUNK));
    for ((((m0, m1), xv), ca), cc) in steps {
        // Local copies: the compiler cannot tell that the stores to the column sums do not
        // alias the other slices, and would otherwise keep everything in memory.
        let (m0, m1, xv) = (chunk(m0), chunk(m1), chunk(xv));
        let (mut ca_v, mut cc_v) = (chunk(ca), chunk(cc));
        for k in 0..CHUNK {
            let p0 = if m0[k] > 0.0 { m0[k] } else { 0.0 };
            let p1 = if m1[k] > 0.0 { m1[k] } else { 0.0 };
            let (q0, q1) = (p0 - m0[k], p1 - m1[k]);
            a0[k] = madd::<FUSED>(p0, xv[k], a0[k]);
            c0[k] = madd::<FUSED>(q0, xv[k], c0[k]);
            a1[k] = madd::<FUSED>(p1, xv[k], a1[k]);
            c1[k] = madd::<FUSED>(q1, xv[k], c1[k]);
            ca_v[k] = madd::<FUSED>(p1, x1, madd::<FUSED>(p0, x0, ca_v[k]));
            cc_v[k] = madd::<FUSED>(q1, x1, madd::<FUSED>(q0, x0, cc_v[k]));
        }
        ca.copy_from_slice(&ca_v);
        cc.copy_from_slice(&cc_v);
    }
    [a0, c0, a1, c1]
}

/// A run of one sign: the sum of that sign of both rows (`a` if `!NEGATIVE`, `c` with the
/// entries negated if `NEGATIVE`) and its column sums. The products and sums are those of
/// [`mixed_steps`] without the ones that add 0, so the results are the same to the bit.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn one_sign_steps<const FUSED: bool, const NEGATIVE: bool>(
    [m0, m1]: [&[f32]; 2],
    x: &[f32],
    [x0, x1]: [f32; 2],
    col: &mut [f32],
    [mut s0, mut s1]: [[f32; CHUNK]; 2],
) -> [[f32; CHUNK]; 2] {
    let steps = m0
        .chunks_exact(CHUNK)
        .zip(m1.chunks_exact(CHUNK))
        .zip(x.chunks_exact(CHUNK))
        .zip(col.chunks_exact_mut(CHUNK));
    for (((m0, m1), xv), col) in steps {
        let (m0, m1, xv) = (chunk(m0), chunk(m1), chunk(xv));
        let mut col_v = chunk(col);
        for k in 0..CHUNK {
            let (p0, p1) = if NEGATIVE {
                (-m0[k], -m1[k])
            } else {
                (m0[k], m1[k])
            };
            s0[k] = madd::<FUSED>(p0, xv[k], s0[k]);
            s1[k] = madd::<FUSED>(p1, xv[k], s1[k]);
            col_v[k] = madd::<FUSED>(p1, x1, madd::<FUSED>(p0, x0, col_v[k]));
        }
        col.copy_from_slice(&col_v);
    }
    [s0, s1]
}

/// [`pair_sums`] in WebAssembly SIMD, 4 lanes at a time. Written out because the generic code,
/// vectorised by LLVM, keeps 16 lanes of each of the four row sums, and 16 `v128` sums do not
/// fit the 16 vector registers a browser has on x86-64: they spill on every step. Here the
/// live values are 4 sums, 2 splats and the step's loads and products. `max(M, 0)` is
/// `f32x4_pmax`, one instruction (the IEEE `f32x4_max` needs a NaN fix-up on x86-64; `M` has
/// no NaN).
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
#[inline(always)]
fn pair_sums<const FUSED: bool>(
    rows: [&[f32]; 2],
    runs: &[Run],
    x: &[f32],
    [x0, x1]: [f32; 2],
    col_a: &mut [f32],
    col_c: &mut [f32],
) -> [f64; 4] {
    use super::wasm_simd::{madd_f32x4 as madd4, nmadd_f32x4 as nmadd4};
    use core::arch::wasm32::{
        f32x4_add, f32x4_extract_lane, f32x4_pmax, f32x4_splat, f32x4_sub, v128, v128_load,
        v128_store,
    };
    const LANES: usize = 4;
    // SAFETY (all loads and stores): each slice is a `chunks_exact` chunk of at least 4 `f32`
    // (or its second half of 4), so 16 valid bytes; `v128_load`/`v128_store` need no alignment.
    #[inline(always)]
    fn load(s: &[f32]) -> v128 {
        debug_assert!(s.len() >= LANES);
        unsafe { v128_load(s.as_ptr().cast::<v128>()) }
    }
    #[inline(always)]
    fn store(d: &mut [f32], v: v128) {
        debug_assert!(d.len() >= LANES);
        unsafe { v128_store(d.as_mut_ptr().cast::<v128>(), v) }
    }
    /// A run of one sign: the sum of that sign of both rows (`a` if `!NEGATIVE`; `c` if
    /// `NEGATIVE`, as `acc - M x`, the same as `acc + (-M) x` to the bit) and its column sums.
    /// Two steps at a time with a second sum per row: with one, the loop would wait on the
    /// latency of each multiply-add (the mixed loop has two sums per row).
    #[inline(always)]
    fn one_sign<const NEGATIVE: bool>(
        rows: [&[f32]; 2],
        x: &[f32],
        [x0, x1]: [v128; 2],
        col: &mut [f32],
        [mut s0, mut s1]: [v128; 2],
    ) -> [v128; 2] {
        let fma = |p, q, acc| {
            if NEGATIVE {
                nmadd4(p, q, acc)
            } else {
                madd4(p, q, acc)
            }
        };
        let (mut s0b, mut s1b) = (f32x4_splat(0.0), f32x4_splat(0.0));
        let steps = rows[0]
            .chunks_exact(2 * LANES)
            .zip(rows[1].chunks_exact(2 * LANES))
            .zip(x.chunks_exact(2 * LANES))
            .zip(col.chunks_exact_mut(2 * LANES));
        for (((m0, m1), xv), col) in steps {
            let (m0b, m1b, xvb) = (load(&m0[LANES..]), load(&m1[LANES..]), load(&xv[LANES..]));
            let (m0, m1, xv) = (load(m0), load(m1), load(xv));
            s0 = fma(m0, xv, s0);
            s1 = fma(m1, xv, s1);
            s0b = fma(m0b, xvb, s0b);
            s1b = fma(m1b, xvb, s1b);
            let (col, col_b) = col.split_at_mut(LANES);
            store(col, fma(m1, x1, fma(m0, x0, load(col))));
            store(col_b, fma(m1b, x1, fma(m0b, x0, load(col_b))));
        }
        [f32x4_add(s0, s0b), f32x4_add(s1, s1b)]
    }
    let lanes = |v: v128| {
        f64::from(f32x4_extract_lane::<0>(v))
            + f64::from(f32x4_extract_lane::<1>(v))
            + (f64::from(f32x4_extract_lane::<2>(v)) + f64::from(f32x4_extract_lane::<3>(v)))
    };
    let zero = f32x4_splat(0.0);
    let (x0, x1) = (f32x4_splat(x0), f32x4_splat(x1));
    let mut total = [0.0f64; 4];
    let (mut a0, mut c0, mut a1, mut c1) = (zero, zero, zero, zero);
    let mut block = 0;
    for run in runs {
        let (b, e) = (run.start as usize, run.end as usize);
        if b / ROW_BLOCK != block {
            block = b / ROW_BLOCK;
            for (t, acc) in total.iter_mut().zip([&mut a0, &mut c0, &mut a1, &mut c1]) {
                *t += lanes(*acc);
                *acc = zero;
            }
        }
        let (rows_b, x_b) = ([&rows[0][b..e], &rows[1][b..e]], &x[b..e]);
        let rows = rows_b[0]
            .chunks_exact(LANES)
            .zip(rows_b[1].chunks_exact(LANES))
            .zip(x_b.chunks_exact(LANES));
        match run.signs {
            Signs::Mixed => {
                let cols = col_a[b..e]
                    .chunks_exact_mut(LANES)
                    .zip(col_c[b..e].chunks_exact_mut(LANES));
                for (((m0, m1), xv), (ca, cc)) in rows.zip(cols) {
                    let (m0, m1, xv) = (load(m0), load(m1), load(xv));
                    let (p0, p1) = (f32x4_pmax(zero, m0), f32x4_pmax(zero, m1));
                    let (q0, q1) = (f32x4_sub(p0, m0), f32x4_sub(p1, m1));
                    a0 = madd4(p0, xv, a0);
                    c0 = madd4(q0, xv, c0);
                    a1 = madd4(p1, xv, a1);
                    c1 = madd4(q1, xv, c1);
                    store(ca, madd4(p1, x1, madd4(p0, x0, load(ca))));
                    store(cc, madd4(q1, x1, madd4(q0, x0, load(cc))));
                }
            }
            Signs::NonNegative => {
                [a0, a1] = one_sign::<false>(rows_b, x_b, [x0, x1], &mut col_a[b..e], [a0, a1]);
            }
            Signs::NonPositive => {
                [c0, c1] = one_sign::<true>(rows_b, x_b, [x0, x1], &mut col_c[b..e], [c0, c1]);
            }
        }
    }
    for (t, acc) in total.iter_mut().zip([a0, c0, a1, c1]) {
        *t += lanes(acc);
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries in blocks of each kind (positive, negative, zero, both signs), not aligned with
    /// the chunks; `n` odd (a lone last row) and wider than two [`ROW_BLOCK`]s.
    fn blocky(i: usize, j: usize) -> f32 {
        let size = 0.05 + ((i * 7919 + j * 104_729) % 97) as f32 / 97.0;
        match (i / 40 + j / 23) % 4 {
            0 => size,
            1 => -size,
            2 => 0.0,
            _ if (i + j) % 3 == 0 => -size,
            _ => size,
        }
    }

    #[test]
    fn pass_sums_match_a_direct_sum_for_every_kind_of_run() {
        let n = 2 * ROW_BLOCK + 77;
        let m = UpperTriangle::new(n, blocky);
        let kinds: Vec<Signs> = m.runs.iter().map(|r| r.signs).collect();
        for kind in [Signs::Mixed, Signs::NonNegative, Signs::NonPositive] {
            assert!(kinds.contains(&kind), "{kind:?} runs");
        }
        let x: Vec<f32> = (0..m.padded)
            .map(|j| match j {
                _ if j >= n => 0.0,
                _ if j % 11 == 0 => 0.0,
                _ => 0.1 + (j % 13) as f32 * 0.3,
            })
            .collect();
        let entry = |i: usize, j: usize| match i.cmp(&j) {
            std::cmp::Ordering::Less => f64::from(blocky(i, j)),
            std::cmp::Ordering::Greater => f64::from(blocky(j, i)),
            std::cmp::Ordering::Equal => 0.0,
        };
        // Two bands as the threads cut them, and one.
        for cuts in [vec![0, n], vec![0, 2 * (n / 5), n]] {
            let mut a = vec![0.0; n];
            let mut c = vec![0.0; n];
            for band in cuts.windows(2) {
                let rows = band[0]..band[1];
                let mut sums = PassSums::new(rows.len(), m.padded);
                band_pass(&m, rows.clone(), &x, &mut sums);
                for (k, i) in rows.clone().enumerate() {
                    a[i] += sums.row_a[k];
                    c[i] += sums.row_c[k];
                }
                for j in rows.start..n {
                    a[j] += sums.col_a[j];
                    c[j] += sums.col_c[j];
                }
            }
            for i in 0..n {
                let (mut a_ref, mut c_ref, mut scale) = (0.0, 0.0, 0.0);
                for (j, &xj) in x[..n].iter().enumerate() {
                    let (v, xj) = (entry(i, j), f64::from(xj));
                    a_ref += v.max(0.0) * xj;
                    c_ref += (-v).max(0.0) * xj;
                    scale += v.abs() * xj;
                }
                let tol = 1e-6 * scale.max(1e-30);
                assert!(
                    (a[i] - a_ref).abs() <= tol,
                    "a[{i}] {} vs {a_ref} ({cuts:?})",
                    a[i]
                );
                assert!(
                    (c[i] - c_ref).abs() <= tol,
                    "c[{i}] {} vs {c_ref} ({cuts:?})",
                    c[i]
                );
            }
        }
    }

    #[test]
    fn runs_cover_the_nonzero_chunks_within_row_blocks() {
        let n = 2 * ROW_BLOCK + 77;
        let m = UpperTriangle::new(n, blocky);
        for i in (0..n).step_by(2) {
            let rows = [m.row(i), m.row((i + 1).min(n - 1))];
            let runs = m.pair_runs(i);
            for w in runs.windows(2) {
                assert!(w[0].end <= w[1].start, "runs in order");
            }
            for run in runs {
                let (b, e) = (run.start as usize, run.end as usize);
                assert_eq!(b / ROW_BLOCK, (e - 1) / ROW_BLOCK, "run inside one block");
                let v = || rows.iter().flat_map(|r| &r[b..e]);
                match run.signs {
                    Signs::NonNegative => assert!(v().all(|&v| v >= 0.0)),
                    Signs::NonPositive => assert!(v().all(|&v| v <= 0.0)),
                    Signs::Mixed => assert!(v().any(|&v| v > 0.0) && v().any(|&v| v < 0.0)),
                }
            }
            // Every chunk with a nonzero entry is in a run.
            for start in (0..rows[0].len()).step_by(CHUNK) {
                let nonzero = rows
                    .iter()
                    .any(|r| r[start..start + CHUNK].iter().any(|&v| v != 0.0));
                let covered = runs
                    .iter()
                    .any(|r| (r.start as usize..r.end as usize).contains(&start));
                assert_eq!(nonzero, covered, "pair of row {i}, chunk at {start}");
            }
        }
    }
}

//! The inner loop of QADP: the two sums `a = M+ x` and `c = M- x` (`M+ = max(M, 0)`,
//! `M- = max(-M, 0)`) for a symmetric matrix `M` with unit or zero diagonal, stored as its
//! strict upper triangle in single precision, and a vector `x >= 0`.
//!
//! Each stored entry `M_ij` (`j > i`) is read once and used twice: for row `i` (`M_ij x_j`) and
//! for row `j` (`M_ij x_i`, accumulated column-wise), so a pass reads `n^2 / 2` values of 4
//! bytes — a quarter of what a full f64 matrix costs, which matters because the pass is
//! memory-bound. Rows are taken in pairs that share their column range, so the column sums are
//! loaded and stored once per pair. The products are exact splits of `M_ij x_j` (`max(M, 0) - M`
//! is exact in floating point) summed in f32 over short stretches (at most [`ROW_BLOCK`]
//! columns of a row, [`FLUSH_ROWS`] rows of a column) and then in f64, so the sums keep a
//! relative accuracy of ~1e-7, the same order as rounding `M` to f32. On x86-64 with AVX2 and
//! FMA (checked at run time) the loop is compiled for those instructions; elsewhere (including
//! wasm32) the same code is compiled for the baseline target.

use std::ops::Range;

/// Columns per step: two 256-bit registers of f32 per sum.
pub(crate) const CHUNK: usize = 16;
// The final reduction in `pair_sums` is written for 16 lanes.
const _: () = assert!(CHUNK == 16);
/// Row sums go from f32 to f64 every this many columns.
const ROW_BLOCK: usize = 512;
/// Column sums go from f32 to f64 every this many rows.
const FLUSH_ROWS: usize = 32;

/// The strict upper triangle of an `n x n` matrix: row `i` holds columns
/// `start(i) = CHUNK floor(i / CHUNK)` to `padded` (a multiple of [`CHUNK`]), with zeros at
/// `j <= i` and `j >= n`. Rows `2k` and `2k + 1` share their start.
#[derive(Debug, Clone)]
pub(crate) struct UpperTriangle {
    pub(crate) n: usize,
    pub(crate) padded: usize,
    data: Vec<f32>,
    offsets: Vec<usize>,
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
        Self {
            n,
            padded,
            data,
            offsets,
        }
    }

    /// First stored column of row `i`.
    pub(crate) fn start(i: usize) -> usize {
        i / CHUNK * CHUNK
    }

    fn row(&self, i: usize) -> &[f32] {
        &self.data[self.offsets[i]..self.offsets[i] + self.padded - Self::start(i)]
    }
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
/// contributions `M_ij x_i` to the column sums.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn pair_sums<const FUSED: bool>(
    rows: [&[f32]; 2],
    x: &[f32],
    [x0, x1]: [f32; 2],
    col_a: &mut [f32],
    col_c: &mut [f32],
) -> [f64; 4] {
    let mut total = [[0.0f64; CHUNK]; 4];
    let len = x.len();
    for b in (0..len).step_by(ROW_BLOCK) {
        let e = (b + ROW_BLOCK).min(len);
        // Separate arrays (not one 2-D array) so that they live in registers.
        let (mut a0, mut c0) = ([0.0f32; CHUNK], [0.0f32; CHUNK]);
        let (mut a1, mut c1) = ([0.0f32; CHUNK], [0.0f32; CHUNK]);
        let steps = rows[0][b..e]
            .chunks_exact(CHUNK)
            .zip(rows[1][b..e].chunks_exact(CHUNK))
            .zip(x[b..e].chunks_exact(CHUNK))
            .zip(col_a[b..e].chunks_exact_mut(CHUNK))
            .zip(col_c[b..e].chunks_exact_mut(CHUNK));
        for ((((m0, m1), xv), ca), cc) in steps {
            // Local copies: the compiler cannot tell that the stores to the column sums do
            // not alias the other slices, and would otherwise keep everything in memory.
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
        for (t, acc) in total.iter_mut().zip([a0, c0, a1, c1]) {
            for k in 0..CHUNK {
                t[k] += f64::from(acc[k]);
            }
        }
    }
    total.map(|t| {
        let mut s4 = [0.0f64; 4];
        for (k, s) in s4.iter_mut().enumerate() {
            *s = (t[k] + t[k + 4]) + (t[k + 8] + t[k + 12]);
        }
        (s4[0] + s4[2]) + (s4[1] + s4[3])
    })
}

/// Columns a wasm row sum adds in f32 before going to f64: with one 4-lane sum per row (not
/// the 16 lanes of the generic code) this keeps 32 terms per lane, as [`ROW_BLOCK`] does there.
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
const WASM_ROW_BLOCK: usize = ROW_BLOCK * 4 / CHUNK;
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
const _: () = assert!(WASM_ROW_BLOCK % CHUNK == 0);

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
    x: &[f32],
    [x0, x1]: [f32; 2],
    col_a: &mut [f32],
    col_c: &mut [f32],
) -> [f64; 4] {
    use super::wasm_simd::madd_f32x4 as madd4;
    use core::arch::wasm32::{
        f32x4_extract_lane, f32x4_pmax, f32x4_splat, f32x4_sub, v128, v128_load, v128_store,
    };
    const LANES: usize = 4;
    // SAFETY (all loads and stores below): each pointer is the start of a `chunks_exact(4)`
    // chunk of `f32`, so 16 valid bytes; `v128_load`/`v128_store` need no alignment.
    let load = |s: &[f32]| unsafe { v128_load(s.as_ptr().cast::<v128>()) };
    let lanes = |v: v128| {
        f64::from(f32x4_extract_lane::<0>(v))
            + f64::from(f32x4_extract_lane::<1>(v))
            + (f64::from(f32x4_extract_lane::<2>(v)) + f64::from(f32x4_extract_lane::<3>(v)))
    };
    let zero = f32x4_splat(0.0);
    let (x0, x1) = (f32x4_splat(x0), f32x4_splat(x1));
    let mut total = [0.0f64; 4];
    let len = x.len();
    for b in (0..len).step_by(WASM_ROW_BLOCK) {
        let e = (b + WASM_ROW_BLOCK).min(len);
        let (mut a0, mut c0, mut a1, mut c1) = (zero, zero, zero, zero);
        let steps = rows[0][b..e]
            .chunks_exact(LANES)
            .zip(rows[1][b..e].chunks_exact(LANES))
            .zip(x[b..e].chunks_exact(LANES))
            .zip(col_a[b..e].chunks_exact_mut(LANES))
            .zip(col_c[b..e].chunks_exact_mut(LANES));
        for ((((m0, m1), xv), ca), cc) in steps {
            let (m0, m1, xv) = (load(m0), load(m1), load(xv));
            let (p0, p1) = (f32x4_pmax(zero, m0), f32x4_pmax(zero, m1));
            let (q0, q1) = (f32x4_sub(p0, m0), f32x4_sub(p1, m1));
            a0 = madd4(p0, xv, a0);
            c0 = madd4(q0, xv, c0);
            a1 = madd4(p1, xv, a1);
            c1 = madd4(q1, xv, c1);
            let ca_v = madd4(p1, x1, madd4(p0, x0, load(ca)));
            let cc_v = madd4(q1, x1, madd4(q0, x0, load(cc)));
            // SAFETY: as for the loads.
            unsafe {
                v128_store(ca.as_mut_ptr().cast::<v128>(), ca_v);
                v128_store(cc.as_mut_ptr().cast::<v128>(), cc_v);
            }
        }
        for (t, acc) in total.iter_mut().zip([a0, c0, a1, c1]) {
            *t += lanes(acc);
        }
    }
    total
}

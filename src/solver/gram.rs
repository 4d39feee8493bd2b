//! The normal equations of the weighted least-squares system `Gamma X = Theta`:
//! `A = Gamma^T W Gamma` and `b = -Gamma^T W Theta` ([method §5]), accumulated from
//! blocks of rows so that `Gamma` never has to exist whole.
//!
//! `A += G^T W G` for a block `G` of rows is a symmetric rank-k update. Only the upper triangle
//! is computed (mirrored in [`NormalEquations::finish`]), in the classic packed form: rows are
//! taken [`KC`] at a time, the weighted rows are packed into panels of [`NR`] columns (kept in
//! L1), the plain rows into panels of [`MR`] columns (kept in L2), and a 4 x 8 register tile
//! accumulates `sum_r g_ri (w_r g_rj)`. Natively the rows of `A` are shared between threads in
//! bands of equal work; on x86-64 with AVX2 and FMA (checked at run time) the tile loop is
//! compiled for those instructions.
//!
//! [method §5]: crate::method#5-the-solver-qadp

use super::{check_finite, check_len, SolverError};

/// Rows of `Gamma` per packed block.
const KC: usize = 256;
/// Column panels per block of the column loop: `KC * NR * NC_PANELS` f64 = 512 KiB, half of L2.
const NC_PANELS: usize = 32;
/// Rows of `A` per register tile.
const MR: usize = 4;
/// Columns of `A` per register tile: 4 x 8 f64 sums in 16 AVX2 registers natively; 4 x 4 in
/// WebAssembly, whose code the browser maps onto 16 128-bit registers (8 sums, 2 packed rows,
/// a broadcast value).
const NR: usize = if cfg!(target_arch = "wasm32") { 4 } else { 8 };

/// Accumulates `A = sum_r w_r g_r g_r^T` and `b = -sum_r w_r theta_r g_r` over rows `g_r` of
/// `Gamma` (`n` unknowns each), weights `w_r >= 0` and data `theta_r` (arcsec in WSLAP+).
#[derive(Debug, Clone)]
pub struct NormalEquations {
    n: usize,
    /// Row-major `n * n`; only the upper triangle (`j >= i`) is up to date before `finish`.
    a: Vec<f64>,
    b: Vec<f64>,
    rows_added: usize,
}

impl NormalEquations {
    /// An empty accumulator for `n` unknowns (`A = 0`, `b = 0`).
    pub fn new(n: usize) -> Result<Self, SolverError> {
        if n == 0 {
            return Err(SolverError::Empty);
        }
        Ok(Self {
            n,
            a: vec![0.0; n * n],
            b: vec![0.0; n],
            rows_added: 0,
        })
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.n
    }

    /// Rows accumulated so far.
    pub fn rows_added(&self) -> usize {
        self.rows_added
    }

    /// Adds `weights.len()` rows: `rows` is row-major `weights.len() * n` (one row of `Gamma`
    /// each), `weights` are `w_r >= 0`, `theta` the right-hand sides `theta_r`. Checks sizes,
    /// finiteness and signs before touching the sums.
    pub fn add_rows(
        &mut self,
        rows: &[f64],
        weights: &[f64],
        theta: &[f64],
    ) -> Result<(), SolverError> {
        let (n, n_rows) = (self.n, weights.len());
        check_len("rows", rows, n_rows * n)?;
        check_len("theta", theta, n_rows)?;
        check_finite("rows", rows)?;
        check_finite("weights", weights)?;
        check_finite("theta", theta)?;
        if let Some(index) = weights.iter().position(|&w| w < 0.0) {
            return Err(SolverError::NegativeWeight {
                what: "weights",
                index,
                value: weights[index],
            });
        }
        let panels = n.div_ceil(NR);
        let mut packed_b = vec![0.0; panels * KC * NR];
        for (block, (w_block, t_block)) in rows
            .chunks(KC * n)
            .zip(weights.chunks(KC).zip(theta.chunks(KC)))
        {
            for (g, (&w, &t)) in block.chunks_exact(n).zip(w_block.iter().zip(t_block)) {
                for (b_j, g_j) in self.b.iter_mut().zip(g) {
                    *b_j -= w * t * g_j;
                }
            }
            pack_weighted(block, w_block, n, &mut packed_b);
            add_block(&mut self.a, n, block, &packed_b, w_block.len());
        }
        self.rows_added += n_rows;
        Ok(())
    }

    /// `(A, b)`: `A` row-major `n * n` and symmetric, `b` of length `n`.
    pub fn finish(mut self) -> (Vec<f64>, Vec<f64>) {
        let n = self.n;
        for i in 0..n {
            for j in 0..i {
                self.a[i * n + j] = self.a[j * n + i];
            }
        }
        (self.a, self.b)
    }
}

/// `(A, b) = (Gamma^T W Gamma, -Gamma^T W Theta)` for `Gamma` row-major `n_rows * n_cols`,
/// diagonal weights `w` and data `theta` (see [`NormalEquations`]).
pub fn gram_weighted(
    gamma_rows: &[f64],
    n_rows: usize,
    n_cols: usize,
    w: &[f64],
    theta: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), SolverError> {
    check_len("w", w, n_rows)?;
    let mut normal = NormalEquations::new(n_cols)?;
    normal.add_rows(gamma_rows, w, theta)?;
    Ok(normal.finish())
}

/// Packs `w_r g_rj` of a block of `k <= KC` rows into panels `[panel][r][jj]` of `NR` columns,
/// zero beyond column `n`.
fn pack_weighted(block: &[f64], w: &[f64], n: usize, packed: &mut [f64]) {
    let k = w.len();
    for (p, panel) in packed.chunks_exact_mut(KC * NR).enumerate() {
        let j0 = p * NR;
        let width = NR.min(n - j0);
        for (r, dst) in panel.chunks_exact_mut(NR).take(k).enumerate() {
            let src = &block[r * n + j0..r * n + j0 + width];
            for (d, s) in dst.iter_mut().zip(src) {
                *d = w[r] * s;
            }
            dst[width..].fill(0.0);
        }
    }
}

/// The upper triangle of `A += G^T W G` for one block `G` of `k` rows.
fn add_block(a: &mut [f64], n: usize, block: &[f64], packed_b: &[f64], k: usize) {
    let row_panels = n.div_ceil(MR);
    let col_panels = n.div_ceil(NR);
    // Work of row panel q: the column panels from the one holding column q*MR on.
    let work = |q: usize| col_panels - q * MR / NR;
    let threads = if cfg!(target_arch = "wasm32") || n < 256 {
        1
    } else {
        crate::threads::available().min(8)
    };
    let total: usize = (0..row_panels).map(work).sum();
    // Cut the row panels into `threads` contiguous bands of about equal work.
    let mut cuts = vec![0];
    let mut done = 0;
    for q in 0..row_panels {
        done += work(q);
        if done * threads >= total * cuts.len() && cuts.len() < threads {
            cuts.push(q + 1);
        }
    }
    if *cuts.last().unwrap_or(&0) != row_panels {
        cuts.push(row_panels);
    }
    let mut bands = Vec::new();
    let mut rest = a;
    for pair in cuts.windows(2) {
        let rows = (pair[1] * MR).min(n) - pair[0] * MR;
        let (band, tail) = rest.split_at_mut(rows * n);
        bands.push((pair[0], pair[1], band));
        rest = tail;
    }
    let threads = bands.len();
    crate::threads::for_each(bands, threads, |(q0, q1, band)| {
        band_update(band, n, block, packed_b, k, q0, q1);
    });
}

/// Row panels `q0..q1` of `A` (their rows are `band`).
fn band_update(
    band: &mut [f64],
    n: usize,
    block: &[f64],
    packed_b: &[f64],
    k: usize,
    q0: usize,
    q1: usize,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above), the only requirement
            // of a `#[target_feature]` function; the function itself is safe code.
            unsafe { band_update_avx2(band, n, block, packed_b, k, q0, q1) };
            return;
        }
    }
    band_update_body::<false>(band, n, block, packed_b, k, q0, q1);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn band_update_avx2(
    band: &mut [f64],
    n: usize,
    block: &[f64],
    packed_b: &[f64],
    k: usize,
    q0: usize,
    q1: usize,
) {
    band_update_body::<true>(band, n, block, packed_b, k, q0, q1);
}

#[inline(always)]
fn band_update_body<const FUSED: bool>(
    band: &mut [f64],
    n: usize,
    block: &[f64],
    packed_b: &[f64],
    k: usize,
    q0: usize,
    q1: usize,
) {
    // Pack the band's columns of G into panels [q][r][ii] of MR columns.
    let mut packed_a = vec![0.0; (q1 - q0) * k * MR];
    for (q, panel) in (q0..q1).zip(packed_a.chunks_exact_mut(k * MR)) {
        let i0 = q * MR;
        let width = MR.min(n - i0);
        for (r, dst) in panel.chunks_exact_mut(MR).enumerate() {
            dst[..width].copy_from_slice(&block[r * n + i0..r * n + i0 + width]);
        }
    }
    // Column panels in blocks of NC_PANELS (their packed rows stay in L2); within a block each
    // row panel (in L1) meets every column panel of the block, walking along rows of A.
    let col_panels = packed_b.len() / (KC * NR);
    let first_col_panel = q0 * MR / NR;
    for jc in (first_col_panel..col_panels).step_by(NC_PANELS) {
        let jc_end = (jc + NC_PANELS).min(col_panels);
        for (q, panel_a) in (q0..q1).zip(packed_a.chunks_exact(k * MR)) {
            let i0 = q * MR;
            if i0 >= jc_end * NR {
                break;
            }
            let rows = MR.min(n - i0);
            for p in jc.max(i0 / NR)..jc_end {
                let panel_b = &packed_b[p * KC * NR..][..k * NR];
                let tile = tile_product::<FUSED>(panel_a, panel_b);
                let j0 = p * NR;
                let width = NR.min(n - j0);
                for (ii, tile_row) in tile.iter().enumerate().take(rows) {
                    let row = &mut band[(i0 - q0 * MR + ii) * n + j0..][..width];
                    for (dst, v) in row.iter_mut().zip(tile_row) {
                        *dst += v;
                    }
                }
            }
        }
    }
}

/// `tile[ii][jj] = sum_r a[r][ii] b[r][jj]` over the `k` packed rows.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
fn tile_product<const FUSED: bool>(panel_a: &[f64], panel_b: &[f64]) -> [[f64; NR]; MR] {
    let mut acc = [[0.0; NR]; MR];
    for (av, bv) in panel_a.chunks_exact(MR).zip(panel_b.chunks_exact(NR)) {
        for ii in 0..MR {
            for jj in 0..NR {
                acc[ii][jj] = if FUSED {
                    av[ii].mul_add(bv[jj], acc[ii][jj])
                } else {
                    av[ii] * bv[jj] + acc[ii][jj]
                };
            }
        }
    }
    acc
}

/// [`tile_product`] in WebAssembly SIMD, the 4 x 4 tile as 8 `f64x2` sums. Not inlined, on
/// purpose: browsers compile a wasm function with a quick baseline compiler first and optimise
/// it only after it has been called often (no on-stack replacement), and the normal equations
/// of a whole system are one call of `add_rows`. As its own function the tile is optimised
/// after its first few calls (the figures: BENCHMARKS.md).
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
#[inline(never)]
fn tile_product<const FUSED: bool>(panel_a: &[f64], panel_b: &[f64]) -> [[f64; NR]; MR] {
    use super::wasm_simd::madd_f64x2;
    use core::arch::wasm32::{f64x2_extract_lane, f64x2_splat, v128};
    const _: () = assert!(MR == 4 && NR == 4);
    let mut acc: [v128; MR * NR / 2] = [f64x2_splat(0.0); MR * NR / 2];
    for (av, bv) in panel_a.chunks_exact(MR).zip(panel_b.chunks_exact(NR)) {
        let b = [
            core::arch::wasm32::f64x2(bv[0], bv[1]),
            core::arch::wasm32::f64x2(bv[2], bv[3]),
        ];
        for (ii, &a_ii) in av.iter().enumerate() {
            let a = f64x2_splat(a_ii);
            for (q, bq) in b.iter().enumerate() {
                let k = ii * NR / 2 + q;
                acc[k] = madd_f64x2(a, *bq, acc[k]);
            }
        }
    }
    let mut tile = [[0.0; NR]; MR];
    for (ii, row) in tile.iter_mut().enumerate() {
        for q in 0..NR / 2 {
            let v = acc[ii * NR / 2 + q];
            row[2 * q] = f64x2_extract_lane::<0>(v);
            row[2 * q + 1] = f64x2_extract_lane::<1>(v);
        }
    }
    tile
}

//! How much each of some unknowns is measured by the data on its own: for a column `l` of
//! `Gamma`, the share of its weighted squared norm `A_ll` that no combination of the other
//! columns reproduces,
//!
//! ```text
//! share_l = (A_ll - A_lo A_oo^-1 A_ol) / A_ll = 1 / (A_ll (A^-1)_ll),
//! ```
//!
//! one minus the `R^2` of regressing column `l` on the others (`1 / share_l` is the variance
//! inflation factor of statistics). Near 1, the data tell what `l` does from what the rest
//! does; near 0, any change of unknown `l` can be undone by the others, so the data do not fix
//! it and the solver's start and stopping point do. It is the unconstrained measure: the
//! positivity of the unknowns can only add information.
//!
//! Computed on the Jacobi-scaled matrix (unit diagonal) plus [`RIDGE`] times the identity,
//! which keeps the Cholesky factorisation defined when the other columns are linearly
//! dependent (the usual case: neighbouring Gaussian cells are nearly collinear) and puts a
//! floor of about `RIDGE` under a share that is exactly 0. The asked-for columns go last, so
//! that the trailing block of the factor is their Schur complement.

/// Added to the unit diagonal of the scaled matrix.
pub const RIDGE: f64 = 1e-10;
/// Most unknowns for which [`column_independence`] factorises the matrix (`n^3 / 6`
/// multiply-adds, twelve times those of the usual ~1085 unknowns at this size: BENCHMARKS.md,
/// "Figures behind choices in the code").
pub const INDEPENDENCE_MAX_UNKNOWNS: usize = 2500;

/// `share_l` (module documentation) of each column of `cols` in the symmetric positive
/// semi-definite `n x n` matrix `a` (row-major), given all other columns, `cols` included.
/// `None` for a column with no weight (`A_ll = 0`); all `None` when `n` exceeds
/// [`INDEPENDENCE_MAX_UNKNOWNS`] or the factorisation fails (non-finite or indefinite `a`).
pub fn column_independence(a: &[f64], n: usize, cols: &[usize]) -> Vec<Option<f64>> {
    let none = vec![None; cols.len()];
    if cols.is_empty() || n > INDEPENDENCE_MAX_UNKNOWNS || a.len() != n * n {
        return none;
    }
    // The other columns with weight, then the asked-for ones with weight.
    let weighted = |i: usize| a[i * n + i] > 0.0;
    let mut order: Vec<usize> = (0..n)
        .filter(|i| !cols.contains(i) && weighted(*i))
        .collect();
    let first_asked = order.len();
    let asked: Vec<usize> = cols.iter().copied().filter(|&i| weighted(i)).collect();
    order.extend(&asked);
    let m = order.len();
    let scale: Vec<f64> = order.iter().map(|&i| 1.0 / a[i * n + i].sqrt()).collect();
    let mut l = vec![0.0; m * m];
    for r in 0..m {
        for c in 0..=r {
            let v = a[order[r] * n + order[c]] * scale[r] * scale[c];
            l[r * m + c] = if r == c { v + RIDGE } else { v };
        }
    }
    if !cholesky_in_place(&mut l, m) {
        return none;
    }
    // The trailing block B of the factor: B B^T is the Schur complement S of the asked-for
    // columns, and share_l = 1 / (S^-1)_ll (the scaled A_ll is 1).
    let k = asked.len();
    let block = |r: usize, c: usize| l[(first_asked + r) * m + first_asked + c];
    let mut shares = Vec::with_capacity(k);
    for j in 0..k {
        // (S^-1)_jj = |B^-1 e_j|^2, by forward substitution from row j (B is lower triangular).
        let mut y = vec![0.0; k];
        let mut sum = 0.0;
        for r in j..k {
            let rhs = if r == j { 1.0 } else { 0.0 };
            let dot: f64 = (j..r).map(|c| block(r, c) * y[c]).sum();
            y[r] = (rhs - dot) / block(r, r);
            sum += y[r] * y[r];
        }
        shares.push((1.0 / sum).min(1.0));
    }
    cols.iter()
        .map(|c| asked.iter().position(|a| a == c).map(|j| shares[j]))
        .collect()
}

/// Lower Cholesky factor of the symmetric `m x m` matrix whose lower triangle `l` holds
/// (row-major), in place; false if a pivot is not positive or not finite.
///
/// Row by row in the dot-product form, four rows at a time, and each earlier row pair against
/// those four at once ([`dot4x2`]), so that a value loaded serves more than one multiply-add
/// (faster than one row at a time natively and much faster in a browser: BENCHMARKS.md).
pub(super) fn cholesky_in_place(l: &mut [f64], m: usize) -> bool {
    let mut r0 = 0;
    while r0 < m {
        let r1 = (r0 + 4).min(m);
        let full = r1 - r0 == 4;
        let (done, block) = l.split_at_mut(r0 * m);
        if full {
            // Columns left of the block, two at a time (r0 is a multiple of 4), from the
            // finished rows above it: the common prefix of both columns' dot products first,
            // then column c, then the one more term of column c + 1.
            let (b0, rest) = block.split_at_mut(m);
            let (b1, rest) = rest.split_at_mut(m);
            let (b2, b3) = rest.split_at_mut(m);
            let mut rows = [b0, b1, b2, &mut b3[..m]];
            for c in (0..r0).step_by(2) {
                let (row_c, row_d) = (&done[c * m..c * m + m], &done[(c + 1) * m..(c + 2) * m]);
                let prefixes = [&rows[0][..c], &rows[1][..c], &rows[2][..c], &rows[3][..c]];
                let d = dot4x2(prefixes, [&row_c[..c], &row_d[..c]]);
                for (row, [dc, dd]) in rows.iter_mut().zip(d) {
                    row[c] = (row[c] - dc) / row_c[c];
                    row[c + 1] = (row[c + 1] - dd - row[c] * row_d[c]) / row_d[c + 1];
                }
            }
        }
        // The rest of the block's rows, one by one (all of a short last block).
        for r in r0..r1 {
            let (above, rest) = l.split_at_mut(r * m);
            let row_r = &mut rest[..m];
            for c in if full { r0 } else { 0 }..=r {
                let row_c = if c == r {
                    None
                } else {
                    Some(&above[c * m..c * m + m])
                };
                let v = row_r[c] - dot(&row_r[..c], &row_c.unwrap_or(row_r)[..c]);
                if r == c {
                    if !(v > 0.0 && v.is_finite()) {
                        return false;
                    }
                    row_r[r] = v.sqrt();
                } else {
                    row_r[c] = v / above[c * m + c];
                }
            }
        }
        r0 = r1;
    }
    true
}

/// The dot products of each of four rows `x_j` with each of two rows `y_0`, `y_1` (all of the
/// length of `y_0`, which is even), two lanes at a time: each value loaded serves two or four
/// multiply-adds.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
fn dot4x2(x: [&[f64]; 4], y: [&[f64]; 2]) -> [[f64; 2]; 4] {
    debug_assert!(y[0].len() % 2 == 0);
    let mut acc = [[[0.0f64; 2]; 2]; 4];
    for (k, (y0, y1)) in y[0].chunks_exact(2).zip(y[1].chunks_exact(2)).enumerate() {
        for (a, row) in acc.iter_mut().zip(x) {
            let p = &row[2 * k..2 * k + 2];
            for lane in 0..2 {
                a[0][lane] += p[lane] * y0[lane];
                a[1][lane] += p[lane] * y1[lane];
            }
        }
    }
    acc.map(|a| a.map(|[u, v]| u + v))
}

/// [`dot4x2`] in WebAssembly SIMD, with the fused multiply-add of relaxed SIMD where the
/// browser has it. Not inlined, for the reason given at `gram.rs`'s `tile_product`: the whole
/// factorisation is one call, which a browser would run in its baseline compiler's code
/// throughout; not inlined, the first factorisation is nearly as fast as the next ones
/// (BENCHMARKS.md).
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
#[inline(never)]
fn dot4x2(x: [&[f64]; 4], y: [&[f64]; 2]) -> [[f64; 2]; 4] {
    use super::wasm_simd::madd_f64x2 as madd;
    use core::arch::wasm32::{f64x2_extract_lane, f64x2_splat, v128, v128_load};
    /// The two f64 of a `chunks_exact(2)` chunk.
    #[inline(always)]
    fn load(pair: &[f64]) -> v128 {
        assert!(pair.len() == 2);
        // SAFETY: `pair` holds two f64 (16 bytes, checked above); `v128_load` needs no
        // alignment.
        unsafe { v128_load(pair.as_ptr().cast::<v128>()) }
    }
    debug_assert!(y[0].len() % 2 == 0);
    let zero = f64x2_splat(0.0);
    // Eight separate sums (not an array) so that they stay in locals.
    let (mut a0, mut b0, mut a1, mut b1) = (zero, zero, zero, zero);
    let (mut a2, mut b2, mut a3, mut b3) = (zero, zero, zero, zero);
    let steps = y[0]
        .chunks_exact(2)
        .zip(y[1].chunks_exact(2))
        .zip(x[0].chunks_exact(2))
        .zip(x[1].chunks_exact(2))
        .zip(x[2].chunks_exact(2))
        .zip(x[3].chunks_exact(2));
    for (((((y0, y1), p0), p1), p2), p3) in steps {
        let (y0, y1) = (load(y0), load(y1));
        let (p0, p1, p2, p3) = (load(p0), load(p1), load(p2), load(p3));
        (a0, b0) = (madd(p0, y0, a0), madd(p0, y1, b0));
        (a1, b1) = (madd(p1, y0, a1), madd(p1, y1, b1));
        (a2, b2) = (madd(p2, y0, a2), madd(p2, y1, b2));
        (a3, b3) = (madd(p3, y0, a3), madd(p3, y1, b3));
    }
    let acc = [[a0, b0], [a1, b1], [a2, b2], [a3, b3]];
    let lanes = |v: v128| f64x2_extract_lane::<0>(v) + f64x2_extract_lane::<1>(v);
    acc.map(|a| a.map(lanes))
}

/// `sum x_k y_k` with eight partial sums, so that it vectorises.
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0f64; 8];
    let (xc, yc) = (x.chunks_exact(8), y.chunks_exact(8));
    let tail: f64 = xc
        .remainder()
        .iter()
        .zip(yc.remainder())
        .map(|(a, b)| a * b)
        .sum();
    for (a, b) in xc.zip(yc) {
        for k in 0..8 {
            acc[k] += a[k] * b[k];
        }
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A = G^T G` of the columns of `g` (`rows x n`, row-major).
    fn gram(g: &[f64], rows: usize, n: usize) -> Vec<f64> {
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..rows).map(|r| g[r * n + i] * g[r * n + j]).sum();
            }
        }
        a
    }

    #[test]
    fn two_columns_share_one_minus_their_squared_correlation() {
        for rho in [0.0, 0.3, -0.8, 0.999] {
            let a = [1.0, rho, rho, 1.0];
            let share = column_independence(&a, 2, &[1])[0].unwrap();
            let want = 1.0 - rho * rho;
            assert!((share - want).abs() < 1e-9, "rho {rho}: {share} vs {want}");
        }
    }

    #[test]
    fn a_column_the_others_reproduce_has_no_share_and_a_new_direction_keeps_its_own() {
        // Columns: e1, e2, e1 + 2 e2 (reproduced), and 0.6 e1 + 0.8 e3 (a new direction for
        // 0.8^2 of its norm), over four rows with scales that the result must not depend on.
        let rows = 4;
        let base = [
            [1.0, 0.0, 1.0, 0.6],
            [0.0, 1.0, 2.0, 0.0],
            [0.0, 0.0, 0.0, 0.8],
            [0.0; 4],
        ];
        let scales = [3.0, 0.5, 7.0, 2.0];
        let g: Vec<f64> = (0..rows)
            .flat_map(|r| (0..4).map(move |c| base[r][c] * scales[c]))
            .collect();
        let a = gram(&g, rows, 4);
        let shares = column_independence(&a, 4, &[2, 3]);
        assert!(shares[0].unwrap() < 1e-8, "{shares:?}");
        // Given e1, e2 and e1 + 2 e2, what is left of 0.6 e1 + 0.8 e3 is 0.8 e3.
        assert!((shares[1].unwrap() - 0.64).abs() < 1e-8, "{shares:?}");
        // A weightless column has no share; too many unknowns, none is computed.
        let mut z = a.clone();
        for k in 0..4 {
            z[3 * 4 + k] = 0.0;
            z[k * 4 + 3] = 0.0;
        }
        assert_eq!(column_independence(&z, 4, &[3]), vec![None]);
        let big = INDEPENDENCE_MAX_UNKNOWNS + 1;
        assert_eq!(
            column_independence(&vec![0.0; big * big], big, &[0]),
            vec![None]
        );
    }

    #[test]
    fn the_share_matches_a_least_squares_residual() {
        // Eleven columns (two blocks of the factorisation and three rows more) of pseudo-random
        // numbers over 40 rows: the share of the last given the
        // others equals the residual of its least-squares fit on them (normal equations
        // solved by Gaussian elimination), over its squared norm.
        let (rows, n) = (40, 11);
        let g: Vec<f64> = (0..rows * n)
            .map(|k| ((k * 7919 + 13) % 101) as f64 / 101.0 - 0.5)
            .collect();
        let a = gram(&g, rows, n);
        let share = column_independence(&a, n, &[n - 1])[0].unwrap();
        let m = n - 1;
        let mut aug: Vec<Vec<f64>> = (0..m)
            .map(|i| {
                let mut row: Vec<f64> = (0..m).map(|j| a[i * n + j]).collect();
                row.push(a[i * n + n - 1]);
                row
            })
            .collect();
        for p in 0..m {
            let pivot_row = aug[p].clone();
            for row in aug.iter_mut().skip(p + 1) {
                let f = row[p] / pivot_row[p];
                for (v, pv) in row.iter_mut().zip(&pivot_row).skip(p) {
                    *v -= f * pv;
                }
            }
        }
        let mut coef = vec![0.0; m];
        for p in (0..m).rev() {
            let s: f64 = (p + 1..m).map(|c| aug[p][c] * coef[c]).sum();
            coef[p] = (aug[p][m] - s) / aug[p][p];
        }
        let residual: f64 = (0..rows)
            .map(|r| {
                let fit: f64 = (0..m).map(|j| g[r * n + j] * coef[j]).sum();
                (g[r * n + n - 1] - fit).powi(2)
            })
            .sum();
        let want = residual / a[n * n - 1];
        assert!((share - want).abs() < 1e-6 * want, "{share} vs {want}");
    }
}

//! The truncated NFW's near field as a table of polynomials, for maps.
//!
//! A map of a member-galaxy layer evaluates every member at every pixel: for the built-in
//! example 94 halos at 65536 pixels, a quarter of them inside the far-field radius, where the
//! closed form costs a `sqrt`, three logarithms and an `atan`/`acosh` (the C library's natively,
//! Rust's slower `libm` in WebAssembly). The two functions the fields need, `m(x)/x^2` and
//! `m'(x)/x`, depend only on `q = x^2` and `tau`, and are analytic in `q` except at `q = 0`
//! (a logarithmic branch point) and `q = -tau^2`. So each binary octave of `q` is cut into
//! `2^SPLIT_BITS` (2) segments, and on each both functions are interpolated at the
//! [`COEFS`] Chebyshev points of the segment by one polynomial in the segment's own variable
//! `s in [-1, 1]` (the nearest singularity is at least 5 half-widths from a segment's centre,
//! so the interpolation error falls like `9.9^-COEFS`: ~1e-14). The segment and `s` come from
//! the bits of `q` (exponent and leading mantissa bit), without a logarithm or a square root.
//! Below [`Q_MIN`] (within `2^-8 r_s` of the centre) the closed form is used.
//!
//! The table is built from the closed form, which the caller passes in (`COEFS` evaluations
//! per segment, ~700 for `tau = 4`), so it pays when a halo is evaluated at thousands of points: it is made on first
//! use (see [`super::TruncatedNfw`]). Taking the functions as an argument keeps this module a
//! leaf: the profile in `tnfw.rs` owns the closed form and uses the table, not the reverse.

/// Mantissa bits that pick the segment within an octave of `q`.
const SPLIT_BITS: u32 = 1;
/// Coefficients of each segment's polynomials (degree `COEFS - 1`).
pub const COEFS: usize = 14;
/// Smallest `q = x^2` served by the table (`2^-16`, `x = 2^-8`).
pub const Q_MIN: f64 = 1.0 / 65536.0;
/// Bits of an f64 below the segment index: the rest of the mantissa.
const LOCAL_BITS: u32 = 52 - SPLIT_BITS;

/// `m(x)/x^2` and `m'(x)/x` (the units of [`super::tnfw_mass_and_kappa_unit`]) on
/// `Q_MIN <= q < q_end`, piecewise polynomial.
#[derive(Clone)]
pub struct NearTable {
    /// `q.to_bits() >> LOCAL_BITS` of the first segment.
    first_key: u64,
    /// Per segment, per power of `s` (lowest first): `[m/x^2, m'(x)/x]`.
    segments: Vec<[[f64; 2]; COEFS]>,
}

impl std::fmt::Debug for NearTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "NearTable({} segments)", self.segments.len())
    }
}

impl NearTable {
    /// The table of `near(q) = [m/x^2, m'(x)/x]` at `q = x^2` covering `Q_MIN <= q < q_end`
    /// (`q_end > Q_MIN`; it is extended to the end of the octave that holds `q_end`). `near` is
    /// called `COEFS` times per segment.
    pub fn new(q_end: f64, near: impl Fn(f64) -> [f64; 2]) -> Self {
        let first_key = Q_MIN.to_bits() >> LOCAL_BITS;
        let last_key = q_end.max(Q_MIN).to_bits() >> LOCAL_BITS;
        // Chebyshev points s_j = cos(t_j) and the basis T_k(s_j) = cos(k t_j).
        let angle = |j: usize| std::f64::consts::PI * (j as f64 + 0.5) / COEFS as f64;
        let nodes: [f64; COEFS] = std::array::from_fn(|j| angle(j).cos());
        let basis: [[f64; COEFS]; COEFS] =
            std::array::from_fn(|k| std::array::from_fn(|j| (k as f64 * angle(j)).cos()));
        let segments = (first_key..=last_key)
            .map(|key| {
                let start = f64::from_bits(key << LOCAL_BITS);
                let width = f64::from_bits((key + 1) << LOCAL_BITS) - start;
                let values: [[f64; 2]; COEFS] =
                    std::array::from_fn(|j| near(start + 0.5 * (nodes[j] + 1.0) * width));
                let mut out = [[0.0; 2]; COEFS];
                for f in 0..2 {
                    let column: [f64; COEFS] = std::array::from_fn(|j| values[j][f]);
                    for (o, a) in out.iter_mut().zip(monomial(&chebyshev(&column, &basis))) {
                        o[f] = a;
                    }
                }
                out
            })
            .collect();
        Self {
            first_key,
            segments,
        }
    }

    /// `(m/x^2, m'(x)/x)` at `q = x^2`, or `None` outside the table.
    #[inline]
    pub fn eval(&self, q: f64) -> Option<(f64, f64)> {
        let bits = q.to_bits();
        let index = (bits >> LOCAL_BITS).checked_sub(self.first_key)?;
        let segment = self.segments.get(usize::try_from(index).ok()?)?;
        let local = bits & ((1 << LOCAL_BITS) - 1);
        let s = local as f64 * (2.0 / (1u64 << LOCAL_BITS) as f64) - 1.0;
        let (mut a, mut b) = (0.0, 0.0);
        for c in segment.iter().rev() {
            a = a * s + c[0];
            b = b * s + c[1];
        }
        Some((a, b))
    }
}

/// Chebyshev coefficients `c_k` of the interpolant through `values` at the Chebyshev points
/// `s_j = cos(pi (j + 1/2) / N)`, `basis[k][j] = T_k(s_j)`: `f(s) = sum_k c_k T_k(s)`.
fn chebyshev(values: &[f64; COEFS], basis: &[[f64; COEFS]; COEFS]) -> [f64; COEFS] {
    let n = COEFS as f64;
    std::array::from_fn(|k| {
        let sum: f64 = values.iter().zip(&basis[k]).map(|(v, t)| v * t).sum();
        sum * if k == 0 { 1.0 } else { 2.0 } / n
    })
}

/// Power-series coefficients (lowest first) of `sum_k c_k T_k(s)`.
fn monomial(c: &[f64; COEFS]) -> [f64; COEFS] {
    let mut out = [0.0; COEFS];
    // T_{k-1} and T_k as power series.
    let mut prev = [0.0; COEFS];
    let mut cur = [0.0; COEFS];
    prev[0] = 1.0;
    cur[1] = 1.0;
    out[0] += c[0];
    for (k, &ck) in c.iter().enumerate().skip(1) {
        for (o, t) in out.iter_mut().zip(&cur) {
            *o += ck * t;
        }
        if k + 1 < COEFS {
            // T_{k+1} = 2 s T_k - T_{k-1}.
            let mut next = [0.0; COEFS];
            for i in 0..COEFS {
                next[i] = -prev[i] + if i > 0 { 2.0 * cur[i - 1] } else { 0.0 };
            }
            prev = cur;
            cur = next;
        }
    }
    out
}

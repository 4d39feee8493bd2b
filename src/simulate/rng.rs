//! A small deterministic random number generator: SplitMix64 (Steele, Lea & Flood 2014) with
//! Box–Muller normal deviates. The simulation must give the same numbers natively and in wasm
//! for a given seed, so it uses no external crate and no platform entropy.

use std::f64::consts::TAU;

/// SplitMix64: a 64-bit state advanced by the golden-ratio increment and mixed.
#[derive(Debug, Clone)]
pub(crate) struct Rng {
    state: u64,
}

impl Rng {
    /// An independent stream for one purpose (`stream`) of the simulation with `seed`, so that
    /// e.g. redrawing a source does not shift the cluster's numbers.
    pub(crate) fn stream(seed: u64, stream: u64) -> Self {
        let mut r = Self {
            state: seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03),
        };
        // Mix the combined state once so neighbouring seeds start far apart.
        r.next_u64();
        r
    }

    /// The next 64 random bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Standard normal deviate (Box–Muller; `1 - u` keeps the logarithm finite).
    pub(crate) fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
    }

    /// An index in `0..n` (`n >= 1`).
    pub(crate) fn index(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n.saturating_sub(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_and_normal_moments() {
        let mut r = Rng::stream(7, 1);
        let n = 20_000;
        let (mut s, mut s2, mut g, mut g2) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            s += u;
            s2 += u * u;
            let x = r.normal();
            g += x;
            g2 += x * x;
        }
        let nf = n as f64;
        assert!((s / nf - 0.5).abs() < 0.01);
        assert!((s2 / nf - 1.0 / 3.0).abs() < 0.01);
        assert!((g / nf).abs() < 0.03);
        assert!((g2 / nf - 1.0).abs() < 0.05);
    }

    #[test]
    fn streams_differ() {
        let a = Rng::stream(1, 1).next_u64();
        let b = Rng::stream(1, 2).next_u64();
        let c = Rng::stream(2, 1).next_u64();
        assert!(a != b && a != c && b != c);
    }
}

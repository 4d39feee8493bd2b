//! Square maps on the lens plane, laid out as the HFF FITS maps are.
//!
//! Pixel `(i, j)` (column, row; both from 0) has its centre at
//! `x = center.x + (i + 0.5 - n/2) * pixel`, `y = center.y + (j + 0.5 - n/2) * pixel`:
//! `i` grows to +x (West, `CDELT1 < 0`), `j` grows to +y (North). Data are row-major,
//! `data[j * n + i]`, which is FITS order (first axis fastest, first row at the bottom).

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// Where a square map lies: `pixels` a side covering `size_arcsec`, centred on `center`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MapGeometry {
    pub pixels: usize,
    pub size_arcsec: f64,
    pub center: DVec2,
}

impl MapGeometry {
    /// A map centred on (0, 0).
    pub fn centered(size_arcsec: f64, pixels: usize) -> Self {
        Self {
            pixels,
            size_arcsec,
            center: DVec2::ZERO,
        }
    }

    /// Pixel width in arcsec.
    pub fn pixel_arcsec(&self) -> f64 {
        self.size_arcsec / self.pixels as f64
    }

    /// Centre of pixel `(i, j)` in arcsec.
    pub fn pixel_center(&self, i: usize, j: usize) -> DVec2 {
        self.pixel_to_arcsec(i as f64, j as f64)
    }

    /// Fractional pixel coordinates (0 = centre of the first pixel) to arcsec.
    pub fn pixel_to_arcsec(&self, i: f64, j: f64) -> DVec2 {
        let half = self.pixels as f64 / 2.0;
        let s = self.pixel_arcsec();
        self.center + DVec2::new((i + 0.5 - half) * s, (j + 0.5 - half) * s)
    }

    /// Arcsec to fractional pixel coordinates (inverse of [`Self::pixel_to_arcsec`]).
    pub fn arcsec_to_pixel(&self, p: DVec2) -> DVec2 {
        let half = self.pixels as f64 / 2.0;
        (p - self.center) / self.pixel_arcsec() + DVec2::splat(half - 0.5)
    }
}

/// One quantity sampled on a [`MapGeometry`].
#[derive(Debug, Clone, PartialEq)]
pub struct Map {
    pub geometry: MapGeometry,
    /// Row-major values, `data[j * pixels + i]`.
    pub data: Vec<f64>,
}

impl Map {
    /// Evaluates `f` at every pixel centre.
    pub fn from_fn(geometry: MapGeometry, mut f: impl FnMut(DVec2) -> f64) -> Self {
        let n = geometry.pixels;
        let mut data = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                data.push(f(geometry.pixel_center(i, j)));
            }
        }
        Self { geometry, data }
    }

    /// The value at pixel `(i, j)`.
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.data[j * self.geometry.pixels + i]
    }

    /// Bilinear interpolation at `p` (arcsec), clamped to the map's edge pixels.
    pub fn sample(&self, p: DVec2) -> f64 {
        let n = self.geometry.pixels;
        let q = self.geometry.arcsec_to_pixel(p);
        let max = (n - 1) as f64;
        let (x, y) = (q.x.clamp(0.0, max), q.y.clamp(0.0, max));
        let (i0, j0) = (
            (x.floor() as usize).min(n.saturating_sub(2)),
            (y.floor() as usize).min(n.saturating_sub(2)),
        );
        if n < 2 {
            return self.data[0];
        }
        let (tx, ty) = (x - i0 as f64, y - j0 as f64);
        let a = self.at(i0, j0) * (1.0 - tx) + self.at(i0 + 1, j0) * tx;
        let b = self.at(i0, j0 + 1) * (1.0 - tx) + self.at(i0 + 1, j0 + 1) * tx;
        a * (1.0 - ty) + b * ty
    }

    /// Catmull-Rom (bicubic) interpolation at `p` (arcsec), exact for quadratics, with an error
    /// of order `h^3` against bilinear's `h^2`: for a map of a smooth field several pixels wide.
    /// The 4 x 4 stencil is clamped to the map's pixels.
    pub fn sample_cubic(&self, p: DVec2) -> f64 {
        let n = self.geometry.pixels;
        if n < 2 {
            return self.data.first().copied().unwrap_or(f64::NAN);
        }
        let q = self.geometry.arcsec_to_pixel(p);
        let max = (n - 1) as f64;
        let (x, y) = (q.x.clamp(0.0, max), q.y.clamp(0.0, max));
        let (i0, j0) = (x.floor().min(max - 1.0), y.floor().min(max - 1.0));
        let weights = |t: f64| {
            let (t2, t3) = (t * t, t * t * t);
            [
                0.5 * (-t3 + 2.0 * t2 - t),
                0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
                0.5 * (-3.0 * t3 + 4.0 * t2 + t),
                0.5 * (t3 - t2),
            ]
        };
        let (wx, wy) = (weights(x - i0), weights(y - j0));
        let index = |base: f64, k: usize| {
            (base as isize + k as isize - 1).clamp(0, n as isize - 1) as usize
        };
        let mut sum = 0.0;
        for (b, wyb) in wy.iter().enumerate() {
            let j = index(j0, b);
            let row: f64 = wx
                .iter()
                .enumerate()
                .map(|(a, wxa)| wxa * self.at(index(i0, a), j))
                .sum();
            sum += wyb * row;
        }
        sum
    }

    /// Smallest and largest finite value.
    pub fn min_max(&self) -> (f64, f64) {
        self.data
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_sampling_is_exact_for_quadratics_and_clamps_at_the_edge() {
        // Points with the whole 4 x 4 stencil inside the map.
        let geometry = MapGeometry::centered(10.0, 11);
        let f = |p: DVec2| 1.0 + 0.3 * p.x - 0.2 * p.y + 0.05 * p.x * p.x - 0.04 * p.x * p.y;
        let map = Map::from_fn(geometry, f);
        for p in [
            DVec2::new(0.13, -1.71),
            DVec2::new(2.5, 3.25),
            DVec2::new(-3.0, 0.6),
        ] {
            assert!((map.sample_cubic(p) - f(p)).abs() < 1e-12, "at {p}");
        }
        // At a pixel centre it is the pixel's value; beyond the map, the edge's.
        let corner = geometry.pixel_center(10, 10);
        assert!((map.sample_cubic(corner) - map.at(10, 10)).abs() < 1e-12);
        assert!((map.sample_cubic(corner + DVec2::splat(5.0)) - map.at(10, 10)).abs() < 1e-12);
    }
}

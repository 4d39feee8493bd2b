//! Square maps on the lens plane, laid out as the HFF FITS maps are.
//!
//! Pixel `(i, j)` (column, row; both from 0) has its centre at
//! `x = center.x + (i + 0.5 - n/2) * pixel`, `y = center.y + (j + 0.5 - n/2) * pixel`:
//! `i` grows to +x (West, `CDELT1 < 0`), `j` grows to +y (North). Data are row-major,
//! `data[j * n + i]`, which is FITS order (first axis fastest, first row at the bottom).

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Where a square map lies: `pixels` a side covering `size_arcsec`, centred on `center`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MapGeometry {
    pub pixels: usize,
    pub size_arcsec: f64,
    pub center: DVec2,
}

/// In words, for messages: "648 x 648 pixels over 129.6″ centred on (0″, 0″)".
impl std::fmt::Display for MapGeometry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{0} x {0} pixels over {1}″ centred on ({2}″, {3}″)",
            self.pixels, self.size_arcsec, self.center.x, self.center.y
        )
    }
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

/// Largest `|mu|` that [`LensMaps::magnification`] returns: on a critical line
/// (`|det A| < 1 / MAGNIFICATION_CLAMP`) the magnification is this value with the sign of `det A`.
pub const MAGNIFICATION_CLAMP: f64 = 1.0e6;

/// The magnification `1/det A` of one point with `kappa`, `gamma1`, `gamma2` for `f =
/// D_ls/D_s`, clamped as [`LensMaps::magnification`] says (NaN without data).
pub fn magnification_at_point(f: f64, kappa: f64, gamma1: f64, gamma2: f64) -> f64 {
    let det = (1.0 - f * kappa).powi(2) - f * f * (gamma1 * gamma1 + gamma2 * gamma2);
    if det.is_nan() {
        f64::NAN
    } else if det.abs() >= 1.0 / MAGNIFICATION_CLAMP {
        1.0 / det
    } else if det < 0.0 {
        -MAGNIFICATION_CLAMP
    } else {
        MAGNIFICATION_CLAMP
    }
}

/// What can be wrong with maps handed to [`LensMaps::from_deflection`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MapsError {
    #[error("the deflection maps do not cover the same field: alpha_x has {alpha_x}, alpha_y has {alpha_y}")]
    GeometryMismatch {
        alpha_x: MapGeometry,
        alpha_y: MapGeometry,
    },
    #[error(
        "{map}: a map of {pixels} pixels a side must hold {expected} values, it holds {found}"
    )]
    WrongLength {
        map: &'static str,
        pixels: usize,
        expected: usize,
        found: usize,
    },
    #[error("deflection maps: size {size_arcsec} arcsec must be finite and positive")]
    BadSize { size_arcsec: f64 },
    #[error("{map}: needs at least 2x2 pixels to take derivatives, has {pixels} a side")]
    TooSmall { map: &'static str, pixels: usize },
    #[error("the deflection maps have no pixel with data (every pixel is NaN or blank)")]
    NoData,
    #[error("{map}: pixel (column {i}, row {j}) holds {value}, which is not finite")]
    NotFinite {
        map: &'static str,
        i: usize,
        j: usize,
        value: f64,
    },
}

/// The lens fields on a [`MapGeometry`], all at `D_ls/D_s = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct LensMaps {
    /// Convergence `kappa = Sigma / Sigma_cr_ref` (dimensionless).
    pub kappa: Map,
    /// Shear component `gamma1 = (psi_xx - psi_yy)/2` (dimensionless).
    pub gamma1: Map,
    /// Shear component `gamma2 = psi_xy` (dimensionless).
    pub gamma2: Map,
    /// Deflection along +x (column direction) in arcsec.
    pub alpha_x: Map,
    /// Deflection along +y (row direction) in arcsec.
    pub alpha_y: Map,
}

impl LensMaps {
    /// Five maps of zeros on `geometry`.
    pub fn zeros(geometry: MapGeometry) -> LensMaps {
        let n = geometry.pixels;
        let zero = || Map {
            geometry,
            data: vec![0.0; n * n],
        };
        LensMaps {
            kappa: zero(),
            gamma1: zero(),
            gamma2: zero(),
            alpha_x: zero(),
            alpha_y: zero(),
        }
    }

    /// Builds the maps from published deflection maps (arcsec, e.g. HFF `_x-arcsec-deflect`):
    /// `kappa = (dax/dx + day/dy)/2`, `gamma1 = (dax/dx - day/dy)/2`,
    /// `gamma2 = (dax/dy + day/dx)/2`, by central differences (one-sided on the map edges).
    ///
    /// NaN pixels have no data (published maps have NaN or blank borders, see
    /// [`crate::FitsImage::to_map_no_data`]): a pixel without data in either map has none in
    /// both and NaN in every derived map; next to one, the differences are one-sided as on the
    /// map edges (NaN with no neighbour along an axis). Infinite values are refused, and so are
    /// maps with no data at all.
    pub fn from_deflection(mut alpha_x: Map, mut alpha_y: Map) -> Result<LensMaps, MapsError> {
        if alpha_x.geometry != alpha_y.geometry {
            return Err(MapsError::GeometryMismatch {
                alpha_x: alpha_x.geometry,
                alpha_y: alpha_y.geometry,
            });
        }
        for (name, map) in [("alpha_x", &alpha_x), ("alpha_y", &alpha_y)] {
            check_map_no_data(name, map)?;
        }
        for k in 0..alpha_x.data.len() {
            if alpha_x.data[k].is_nan() || alpha_y.data[k].is_nan() {
                (alpha_x.data[k], alpha_y.data[k]) = (f64::NAN, f64::NAN);
            }
        }
        if alpha_x.data.iter().all(|v| v.is_nan()) {
            return Err(MapsError::NoData);
        }
        let geometry = alpha_x.geometry;
        if !(geometry.size_arcsec.is_finite() && geometry.size_arcsec > 0.0) {
            return Err(MapsError::BadSize {
                size_arcsec: geometry.size_arcsec,
            });
        }
        let n = geometry.pixels;
        let h = geometry.pixel_arcsec();
        let mut kappa = vec![0.0; n * n];
        let mut gamma1 = vec![0.0; n * n];
        let mut gamma2 = vec![0.0; n * n];
        for j in 0..n {
            for i in 0..n {
                let (axx, axy) = gradient(&alpha_x, i, j, h);
                let (ayx, ayy) = gradient(&alpha_y, i, j, h);
                let k = j * n + i;
                kappa[k] = 0.5 * (axx + ayy);
                gamma1[k] = 0.5 * (axx - ayy);
                gamma2[k] = 0.5 * (axy + ayx);
            }
        }
        let wrap = |data| Map { geometry, data };
        Ok(LensMaps {
            kappa: wrap(kappa),
            gamma1: wrap(gamma1),
            gamma2: wrap(gamma2),
            alpha_x,
            alpha_y,
        })
    }

    /// The geometry shared by all five maps.
    pub fn geometry(&self) -> MapGeometry {
        self.kappa.geometry
    }

    /// Magnification for a source with `f = D_ls/D_s`:
    /// `mu = 1/((1 - f kappa)^2 - f^2 |gamma|^2)`. Where `|det A| < 1/MAGNIFICATION_CLAMP` (on a
    /// critical line) the result is `±MAGNIFICATION_CLAMP` with the sign of `det A` (`+` for an
    /// exact zero), so the map is finite wherever the fields are; a pixel without data (NaN)
    /// stays NaN.
    pub fn magnification(&self, f: f64) -> Map {
        self.pointwise(|k, g1, g2| magnification_at_point(f, k, g1, g2))
    }

    /// The eigenvalues of the lensing Jacobian for `f = D_ls/D_s`, `(lambda_t, lambda_r)` with
    /// `lambda_t = 1 - f (kappa + |gamma|)` (zero on tangential critical curves) and
    /// `lambda_r = 1 - f (kappa - |gamma|)` (zero on radial critical curves).
    pub fn eigen_maps(&self, f: f64) -> (Map, Map) {
        let len = self.kappa.data.len();
        let (mut lambda_t, mut lambda_r) = (Vec::with_capacity(len), Vec::with_capacity(len));
        let fields = self
            .kappa
            .data
            .iter()
            .zip(&self.gamma1.data)
            .zip(&self.gamma2.data);
        for ((&k, &g1), &g2) in fields {
            // |gamma| by a plain square root: hypot's overflow guard is far slower, and a shear
            // beyond 1e150 is no lens.
            let g = (g1 * g1 + g2 * g2).sqrt();
            lambda_t.push(1.0 - f * (k + g));
            lambda_r.push(1.0 - f * (k - g));
        }
        let geometry = self.geometry();
        (
            Map {
                geometry,
                data: lambda_t,
            },
            Map {
                geometry,
                data: lambda_r,
            },
        )
    }

    /// A map of `g(kappa, gamma1, gamma2)` at every pixel.
    fn pointwise(&self, g: impl Fn(f64, f64, f64) -> f64) -> Map {
        let data = self
            .kappa
            .data
            .iter()
            .zip(&self.gamma1.data)
            .zip(&self.gamma2.data)
            .map(|((&k, &g1), &g2)| g(k, g1, g2))
            .collect();
        Map {
            geometry: self.geometry(),
            data,
        }
    }
}

/// Checks that `map` has the right length, at least 2x2 pixels and only finite values.
/// As [`check_map`], but NaN (no data) is allowed; infinities are not.
fn check_map_no_data(name: &'static str, map: &Map) -> Result<(), MapsError> {
    let n = map.geometry.pixels;
    let mut finite = map.clone();
    let infinite = map.data.iter().position(|v| v.is_infinite());
    if let Some(k) = infinite {
        return Err(MapsError::NotFinite {
            map: name,
            i: k % n.max(1),
            j: k / n.max(1),
            value: map.data[k],
        });
    }
    finite
        .data
        .iter_mut()
        .for_each(|v| *v = if v.is_nan() { 0.0 } else { *v });
    check_map(name, &finite)
}

fn check_map(name: &'static str, map: &Map) -> Result<(), MapsError> {
    let n = map.geometry.pixels;
    if n < 2 {
        return Err(MapsError::TooSmall {
            map: name,
            pixels: n,
        });
    }
    if map.data.len() != n * n {
        return Err(MapsError::WrongLength {
            map: name,
            pixels: n,
            expected: n * n,
            found: map.data.len(),
        });
    }
    match map.data.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(MapsError::NotFinite {
            map: name,
            i: k % n,
            j: k / n,
            value: map.data[k],
        }),
        None => Ok(()),
    }
}

/// `(d/dx, d/dy)` of `map` at pixel `(i, j)`: central differences, one-sided on the edges
/// and next to pixels without data (NaN); NaN at a pixel without data or with no neighbour
/// with data along an axis. `h` is the pixel width in arcsec; the map must have at least 2
/// pixels a side.
fn gradient(map: &Map, i: usize, j: usize, h: f64) -> (f64, f64) {
    let n = map.geometry.pixels;
    let here = map.at(i, j);
    let with_data = |k: usize, at: &dyn Fn(usize) -> f64| Some(k).filter(|&k| !at(k).is_nan());
    let axis = |c: usize, at: &dyn Fn(usize) -> f64| -> f64 {
        let lo = c.checked_sub(1).and_then(|k| with_data(k, at)).unwrap_or(c);
        let hi = Some(c + 1)
            .filter(|&k| k < n)
            .and_then(|k| with_data(k, at))
            .unwrap_or(c);
        if here.is_nan() || hi == lo {
            return f64::NAN;
        }
        (at(hi) - at(lo)) / ((hi - lo) as f64 * h)
    };
    let dx = axis(i, &|k| map.at(k, j));
    let dy = axis(j, &|k| map.at(i, k));
    (dx, dy)
}

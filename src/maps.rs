//! Convergence, shear, deflection and magnification maps of a lens ([method §6]).
//!
//! All stored maps use the reference normalisation `D_ls/D_s = 1`; the source-dependent
//! products (magnification, eigenvalues) take `f = D_ls/D_s` of the source.
//!
//! [method §6]: crate::method#6-products

use thiserror::Error;

use crate::grid::{Map, MapGeometry};
use crate::profiles::MassComponent;

/// Largest `|mu|` that [`LensMaps::magnification`] returns: on a critical line
/// (`|det A| < 1 / MAGNIFICATION_CLAMP`) the magnification is this value with the sign of `det A`.
pub const MAGNIFICATION_CLAMP: f64 = 1.0e6;

/// What can be wrong with maps handed to [`LensMaps::from_deflection`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MapsError {
    #[error("deflection maps differ in geometry: alpha_x is {alpha_x:?}, alpha_y is {alpha_y:?}")]
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

/// The five output rows of one map row: `[kappa, gamma1, gamma2, alpha_x, alpha_y]`.
type RowSlices<'a> = [&'a mut [f64]; 5];

/// Adds, to whole rows `first_row..` of the five maps, the sum of the `parts` at the pixel
/// centres (summed in order at each pixel, as [`crate::profiles::Lens`] does).
fn fill_rows(
    parts: &[&dyn MassComponent],
    geometry: &MapGeometry,
    first_row: usize,
    out: RowSlices,
) {
    let n = geometry.pixels;
    let [kappa, gamma1, gamma2, alpha_x, alpha_y] = out;
    for (k, kap) in kappa.iter_mut().enumerate() {
        let p = geometry.pixel_center(k % n, first_row + k / n);
        let (a, [xx, xy, yy]) = parts
            .iter()
            .fold((glam::DVec2::ZERO, [0.0; 3]), |(a, h), c| {
                let (da, dh) = c.deflection_hessian(p);
                (a + da, [h[0] + dh[0], h[1] + dh[1], h[2] + dh[2]])
            });
        *kap += 0.5 * (xx + yy);
        gamma1[k] += 0.5 * (xx - yy);
        gamma2[k] += xy;
        alpha_x[k] += a.x;
        alpha_y[k] += a.y;
    }
}

/// Adds the sum of `parts` to every pixel of `maps`, evaluating
/// [`MassComponent::deflection_hessian`] at each pixel centre: `kappa = (psi_xx + psi_yy)/2`,
/// `gamma1 = (psi_xx - psi_yy)/2`, `gamma2 = psi_xy`, `alpha` in arcsec. Natively the rows are
/// split over all available threads; on wasm32 it runs serially.
pub fn add_pixelwise(parts: &[&dyn MassComponent], maps: &mut LensMaps) {
    let geometry = maps.geometry();
    let LensMaps {
        kappa,
        gamma1,
        gamma2,
        alpha_x,
        alpha_y,
    } = maps;
    fill_parallel(
        parts,
        &geometry,
        [
            &mut kappa.data,
            &mut gamma1.data,
            &mut gamma2.data,
            &mut alpha_x.data,
            &mut alpha_y.data,
        ],
    );
}

impl LensMaps {
    /// The lens fields at every pixel centre: `alpha` from `deflection`, and
    /// `kappa = (psi_xx + psi_yy)/2`, `gamma1 = (psi_xx - psi_yy)/2`, `gamma2 = psi_xy` from the
    /// Hessian. Components with a whole-map method ([`MassComponent::add_to_maps`], e.g. the
    /// FFT convolution of a regular grid of cells) use it; the others are evaluated pixel by
    /// pixel as in [`Self::from_lens_pixelwise`].
    pub fn from_lens(lens: &dyn MassComponent, geometry: MapGeometry) -> LensMaps {
        let mut maps = Self::zeros(geometry);
        if !lens.add_to_maps(&mut maps) {
            add_pixelwise(&[lens], &mut maps);
        }
        maps
    }

    /// The reference path: [`MassComponent::deflection_hessian`] of the whole lens at every pixel
    /// centre (see [`add_pixelwise`]), with no whole-map shortcut.
    pub fn from_lens_pixelwise(lens: &dyn MassComponent, geometry: MapGeometry) -> LensMaps {
        let mut maps = Self::zeros(geometry);
        add_pixelwise(&[lens], &mut maps);
        maps
    }

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
    pub fn from_deflection(alpha_x: Map, alpha_y: Map) -> Result<LensMaps, MapsError> {
        if alpha_x.geometry != alpha_y.geometry {
            return Err(MapsError::GeometryMismatch {
                alpha_x: alpha_x.geometry,
                alpha_y: alpha_y.geometry,
            });
        }
        for (name, map) in [("alpha_x", &alpha_x), ("alpha_y", &alpha_y)] {
            check_map(name, map)?;
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
    /// exact zero or a non-finite input), so the map is finite everywhere.
    pub fn magnification(&self, f: f64) -> Map {
        self.pointwise(|k, g1, g2| {
            let det = (1.0 - f * k).powi(2) - f * f * (g1 * g1 + g2 * g2);
            if det.abs() >= 1.0 / MAGNIFICATION_CLAMP {
                1.0 / det
            } else if det < 0.0 {
                -MAGNIFICATION_CLAMP
            } else {
                MAGNIFICATION_CLAMP
            }
        })
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

/// `(d/dx, d/dy)` of `map` at pixel `(i, j)`: central differences, one-sided on the edges.
/// `h` is the pixel width in arcsec; the map must have at least 2 pixels a side.
fn gradient(map: &Map, i: usize, j: usize, h: f64) -> (f64, f64) {
    let n = map.geometry.pixels;
    let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n - 1));
    let (j0, j1) = (j.saturating_sub(1), (j + 1).min(n - 1));
    let dx = (map.at(i1, j) - map.at(i0, j)) / ((i1 - i0) as f64 * h);
    let dy = (map.at(i, j1) - map.at(i, j0)) / ((j1 - j0) as f64 * h);
    (dx, dy)
}

/// Splits the rows of the five output maps into one band per thread.
#[cfg(not(target_arch = "wasm32"))]
fn fill_parallel(parts: &[&dyn MassComponent], geometry: &MapGeometry, out: RowSlices) {
    let n = geometry.pixels;
    if n == 0 {
        return;
    }
    let threads = crate::threads::available();
    // A few bands per thread balance rows of uneven cost (e.g. a dense cluster core).
    let bands = (threads * 4).min(n);
    let rows_per_band = n.div_ceil(bands);
    let chunk = rows_per_band * n;
    let [k, g1, g2, ax, ay] = out;
    let work: Vec<(usize, RowSlices)> = k
        .chunks_mut(chunk)
        .zip(g1.chunks_mut(chunk))
        .zip(g2.chunks_mut(chunk))
        .zip(ax.chunks_mut(chunk))
        .zip(ay.chunks_mut(chunk))
        .enumerate()
        .map(|(b, ((((k, g1), g2), ax), ay))| (b * rows_per_band, [k, g1, g2, ax, ay]))
        .collect();
    crate::threads::for_each(work, threads, |(row, slices)| {
        fill_rows(parts, geometry, row, slices);
    });
}

/// wasm32 has no threads here: fill every row in turn.
#[cfg(target_arch = "wasm32")]
fn fill_parallel(parts: &[&dyn MassComponent], geometry: &MapGeometry, out: RowSlices) {
    fill_rows(parts, geometry, 0, out);
}

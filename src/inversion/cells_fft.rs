//! Exact product maps of a [`super::GridMass`] by FFT convolution.
//!
//! Map pixel `(i, j)` has its centre at `x_0 + (i, j) p` (`p` the pixel width, arcsec). A set of
//! cells of one width `s` whose centres are `c_ref + (a, b) p` for integers `(a, b)` (a sub-lattice
//! of the pixel lattice, with any constant offset: the half-pixel shift of cell centres against
//! pixel centres is part of `x_0 - c_ref`) gives every field `F` of the map as
//! `F(i, j) = sum_(a, b) m_ab K(x_0 - c_ref + (i - a, j - b) p)`: a discrete 2-D convolution of
//! the masses `m_ab = K m / D_l` (arcsec^2) with the field `K` of one unit cell sampled at whole
//! pixel offsets. It is evaluated by zero-padded FFT of side `P >= T + B - 1` (`T` output pixels,
//! `B` lattice points a side), so the circular convolution has no wrap-around and equals the
//! direct sum to rounding (~1e-14 of the largest value). The kernels are exactly the functions
//! of the direct path: [`cell_unit_deflection`] and [`gaussian_unit_hessian`].
//!
//! The default reconstruction map (side = grid width, 512 pixels, 32 cells) has 16 pixels per
//! cell; after `refine` each level is its own group (8, 4, ... pixels per cell). Cells off the
//! pixel lattice, or groups too small to gain, go to the direct per-pixel sum. Cells a
//! fractional number of pixels apart are split by their sub-pixel phase into groups that are
//! each on a lattice (24 cells on 256 pixels: 9 groups).

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::DVec2;
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

use crate::map::LensMaps;
use crate::map::MapGeometry;
use crate::profiles::{cell_unit_deflection, gaussian_unit_hessian};

/// Largest distance (pixels) of a cell centre from the pixel lattice that still counts as on it:
/// far below the rounding of centres computed as `centre + offset * size`, and a shift of
/// `1e-9 p` changes a kernel value by about `1e-9 p / s`, below 1e-10 relative.
const LATTICE_TOL_PIXELS: f64 = 1.0e-9;
/// Cells further than this (pixels) from their group's first cell go to the direct sum: their
/// lattice would be too large to hold.
const MAX_LATTICE_PIXELS: f64 = 1.0e6;
/// Sub-pixel phases of cell centres are compared in steps of `1 / PHASE_BUCKETS` pixel.
const PHASE_BUCKETS: f64 = 1.0e6;
/// Largest FFT side; larger maps or lattices are cut into tiles and blocks. Five complex
/// buffers of this side squared are held at once (5 x 64 MB at 2048).
const MAX_FFT_SIDE: usize = 2048;
/// Cost of one FFT grid point (kernel evaluation, 7 transforms, products) in units of one
/// direct cell-pixel evaluation: measured about 5 (benches/grid_maps_bench.rs, 2 threads);
/// near the break-even either path takes about as long.
const FFT_POINT_COST: f64 = 5.0;

/// How [`super::GridMass::map_plan`] shares the cells between the FFT and the direct sum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MapPlan {
    /// Groups of cells (one width each) done by FFT convolution.
    pub fft_groups: usize,
    /// Cells done by FFT convolution.
    pub fft_cells: usize,
    /// Cells evaluated pixel by pixel.
    pub direct_cells: usize,
}

/// Cells of one width on a sub-lattice of the pixel lattice.
pub(crate) struct Group {
    sigma_arcsec: f64,
    /// `x_0 - c_ref` in arcsec: first pixel centre minus the group's first cell centre.
    base: DVec2,
    /// Lattice index of the lowest point relative to `c_ref` (pixels, per axis).
    low: [i64; 2],
    /// Lattice points a side, `max - low + 1`.
    extent: [usize; 2],
    /// `(index from low, K m / D_l)` of every cell.
    points: Vec<([usize; 2], f64)>,
}

/// How one axis is cut: output tiles of `tile` pixels, lattice blocks of `block` points,
/// transforms of `fft >= tile + block - 1` points.
#[derive(Debug, Clone, Copy)]
struct Split {
    tile: usize,
    block: usize,
    fft: usize,
}

/// Smallest `2^a 3^b 5^c >= n` (sizes rustfft transforms fastest).
fn good_size(n: usize) -> usize {
    let smooth = |mut m: usize| {
        for f in [2, 3, 5] {
            while m % f == 0 {
                m /= f;
            }
        }
        m == 1
    };
    (n.max(1)..).find(|&m| smooth(m)).unwrap_or(n)
}

/// Cuts an axis of `n` output pixels and `m` lattice points so that `tile + block - 1` fits
/// [`MAX_FFT_SIDE`].
fn split(n: usize, m: usize) -> Split {
    let half = MAX_FFT_SIDE / 2;
    let (tile, block) = if n + m - 1 <= MAX_FFT_SIDE {
        (n, m)
    } else if m <= half {
        (MAX_FFT_SIDE + 1 - m, m)
    } else if n <= half {
        (n, MAX_FFT_SIDE + 1 - n)
    } else {
        (half, MAX_FFT_SIDE + 1 - half)
    };
    Split {
        tile,
        block,
        fft: good_size(tile + block - 1),
    }
}

/// Upper bound of the FFT grid points for a group of `extent` lattice points on `n` pixels.
fn fft_points(n: usize, extent: [usize; 2]) -> f64 {
    let (sx, sy) = (split(n, extent[0]), split(n, extent[1]));
    // In f64: the product overflows a 32-bit usize (wasm32) for large lattices.
    let count = |a: usize, b: usize| a.div_ceil(b) as f64;
    count(n, sx.tile)
        * count(n, sy.tile)
        * count(extent[0], sx.block)
        * count(extent[1], sy.block)
        * sx.fft as f64
        * sy.fft as f64
}

/// Cell-pixel evaluations of the direct sum of `cells` cells on `n x n` pixels.
fn direct_points(cells: usize, n: usize) -> f64 {
    cells as f64 * n as f64 * n as f64
}

/// Groups the cells by width and by their offset from the pixel lattice of `geometry`, keeps
/// the groups that the FFT does faster; returns them and the indices of the cells left to the
/// direct sum.
pub(crate) fn plan(
    centers: &[DVec2],
    sigmas_arcsec: &[f64],
    b2_arcsec2: &[f64],
    geometry: &MapGeometry,
) -> (Vec<Group>, Vec<usize>) {
    let n = geometry.pixels;
    let p = geometry.pixel_arcsec();
    let all = || (0..centers.len()).collect();
    if n == 0 || !(p.is_finite() && p > 0.0) || !geometry.center.is_finite() {
        return (Vec::new(), all());
    }
    // Cells of one width whose centres sit at the same fraction of a pixel from the pixel
    // centres form one lattice: with whole pixels per cell that is every cell of the width,
    // otherwise one group per phase (24 cells on 256 pixels: 10 2/3 pixels per cell, 3
    // phases a side, 9 groups of 8 x 8 cells 32 pixels apart). A cell whose phase lies within
    // rounding of a bucket edge may land in a bucket of its own and go to the direct sum.
    let x0 = geometry.pixel_center(0, 0);
    let phase = |c: DVec2| {
        let s = (c - x0) / p;
        let f = s - s.floor();
        let q = |v: f64| ((v * PHASE_BUCKETS).round() as u64) % PHASE_BUCKETS as u64;
        [q(f.x), q(f.y)]
    };
    let mut by_lattice: BTreeMap<(u64, [u64; 2]), Vec<usize>> = BTreeMap::new();
    for (j, s) in sigmas_arcsec.iter().enumerate() {
        let key = match centers[j].is_finite() {
            true => phase(centers[j]),
            false => [u64::MAX; 2],
        };
        by_lattice.entry((s.to_bits(), key)).or_default().push(j);
    }
    let (mut groups, mut direct) = (Vec::new(), Vec::new());
    for cells in by_lattice.into_values() {
        match lattice_group(&cells, centers, sigmas_arcsec, b2_arcsec2, geometry) {
            Some(g) if FFT_POINT_COST * fft_points(n, g.extent) < direct_points(cells.len(), n) => {
                groups.push(g)
            }
            _ => direct.extend(cells),
        }
    }
    direct.sort_unstable();
    (groups, direct)
}

/// The cells `cells` (one width) as a lattice group, or `None` when one is off the pixel
/// lattice or a value is not finite.
fn lattice_group(
    cells: &[usize],
    centers: &[DVec2],
    sigmas_arcsec: &[f64],
    b2_arcsec2: &[f64],
    geometry: &MapGeometry,
) -> Option<Group> {
    let p = geometry.pixel_arcsec();
    let first = *cells.first()?;
    let (c_ref, sigma_arcsec) = (centers[first], sigmas_arcsec[first]);
    if !(sigma_arcsec.is_finite() && sigma_arcsec > 0.0 && c_ref.is_finite()) {
        return None;
    }
    let mut offsets = Vec::with_capacity(cells.len());
    for &j in cells {
        let s = (centers[j] - c_ref) / p;
        let r = s.round();
        let off_lattice = (s - r).abs().max_element() > LATTICE_TOL_PIXELS;
        let too_far = r.abs().max_element() > MAX_LATTICE_PIXELS;
        if off_lattice || too_far || !centers[j].is_finite() || !b2_arcsec2[j].is_finite() {
            return None;
        }
        offsets.push([r.x as i64, r.y as i64]);
    }
    let low = [0, 1].map(|k| offsets.iter().map(|o| o[k]).min().unwrap_or(0));
    let high = [0, 1].map(|k| offsets.iter().map(|o| o[k]).max().unwrap_or(0));
    let points = offsets
        .iter()
        .zip(cells)
        .map(|(o, &j)| {
            let idx = [0, 1].map(|k| (o[k] - low[k]) as usize);
            (idx, b2_arcsec2[j])
        })
        .collect();
    Some(Group {
        sigma_arcsec,
        base: geometry.pixel_center(0, 0) - c_ref,
        low,
        extent: [0, 1].map(|k| (high[k] - low[k]) as usize + 1),
        points,
    })
}

/// Counts of [`plan`] for reporting.
pub(crate) fn summarize(groups: &[Group], direct: &[usize]) -> MapPlan {
    MapPlan {
        fft_groups: groups.len(),
        fft_cells: groups.iter().map(|g| g.points.len()).sum(),
        direct_cells: direct.len(),
    }
}

/// Adds the fields of `group` to `maps` (all at `D_ls/D_s = 1`): `alpha` in arcsec, `kappa`,
/// `gamma1`, `gamma2` from the Hessian as [`LensMaps::from_lens`] does.
pub(crate) fn add_group(group: &Group, maps: &mut LensMaps) {
    let geometry = maps.geometry();
    let n = geometry.pixels;
    let sp = [split(n, group.extent[0]), split(n, group.extent[1])];
    let fft = Fft2::new(sp[0].fft, sp[1].fft);
    let len = fft.nx * fft.ny;
    let zero = Complex64::new(0.0, 0.0);
    let mut mass_spec = vec![zero; len];
    let mut spec = vec![zero; len];
    let mut kernels: [Vec<Complex64>; 3] = std::array::from_fn(|_| vec![zero; len]);
    let scale = 1.0 / len as f64;
    for b0y in (0..group.extent[1]).step_by(sp[1].block) {
        for b0x in (0..group.extent[0]).step_by(sp[0].block) {
            let b0 = [b0x, b0y];
            let mass = &mut kernels[0];
            mass.fill(zero);
            let mut any = false;
            for &(idx, b2) in &group.points {
                let s = [0, 1].map(|k| idx[k].wrapping_sub(b0[k]));
                if s[0] < sp[0].block && s[1] < sp[1].block {
                    mass[s[1] * fft.nx + s[0]].re += b2;
                    any = true;
                }
            }
            if !any {
                continue;
            }
            fft.forward(mass, &mut mass_spec);
            for i0y in (0..n).step_by(sp[1].tile) {
                for i0x in (0..n).step_by(sp[0].tile) {
                    let tile = [i0x, i0y];
                    fill_kernels(group, &geometry, &sp, tile, b0, fft.nx, &mut kernels);
                    for kernel in kernels.iter_mut() {
                        fft.forward(kernel, &mut spec);
                        for (s, m) in spec.iter_mut().zip(&mass_spec) {
                            *s *= m;
                        }
                        fft.inverse(&mut spec, kernel);
                    }
                    add_tile(maps, &kernels, &sp, tile, fft.nx, scale);
                }
            }
        }
    }
}

/// Fills the three packed kernels `(alpha_x + i alpha_y, kappa + i gamma1, gamma2)` of one
/// unit cell for output tile `tile` (first pixel) and lattice block `b0` (first point): entry
/// `t` per axis is the field at offset `base + (t - (block - 1) + tile - b0 - low) p`.
fn fill_kernels(
    group: &Group,
    geometry: &MapGeometry,
    sp: &[Split; 2],
    tile: [usize; 2],
    b0: [usize; 2],
    nx: usize,
    kernels: &mut [Vec<Complex64>; 3],
) {
    let p = geometry.pixel_arcsec();
    let (sigma, inv_2s2) = (
        group.sigma_arcsec,
        0.5 / (group.sigma_arcsec * group.sigma_arcsec),
    );
    let used = [0, 1].map(|k| sp[k].tile + sp[k].block - 1);
    let first = [0, 1].map(|k| tile[k] as i64 - b0[k] as i64 - (sp[k].block as i64 - 1));
    let offset =
        |k: usize, t: usize| group.base[k] + (t as i64 + first[k] - group.low[k]) as f64 * p;
    let dxs: Vec<f64> = (0..used[0]).map(|t| offset(0, t)).collect();
    let zero = Complex64::new(0.0, 0.0);
    let [ka, kb, kc] = kernels;
    let rows: Vec<_> = ka
        .chunks_mut(nx)
        .zip(kb.chunks_mut(nx))
        .zip(kc.chunks_mut(nx))
        .enumerate()
        .collect();
    for_each_band(rows, |(ty, ((ra, rb), rc))| {
        if ty >= used[1] {
            ra.fill(zero);
            rb.fill(zero);
            rc.fill(zero);
            return;
        }
        let dy = offset(1, ty);
        for (tx, &dx) in dxs.iter().enumerate() {
            let (ax, ay) = cell_unit_deflection(dx, dy, inv_2s2);
            let [xx, xy, yy] = gaussian_unit_hessian(dx, dy, sigma);
            ra[tx] = Complex64::new(ax, ay);
            rb[tx] = Complex64::new(0.5 * (xx + yy), 0.5 * (xx - yy));
            rc[tx] = Complex64::new(xy, 0.0);
        }
        ra[used[0]..].fill(zero);
        rb[used[0]..].fill(zero);
        rc[used[0]..].fill(zero);
    });
}

/// Adds the convolved tile (entry `t + block - 1` per axis is output pixel `tile + t`) to the
/// maps, scaled by `1 / (P_x P_y)` (rustfft does not normalise).
fn add_tile(
    maps: &mut LensMaps,
    kernels: &[Vec<Complex64>; 3],
    sp: &[Split; 2],
    tile: [usize; 2],
    nx: usize,
    scale: f64,
) {
    let n = maps.geometry().pixels;
    let width = sp[0].tile.min(n - tile[0]);
    let height = sp[1].tile.min(n - tile[1]);
    for ty in 0..height {
        let src = (ty + sp[1].block - 1) * nx + sp[0].block - 1;
        let dst = (tile[1] + ty) * n + tile[0];
        for tx in 0..width {
            let (a, h, g) = (
                kernels[0][src + tx] * scale,
                kernels[1][src + tx] * scale,
                kernels[2][src + tx] * scale,
            );
            maps.alpha_x.data[dst + tx] += a.re;
            maps.alpha_y.data[dst + tx] += a.im;
            maps.kappa.data[dst + tx] += h.re;
            maps.gamma1.data[dst + tx] += h.im;
            maps.gamma2.data[dst + tx] += g.re;
        }
    }
}

/// A 2-D complex FFT of `nx x ny` points, row-major with `x` fastest. Spectra are kept
/// transposed (`y` fastest): products of two spectra do not care, and it saves a transpose.
struct Fft2 {
    nx: usize,
    ny: usize,
    fwd_x: Arc<dyn Fft<f64>>,
    fwd_y: Arc<dyn Fft<f64>>,
    inv_x: Arc<dyn Fft<f64>>,
    inv_y: Arc<dyn Fft<f64>>,
}

impl Fft2 {
    fn new(nx: usize, ny: usize) -> Self {
        let mut planner = FftPlanner::new();
        Self {
            nx,
            ny,
            fwd_x: planner.plan_fft_forward(nx),
            fwd_y: planner.plan_fft_forward(ny),
            inv_x: planner.plan_fft_inverse(nx),
            inv_y: planner.plan_fft_inverse(ny),
        }
    }

    /// Transforms `data` (clobbered) into `spec` (transposed layout).
    fn forward(&self, data: &mut [Complex64], spec: &mut [Complex64]) {
        rows(data, &self.fwd_x);
        transpose(data, self.ny, self.nx, spec);
        rows(spec, &self.fwd_y);
    }

    /// Unnormalised inverse of [`Self::forward`]: `spec` (clobbered) into `data`.
    fn inverse(&self, spec: &mut [Complex64], data: &mut [Complex64]) {
        rows(spec, &self.inv_y);
        transpose(spec, self.nx, self.ny, data);
        rows(data, &self.inv_x);
    }
}

/// Transforms every row of `data` (rows of `fft.len()` points).
fn rows(data: &mut [Complex64], fft: &Arc<dyn Fft<f64>>) {
    let len = fft.len();
    let bands = crate::threads::available();
    let rows_per_band = (data.len() / len).div_ceil(bands).max(1);
    let chunks: Vec<&mut [Complex64]> = data.chunks_mut(rows_per_band * len).collect();
    for_each_band(chunks, |chunk| fft.process(chunk));
}

/// `dst[c * rows + r] = src[r * cols + c]` for `src` of `rows x cols` (row-major), in blocks
/// for the cache.
fn transpose(src: &[Complex64], rows: usize, cols: usize, dst: &mut [Complex64]) {
    const BLOCK: usize = 32;
    let bands: Vec<(usize, &mut [Complex64])> = dst.chunks_mut(BLOCK * rows).enumerate().collect();
    for_each_band(bands, |(b, band)| {
        let c0 = b * BLOCK;
        let c1 = (c0 + BLOCK).min(cols);
        for r0 in (0..rows).step_by(BLOCK) {
            for c in c0..c1 {
                let out = &mut band[(c - c0) * rows..];
                for r in r0..(r0 + BLOCK).min(rows) {
                    out[r] = src[r * cols + c];
                }
            }
        }
    });
}

/// Runs `f` on every item, spread over [`crate::threads::available`] threads.
fn for_each_band<T: Send>(items: Vec<T>, f: impl Fn(T) + Sync) {
    crate::threads::for_each(items, crate::threads::available(), f);
}

//! The maps of a lens: every mass component evaluated at every pixel centre, or added by its
//! own whole-map method ([`MassComponent::add_to_maps`], e.g. the FFT convolution of a grid of
//! cells). The maps themselves, and what is derived from them alone, are in [`crate::map`].

use super::MassComponent;
use crate::map::{LensMaps, MapGeometry};

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

/// The components of `lens` that are not made of others ([`MassComponent::parts`]), in order.
fn leaves<'a>(lens: &'a dyn MassComponent, out: &mut Vec<&'a dyn MassComponent>) {
    match lens.parts() {
        [] => out.push(lens),
        parts => parts.iter().for_each(|p| leaves(p.as_ref(), out)),
    }
}

impl LensMaps {
    /// The lens fields at every pixel centre: `alpha` from `deflection`, and
    /// `kappa = (psi_xx + psi_yy)/2`, `gamma1 = (psi_xx - psi_yy)/2`, `gamma2 = psi_xy` from the
    /// Hessian. Components with a whole-map method ([`MassComponent::add_to_maps`], e.g. the
    /// FFT convolution of a regular grid of cells) use it; the others are evaluated pixel by
    /// pixel as in [`Self::from_lens_pixelwise`].
    pub fn from_lens(lens: &dyn MassComponent, geometry: MapGeometry) -> LensMaps {
        let mut maps = Self::zeros(geometry);
        let mut parts = Vec::new();
        leaves(lens, &mut parts);
        let declined: Vec<&dyn MassComponent> = parts
            .into_iter()
            .filter(|c| !c.add_to_maps(&mut maps))
            .collect();
        if !declined.is_empty() {
            add_pixelwise(&declined, &mut maps);
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

//! What a frame needs of the lens, computed once and kept while the lens stays the same.
//!
//! A frame paints every pixel from its deflection (`beta = theta - f alpha(theta)`), and draws
//! the critical curves from the Hessian. Neither depends on the sources: moving a source
//! repaints with the kept deflections and curves and evaluates no lens at all. The curves are
//! traced on a grid of at most [`CURVE_PIXELS`] a side (the marching squares interpolate
//! between pixel centres, and critical curves are smooth on that scale: see the playground
//! tests), so the Hessian is evaluated at a quarter of the pixels of a 512² frame; the
//! deflection is evaluated at every pixel of the frame, without the Hessian.

use glam::DVec2;

use crate::curves::critical_curves;
use crate::map::{LensMaps, MapGeometry};
use crate::profiles::MassComponent;

use super::scene::{BuiltScene, Scene, SceneLens};
use super::PlaneCurves;
use crate::cosmology::Cosmology;

/// Most pixels a side of the grid a frame's critical curves, caustics and point-image search
/// use (a frame with fewer pixels uses its own).
pub const CURVE_PIXELS: usize = 256;

/// What the lens of a frame depends on: the kept results hold while this stays equal.
#[derive(Debug, Clone, PartialEq)]
struct LensKey {
    cosmology: Cosmology,
    z_lens: f64,
    fov: f64,
    lenses: Vec<SceneLens>,
}

impl LensKey {
    fn of(scene: &Scene) -> Self {
        Self {
            cosmology: scene.cosmology,
            z_lens: scene.z_lens,
            fov: scene.fov,
            lenses: scene.lenses.clone(),
        }
    }
}

/// The lens's results for the frames drawn since it last changed.
#[derive(Debug, Default)]
pub(super) struct LensCache {
    key: Option<LensKey>,
    /// Deflection (`D_ls/D_s = 1`, arcsec) at every pixel centre of a frame, rows from the
    /// bottom, by frame side.
    deflections: Vec<(usize, Vec<DVec2>)>,
    /// The maps of the curve grid, by side.
    maps: Vec<LensMaps>,
    /// Curves by curve-grid side and source redshift.
    curves: Vec<(usize, f64, PlaneCurves)>,
}

impl LensCache {
    /// Forgets everything unless the lens of `scene` is the one the results are for.
    pub fn keep_if_lens_of(&mut self, scene: &Scene) {
        let key = LensKey::of(scene);
        if self.key.as_ref() != Some(&key) {
            *self = Self {
                key: Some(key),
                ..Self::default()
            };
        }
    }

    /// The deflection at every pixel centre of `geometry` (rows from the bottom).
    pub fn deflection(&mut self, lens: &dyn MassComponent, geometry: MapGeometry) -> &[DVec2] {
        let n = geometry.pixels;
        let k = match self.deflections.iter().position(|(p, _)| *p == n) {
            Some(k) => k,
            None => {
                self.deflections.push((n, deflection_field(lens, geometry)));
                self.deflections.len() - 1
            }
        };
        &self.deflections[k].1
    }

    /// The maps (with Hessian) of the curve grid for a frame of `geometry`.
    pub fn curve_maps(&mut self, lens: &dyn MassComponent, geometry: MapGeometry) -> &LensMaps {
        let grid = curve_geometry(geometry);
        let k = match self.maps.iter().position(|m| m.geometry() == grid) {
            Some(k) => k,
            None => {
                self.maps.push(LensMaps::from_lens(lens, grid));
                self.maps.len() - 1
            }
        };
        &self.maps[k]
    }

    /// The curves and caustics of every source plane of `built` for a frame of `geometry`.
    pub fn curves(&mut self, built: &BuiltScene, geometry: MapGeometry) -> Vec<PlaneCurves> {
        let side = curve_geometry(geometry).pixels;
        let lens = &built.lens;
        let mut out = Vec::with_capacity(built.planes.len());
        for plane in &built.planes {
            let kept = self
                .curves
                .iter()
                .find(|(p, z, _)| *p == side && *z == plane.z);
            if let Some((_, _, c)) = kept {
                out.push(c.clone());
                continue;
            }
            let c = critical_curves(
                self.curve_maps(lens, geometry),
                plane.f,
                plane.z,
                Some(lens),
            );
            let c = PlaneCurves {
                z: plane.z,
                einstein_radius_arcsec: c.einstein_radius_arcsec,
                tangential: c.tangential,
                radial: c.radial,
                tangential_caustics: c.caustics.tangential,
                radial_caustics: c.caustics.radial,
            };
            self.curves.push((side, plane.z, c.clone()));
            out.push(c);
        }
        out
    }
}

/// The grid the curves of a frame of `geometry` are traced on: the same view, at most
/// [`CURVE_PIXELS`] a side.
pub fn curve_geometry(geometry: MapGeometry) -> MapGeometry {
    MapGeometry {
        pixels: geometry.pixels.min(CURVE_PIXELS),
        ..geometry
    }
}

/// [`MassComponent::deflection`] of `lens` (arcsec, `D_ls/D_s = 1`) at every pixel centre of
/// `geometry`, rows from the bottom: the lensed image needs no Hessian.
pub fn deflection_field(lens: &dyn MassComponent, geometry: MapGeometry) -> Vec<DVec2> {
    let n = geometry.pixels;
    (0..n * n)
        .map(|k| lens.deflection(geometry.pixel_center(k % n, k / n)))
        .collect()
}

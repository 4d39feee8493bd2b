//! What a frame needs of the lens, computed once and kept while the lens stays the same.
//!
//! A frame paints every pixel from its deflection (`beta = theta - f alpha(theta)`), and draws
//! the critical curves from the Hessian. Neither depends on the sources: moving a source
//! repaints with the kept deflections and curves and evaluates no lens at all. The curves are
//! traced on a grid of at most [`CURVE_PIXELS`] a side (the marching squares interpolate
//! between pixel centres, and critical curves are smooth on that scale: see the playground
//! tests), so the Hessian is evaluated at a quarter of the pixels of a 512² frame; the
//! deflection is evaluated at every pixel of the frame, without the Hessian. Where a critical
//! curve leaves the view, its caustic (and the Einstein radius) come from the curves traced
//! again over a wider field, so that the source plane shows whole caustics, not pieces.

use glam::DVec2;

use crate::curves::{critical_curves, CriticalCurves, Polyline};
use crate::ds9::polyline_is_open;
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
    pub fn curve_maps(&mut self, lens: &dyn MassComponent, grid: MapGeometry) -> &LensMaps {
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
            let view = curve_geometry(geometry);
            let seen = critical_curves(self.curve_maps(lens, view), plane.f, plane.z, Some(lens));
            // A curve cut by the view's border maps to caustic pieces that end in mid-air, and
            // its Einstein radius counts only closed loops: trace the caustics and the radius
            // on a wider field (the view's own curves stay, at the view's resolution).
            let mut whole = None;
            let mut wide = view;
            for _ in 0..MAX_WIDENINGS {
                if !cut_by_border(whole.as_ref().unwrap_or(&seen), wide) {
                    break;
                }
                wide = MapGeometry {
                    size_arcsec: 2.0 * wide.size_arcsec,
                    ..wide
                };
                whole = Some(critical_curves(
                    self.curve_maps(lens, wide),
                    plane.f,
                    plane.z,
                    Some(lens),
                ));
            }
            let (whole, traced) = match &whole {
                Some(w) => (w, wide),
                None => (&seen, view),
            };
            let c = PlaneCurves {
                z: plane.z,
                einstein_radius_arcsec: whole.einstein_radius_arcsec,
                tangential_caustics: closed(&whole.caustics.tangential, &whole.tangential, traced),
                radial_caustics: closed(&whole.caustics.radial, &whole.radial, traced),
                tangential: closed(&seen.tangential, &seen.tangential, view),
                radial: closed(&seen.radial, &seen.radial, view),
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

/// Times the field of a frame's caustics is doubled, at most, while a critical curve crosses
/// its border (a 40″ view: up to 160″). The pixel count stays: a caustic traced at half or a
/// quarter of the view's resolution lies within a pixel of one traced finely (tested), and a
/// lens release costs a curve grid more per widening, not four.
const MAX_WIDENINGS: usize = 2;

/// True when a critical curve of `curves` is cut by the border of `geometry`.
fn cut_by_border(curves: &CriticalCurves, geometry: MapGeometry) -> bool {
    let mut lines = curves.tangential.iter().chain(&curves.radial);
    lines.any(|line| polyline_is_open(line, &geometry))
}

/// `lines` with the first point repeated at the end of each whose critical curve (`curves`,
/// traced on `geometry`, one per line) is a closed loop, so that a polyline draws all of it.
fn closed(lines: &[Polyline], curves: &[Polyline], geometry: MapGeometry) -> Vec<Polyline> {
    lines
        .iter()
        .zip(curves)
        .map(|(line, curve)| {
            let mut line = line.clone();
            if line.len() > 2 && !polyline_is_open(curve, &geometry) {
                line.push(line[0]);
            }
            line
        })
        .collect()
}

/// [`MassComponent::deflection`] of `lens` (arcsec, `D_ls/D_s = 1`) at every pixel centre of
/// `geometry`, rows from the bottom: the lensed image needs no Hessian.
pub fn deflection_field(lens: &dyn MassComponent, geometry: MapGeometry) -> Vec<DVec2> {
    let n = geometry.pixels;
    (0..n * n)
        .map(|k| lens.deflection(geometry.pixel_center(k % n, k / n)))
        .collect()
}

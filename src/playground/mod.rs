//! The live lensing playground: a scene of lenses and sources, rendered lensed, with its
//! critical curves, caustics and the images of any source point.
//!
//! All the lensing here is the core's ([`crate::MassComponent`] profiles, the lens equation
//! of [`crate::source_position`], [`crate::critical_curves`], [`crate::find_images`],
//! [`crate::arrival_time_days`]); the browser only draws what this module returns.
//!
//! # The scene format (version 1)
//!
//! ```json
//! {"v": 1, "z_lens": 0.3, "fov": 60,
//!  "lenses": [
//!    {"type": "sie", "x": 0, "y": 0, "sigma_v": 900, "q": 0.7, "pa": 20},
//!    {"type": "member", "x": 8, "y": -3, "mag": 19.5},
//!    {"type": "shear", "gamma1": 0.05, "gamma2": 0.0}],
//!  "sources": [
//!    {"type": "sersic", "x": 1.0, "y": 0.5, "z": 2.0, "r_eff": 0.8, "n": 1.0, "q": 0.7, "pa": 30},
//!    {"type": "gaussian", "x": -2, "y": 1, "z": 1.2, "sigma": 0.5},
//!    {"type": "point", "x": 0.3, "y": -0.2, "z": 3.0},
//!    {"type": "image", "x": 0, "y": 0, "z": 2.0, "size": 4, "slot": 1}]}
//! ```
//!
//! - `v`: the format version, 1. Other versions are refused with an error that says so.
//! - `cosmology` (optional, default `{"h0": 70, "omega_m": 0.3}`), `z_lens`: as in the model
//!   file ([`crate::ModelFile`]).
//! - `fov`: side in arcsec of the image-plane view, centred on the origin; `source_fov`
//!   (optional, default `fov / 2`) that of the source-plane view.
//! - `lenses`: any model-file component (`nfw`, `tnfw`, `sis`, `sie`, `point`, `gaussian`,
//!   `shear`, `sheet`, with the model file's units and defaults), or a `member` galaxy at `x`,
//!   `y` (arcsec) of apparent magnitude `mag`, whose truncated NFW halo follows the
//!   inversion's member scaling with its default settings ([`crate::MemberConfig`]), so an
//!   inversion given the same catalogue has `C = 1` as its truth. Every field of a lens is at
//!   `D_ls/D_s = 1`; each source sees it times its own `D_ls/D_s`.
//! - `sources`, each at its own redshift `z > z_lens`: `gaussian` (`sigma`, arcsec),
//!   `sersic` (half-light radius `r_eff`, arcsec, and index `n` in [0.2, 10]), both with
//!   optional axis ratio `q` (default 1) and position angle `pa` (degrees counter-clockwise
//!   from +x, default 0); `point` (its images are found, not painted); `image`, a picture
//!   `size` arcsec on its longer side whose pixels the playground holds under `slot` (the
//!   pixels are not part of the scene: a shared scene shows the picture's place, not the
//!   picture).
//!
//! Positions are arcsec in the frame of [method §1] (+x to the right of the view, +y up).
//! [`Scene::truth_model`] turns a scene into the [`crate::ModelFile`] of its lens.
//!
//! [method §1]: crate::method#1-frames-and-units

use std::collections::HashMap;
use std::sync::{Mutex, PoisonError};

use glam::DVec2;
use serde::Serialize;

use crate::curves::{zero_contours, Polyline};
use crate::image_search::{find_images, ImageKind, ImageSearch, Parity, SearchGrid};
use crate::map::{magnification_at_point, LensMaps, Map, MapGeometry};
use crate::potential::{arrival_time_days, potential_difference, potential_map};
use crate::products::Clock;

mod frame;
mod light;
mod observe;
mod scene;

pub use frame::CURVE_PIXELS;

pub use light::{sersic_b, SourcePixels, BACKGROUND_RGB, SOURCE_RGB};
pub use observe::{
    observe, Observation, ObserveOptions, ObservedSystem, MAX_OBSERVE_PIXELS, MIN_IMAGE_PIXELS,
};
pub use scene::{
    BuiltScene, MemberGalaxy, Scene, SceneError, SceneLens, SourcePlane, SourceSpec,
    DEFAULT_Z_SOURCE, MAX_SCENE_ITEMS, SCENE_VERSION,
};

use frame::LensCache;
use light::{to_byte, Painter};

/// Pixels a side of the grid on which [`Playground::images_of`] starts its search.
pub const IMAGE_SEARCH_PIXELS: usize = 200;
/// Most pixels a side of a frame or a contour map.
pub const MAX_FRAME_PIXELS: usize = 1024;

/// The critical curves and caustics for one source redshift, in arcsec, ready to draw as
/// polylines: a closed loop (and the caustic of one) ends with its first point again; a curve
/// cut by the view's border does not.
#[derive(Debug, Clone, Serialize)]
pub struct PlaneCurves {
    pub z: f64,
    pub einstein_radius_arcsec: f64,
    pub tangential: Vec<Polyline>,
    pub radial: Vec<Polyline>,
    pub tangential_caustics: Vec<Polyline>,
    pub radial_caustics: Vec<Polyline>,
}

/// One image of a point.
#[derive(Debug, Clone, Serialize)]
pub struct PointImage {
    /// Position in arcsec.
    pub x: f64,
    pub y: f64,
    /// Signed magnification.
    pub magnification: f64,
    /// `"+"` or `"-"` (the sign of `det A`).
    pub parity: &'static str,
    /// `"minimum"`, `"saddle"` or `"maximum"` of the arrival time.
    pub kind: &'static str,
    /// Arrival time after the first image, in days.
    pub delay_days: f64,
}

/// The images of one point source of the scene.
#[derive(Debug, Clone, Serialize)]
pub struct PointSourceImages {
    /// Index into [`Scene::sources`].
    pub source: usize,
    pub images: Vec<PointImage>,
}

/// One rendered frame.
#[derive(Debug, Clone, Serialize)]
pub struct Frame {
    /// Pixels a side of both views.
    pub pixels: usize,
    /// The lensed image plane, RGBA, rows from the top (+y up).
    #[serde(skip)]
    pub image_rgba: Vec<u8>,
    /// The unlensed sources on the source-plane view, RGBA, rows from the top.
    #[serde(skip)]
    pub source_rgba: Vec<u8>,
    /// One entry per source redshift, ascending.
    pub curves: Vec<PlaneCurves>,
    /// The images of every point source.
    pub points: Vec<PointSourceImages>,
    /// Time spent in the core, in ms.
    pub compute_ms: f64,
}

/// Where a ray seen at some pixel lands on one source plane.
#[derive(Debug, Clone, Serialize)]
pub struct RayLanding {
    pub z: f64,
    /// Source position in arcsec.
    pub x: f64,
    pub y: f64,
    /// Signed magnification at the pixel for this source plane.
    pub magnification: f64,
}

/// A contour line at one level.
#[derive(Debug, Clone, Serialize)]
pub struct ContourLine {
    pub level: f64,
    pub points: Polyline,
    pub closed: bool,
}

/// What [`Playground::contours`] draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContourKind {
    /// `f kappa` at 0.25, 0.5, 1, 2, 4.
    Kappa,
    /// `|mu|` at 2, 4, 10, 30.
    Magnification,
    /// The arrival time (Fermat potential) of one source's position, in days after its
    /// earliest point on the map, at even steps.
    ArrivalTime,
}

/// Levels of [`ContourKind::Kappa`].
pub const KAPPA_LEVELS: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];
/// Levels of [`ContourKind::Magnification`].
pub const MAGNIFICATION_LEVELS: [f64; 4] = [2.0, 4.0, 10.0, 30.0];
/// Arrival-time contour levels drawn between the map's minimum and its median.
pub const ARRIVAL_LEVELS: usize = 14;

/// A scene, built, with the pixels of its uploaded pictures.
#[derive(Debug)]
pub struct Playground {
    scene: Scene,
    built: BuiltScene,
    pictures: HashMap<u32, SourcePixels>,
    /// The lens's deflections and curves for the frames drawn since it last changed.
    cache: Mutex<LensCache>,
}

impl Playground {
    /// A playground showing `scene` (validated).
    pub fn new(scene: Scene) -> Result<Self, SceneError> {
        let built = scene.build()?;
        Ok(Self {
            scene,
            built,
            pictures: HashMap::new(),
            cache: Mutex::default(),
        })
    }

    /// Replaces the scene, keeping the uploaded pictures; on error the old scene stays.
    pub fn set_scene(&mut self, scene: Scene) -> Result<(), SceneError> {
        self.built = scene.build()?;
        self.scene = scene;
        Ok(())
    }

    /// The scene shown.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The built lens and source planes.
    pub fn built(&self) -> &BuiltScene {
        &self.built
    }

    /// Holds `pixels` for the image sources with this `slot`.
    pub fn set_picture(&mut self, slot: u32, pixels: SourcePixels) {
        self.pictures.insert(slot, pixels);
    }

    /// True if a picture is held under `slot`.
    pub fn has_picture(&self, slot: u32) -> bool {
        self.pictures.contains_key(&slot)
    }

    fn painters(&self) -> Vec<Painter<'_>> {
        self.scene
            .sources
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let pixels = match s {
                    SourceSpec::Image { slot, .. } => self.pictures.get(slot),
                    _ => None,
                };
                Painter::new(*s, k, pixels)
            })
            .collect()
    }

    /// Renders both views at `pixels` a side (clamped to [16, [`MAX_FRAME_PIXELS`]]): every
    /// pixel traced to each source's plane with the lens's deflection, the critical curves of
    /// each source redshift (traced on a grid of at most [`CURVE_PIXELS`] a side) and the
    /// caustics through the exact lens, and the images of the point sources. The deflections
    /// and curves are kept while the lens stays the same: a frame after only the sources
    /// changed evaluates no lens.
    pub fn frame(&self, pixels: usize) -> Frame {
        let clock = Clock::start();
        let n = pixels.clamp(16, MAX_FRAME_PIXELS);
        let geometry = MapGeometry::centered(self.scene.fov, n);
        let lens = &self.built.lens;
        let mut cache = self.cache.lock().unwrap_or_else(PoisonError::into_inner);
        cache.keep_if_lens_of(&self.scene);
        let painters = self.painters();
        let mut image_rgba = vec![0u8; n * n * 4];
        let alpha = cache.deflection(lens, geometry);
        for j in 0..n {
            for i in 0..n {
                let theta = geometry.pixel_center(i, j);
                let alpha = alpha[j * n + i];
                let mut rgb = BACKGROUND_RGB;
                for (p, f) in painters.iter().zip(&self.built.source_f) {
                    p.add(theta - *f * alpha, &mut rgb);
                }
                put(&mut image_rgba, (n - 1 - j) * n + i, rgb);
            }
        }
        let source_geometry = MapGeometry::centered(self.scene.source_fov(), n);
        let mut source_rgba = vec![0u8; n * n * 4];
        for j in 0..n {
            for i in 0..n {
                let beta = source_geometry.pixel_center(i, j);
                let mut rgb = BACKGROUND_RGB;
                for p in &painters {
                    p.add(beta, &mut rgb);
                }
                put(&mut source_rgba, (n - 1 - j) * n + i, rgb);
            }
        }
        let curves = cache.curves(&self.built, geometry);
        let maps = cache.curve_maps(lens, frame::curve_geometry(geometry));
        let points = self
            .scene
            .sources
            .iter()
            .enumerate()
            .filter(|(_, s)| matches!(s, SourceSpec::Point { .. }))
            .map(|(k, s)| PointSourceImages {
                source: k,
                images: self.images_with(SearchGrid::Maps(maps), s.position(), s.z()),
            })
            .collect();
        Frame {
            pixels: n,
            image_rgba,
            source_rgba,
            curves,
            points,
            compute_ms: clock.ms(),
        }
    }

    /// Where the ray seen at `theta` (arcsec) lands on each source plane (ascending `z`), with
    /// the magnification there: `beta = theta - f alpha(theta)`.
    pub fn ray(&self, theta: DVec2) -> Vec<RayLanding> {
        let lens = &self.built.lens;
        let (alpha, h) = crate::profiles::MassComponent::deflection_hessian(lens, theta);
        let (kappa, g1, g2) = (0.5 * (h[0] + h[2]), 0.5 * (h[0] - h[2]), h[1]);
        self.built
            .planes
            .iter()
            .map(|p| {
                let beta = theta - p.f * alpha;
                RayLanding {
                    z: p.z,
                    x: beta.x,
                    y: beta.y,
                    magnification: magnification_at_point(p.f, kappa, g1, g2),
                }
            })
            .collect()
    }

    /// Every image of a point source at `beta` (arcsec) and redshift `z`, inside the
    /// image-plane view, brightest first, with the delay after the first to arrive. Empty for
    /// `z <= z_lens`.
    pub fn images_of(&self, beta: DVec2, z: f64) -> Vec<PointImage> {
        let geometry = MapGeometry::centered(self.scene.fov, IMAGE_SEARCH_PIXELS);
        self.images_with(SearchGrid::Lens(geometry), beta, z)
    }

    fn images_with(&self, grid: SearchGrid, beta: DVec2, z: f64) -> Vec<PointImage> {
        let lens = &self.built.lens;
        let plane = &self.built.plane;
        let Ok(f) = plane.distance_ratio(z) else {
            return Vec::new();
        };
        let Ok(found) = find_images(lens, grid, f, beta, &ImageSearch::default()) else {
            return Vec::new();
        };
        let times: Vec<f64> = found
            .iter()
            .map(|im| {
                let psi = potential_difference(lens, DVec2::ZERO, im.position);
                arrival_time_days(plane, z, im.position, beta, psi).unwrap_or(f64::NAN)
            })
            .collect();
        let first = times.iter().copied().fold(f64::INFINITY, f64::min);
        found
            .iter()
            .zip(times)
            .map(|(im, t)| PointImage {
                x: im.position.x,
                y: im.position.y,
                magnification: im.magnification,
                parity: match im.parity {
                    Parity::Positive => "+",
                    Parity::Negative => "-",
                },
                kind: match im.kind {
                    ImageKind::Minimum => "minimum",
                    ImageKind::Saddle => "saddle",
                    ImageKind::Maximum => "maximum",
                },
                delay_days: t - first,
            })
            .collect()
    }

    /// Contours of `kind` on the image-plane view at `pixels` a side, for a source at redshift
    /// `z` (and, for the arrival time, at `beta`, arcsec).
    pub fn contours(
        &self,
        kind: ContourKind,
        pixels: usize,
        z: f64,
        beta: DVec2,
    ) -> Vec<ContourLine> {
        let n = pixels.clamp(16, MAX_FRAME_PIXELS);
        let Ok(f) = self.built.plane.distance_ratio(z) else {
            return Vec::new();
        };
        let geometry = MapGeometry::centered(self.scene.fov, n);
        let maps = LensMaps::from_lens(&self.built.lens, geometry);
        let (field, levels): (Map, Vec<f64>) = match kind {
            ContourKind::Kappa => {
                let mut m = maps.kappa.clone();
                m.data.iter_mut().for_each(|v| *v *= f);
                (m, KAPPA_LEVELS.to_vec())
            }
            ContourKind::Magnification => {
                let mut m = maps.magnification(f);
                m.data.iter_mut().for_each(|v| *v = v.abs());
                (m, MAGNIFICATION_LEVELS.to_vec())
            }
            ContourKind::ArrivalTime => {
                let psi = potential_map(&maps);
                let plane = &self.built.plane;
                let mut m = psi.clone();
                for j in 0..n {
                    for i in 0..n {
                        let k = j * n + i;
                        let theta = geometry.pixel_center(i, j);
                        m.data[k] = arrival_time_days(plane, z, theta, beta, psi.data[k])
                            .unwrap_or(f64::NAN);
                    }
                }
                // Evenly spaced up to a little past the latest image, and exactly at each
                // saddle image: the contour through a saddle crosses itself there, the
                // figure-eight that shows which images pair up.
                let images = self.images_of(beta, z);
                let at = |im: &PointImage| m.sample(DVec2::new(im.x, im.y));
                let latest = images
                    .iter()
                    .map(at)
                    .filter(|t| t.is_finite())
                    .reduce(f64::max);
                let mut levels = arrival_levels(&m.data, latest);
                levels.extend(images.iter().filter(|im| im.kind == "saddle").map(at));
                (m, levels)
            }
        };
        let mut out = Vec::new();
        for level in levels {
            let shifted = Map {
                geometry,
                data: field.data.iter().map(|v| v - level).collect(),
            };
            for c in zero_contours(&shifted) {
                out.push(ContourLine {
                    level,
                    points: c.points,
                    closed: c.closed,
                });
            }
        }
        out
    }
}

/// [`ARRIVAL_LEVELS`] even steps from the minimum of `t` to 1.5 times the way to the
/// `latest` image's arrival time, or without images to the median of `t` (the far field's
/// arrival time rises as `theta^2` and would take every level).
fn arrival_levels(t: &[f64], latest: Option<f64>) -> Vec<f64> {
    let mut v: Vec<f64> = t.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return Vec::new();
    }
    v.sort_by(f64::total_cmp);
    let lo = v[0];
    let mid = match latest {
        Some(t) if t > lo => lo + 1.5 * (t - lo),
        _ => v[v.len() / 2],
    };
    let step = (mid - lo) / ARRIVAL_LEVELS as f64;
    (0..ARRIVAL_LEVELS)
        .map(|k| lo + (k as f64 + 0.5) * step)
        .collect()
}

fn put(rgba: &mut [u8], pixel: usize, rgb: [f32; 3]) {
    let o = 4 * pixel;
    rgba[o] = to_byte(rgb[0]);
    rgba[o + 1] = to_byte(rgb[1]);
    rgba[o + 2] = to_byte(rgb[2]);
    rgba[o + 3] = 255;
}

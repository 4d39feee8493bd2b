//! "Observe": a scene frozen into mock data that the research app reads, and the truth it was
//! made from.
//!
//! - Point sources: their images from the core's image finder ([`Playground::images_of`]),
//!   those with `|mu| >=` [`ObserveOptions::min_abs_magnification`] kept, each position moved
//!   by a normal deviate of `sigma = hypot(pixel / sqrt(12), FWHM x noise)` arcsec per axis
//!   (the pixel's own scatter and a centroid at signal-to-noise `1 / noise`), written as a
//!   Lenstool image catalogue, one system per source (`2.1`, `2.2`, ... for `sources[1]`).
//! - Extended sources (Gaussian, Sérsic): each source's lensed light alone on a grid of
//!   `pixel_arcsec` pixels over the view, peak surface brightness 1 (lensing conserves it),
//!   blurred by a Gaussian PSF of `psf_fwhm_arcsec`, plus Gaussian noise of rms `noise`;
//!   pixels above `threshold_sigma x noise` are detected, and each 8-connected group of at
//!   least [`MIN_IMAGE_PIXELS`] of them is one image of that source's system, written as the
//!   project's arcs JSON ([`crate::parse_arcs`]).
//! - Member galaxies: a Lenstool member catalogue with their magnitudes, so the inversion's
//!   luminosity scaling rebuilds the scene's halos (`C = 1` is the truth).
//! - The truth ([`Scene::truth_model`]) and settings for a reconstruction of these data.
//!
//! A system with fewer than two detected images is dropped (a single image does not constrain
//! the lens) and a note says so. Everything is deterministic for a seed
//! ([`crate::simulate`]'s generator).

use std::fmt::Write as _;

use glam::DVec2;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::light::sersic_b;
use super::scene::{SceneError, SceneLens, SourceSpec};
use super::{Playground, Scene};
use crate::inversion::MemberConfig;
use crate::map::{LensMaps, MapGeometry};
use crate::simulate::rng::Rng;

/// Sky position (degrees) written as the catalogues' `#REFERENCE`: the frame has no sky place
/// of its own; any one will do as long as all files share it.
pub const OBSERVED_RA_DEG: f64 = 150.0;
pub const OBSERVED_DEC_DEG: f64 = 2.2;
/// Fewest detected pixels that make an image of an extended source (fewer: noise).
pub const MIN_IMAGE_PIXELS: usize = 3;
/// Most pixels a side of the observed grid.
pub const MAX_OBSERVE_PIXELS: usize = 1024;
/// Magnitude of a point image of `|mu| = 1` in the catalogue (`mag = 25 - 2.5 log10 |mu|`).
const POINT_MAG_ZERO: f64 = 25.0;

/// How the scene is observed; every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ObserveOptions {
    /// Pixel size in arcsec (default 0.2, a drizzled HST pixel). At most
    /// [`MAX_OBSERVE_PIXELS`] pixels a side over the view.
    pub pixel_arcsec: f64,
    /// FWHM of the Gaussian blur (PSF) in arcsec, 0 for none (default 0.3).
    pub psf_fwhm_arcsec: f64,
    /// Noise rms per pixel relative to a source's peak surface brightness, in (0, 1]
    /// (default 0.02: signal-to-noise 50 at the peak).
    pub noise: f64,
    /// Detection threshold in units of the noise rms (default 5).
    pub threshold_sigma: f64,
    /// Point images fainter than this `|mu|` are not detected (default 0.3).
    pub min_abs_magnification: f64,
    /// Seed of the noise and the position errors (default 1).
    pub seed: u64,
}

impl Default for ObserveOptions {
    fn default() -> Self {
        Self {
            pixel_arcsec: 0.2,
            psf_fwhm_arcsec: 0.3,
            noise: 0.02,
            threshold_sigma: 5.0,
            min_abs_magnification: 0.3,
            seed: 1,
        }
    }
}

impl Observation {
    /// The suggested value of setting `path`, if any.
    pub fn setting(&self, path: &str) -> Option<&Value> {
        self.settings
            .iter()
            .find(|(p, _)| p == path)
            .map(|(_, v)| v)
    }
}

impl ObserveOptions {
    /// Checks every field; `fov` is the view's side in arcsec.
    pub fn validate(&self, fov: f64) -> Result<(), SceneError> {
        let bad = |field: &str, value: f64, reason| {
            Err(SceneError::BadField {
                field: format!("observe.{field}"),
                value,
                reason,
            })
        };
        let p = self.pixel_arcsec;
        if !(p.is_finite() && p > 0.0) {
            return bad("pixel_arcsec", p, "must be positive");
        }
        if fov / p > MAX_OBSERVE_PIXELS as f64 {
            return bad(
                "pixel_arcsec",
                p,
                "gives more than 1024 pixels across the view",
            );
        }
        let f = self.psf_fwhm_arcsec;
        if !(f.is_finite() && (0.0..=10.0).contains(&f)) {
            return bad("psf_fwhm_arcsec", f, "must be in [0, 10]");
        }
        if !(self.noise.is_finite() && self.noise > 0.0 && self.noise <= 1.0) {
            return bad("noise", self.noise, "must be in (0, 1]");
        }
        let t = self.threshold_sigma;
        if !(t.is_finite() && t > 0.0 && t * self.noise < 1.0) {
            return bad(
                "threshold_sigma",
                t,
                "must be positive and below the peak (threshold_sigma x noise < 1)",
            );
        }
        let m = self.min_abs_magnification;
        if !(m.is_finite() && m >= 0.0) {
            return bad("min_abs_magnification", m, "must be 0 or more");
        }
        Ok(())
    }

    /// Per-axis rms of a point image's position error in arcsec (module documentation).
    pub fn position_sigma_arcsec(&self) -> f64 {
        (self.pixel_arcsec / 12f64.sqrt()).hypot(self.psf_fwhm_arcsec * self.noise)
    }
}

/// One detected system, for drawing: its images' positions (point images; an arc's pixel
/// centroid) and pixel counts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObservedSystem {
    /// System id in the files (`sources[k]` is system `k + 1`).
    pub id: String,
    /// Index into [`Scene::sources`].
    pub source: usize,
    pub z: f64,
    /// `"point"` or `"arcs"`.
    pub kind: &'static str,
    /// Image positions in arcsec (an arc's centroid).
    pub images: Vec<[f64; 2]>,
    /// Pixels of each image (1 for a point image).
    pub pixels: Vec<usize>,
    /// Every detected pixel (arcsec) of an extended source; empty for a point source.
    pub arc_pixels: Vec<[f64; 2]>,
}

/// A scene observed: the files the research app reads and the settings to reconstruct them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Observation {
    /// Lenstool image catalogue of the point sources' images (None: no point system).
    pub images_cat: Option<String>,
    /// Arcs JSON of the extended sources (and, when there are any, the point images as
    /// one-pixel images, so one constraint mode fits both); None: no extended system.
    pub arcs_json: Option<String>,
    /// Lenstool member catalogue (None: the scene has no member galaxy).
    pub members_cat: Option<String>,
    /// The truth as a model file ([`Scene::truth_model`]).
    pub model_json: String,
    /// The lens redshift.
    pub z_lens: f64,
    /// Suggested settings as `[path, value]` pairs, paths as in the app's settings
    /// (`reconstruct.solver.iterations`, ...), in the order to set them (the solver method
    /// before the strength it allows).
    pub settings: Vec<(String, Value)>,
    /// The systems kept.
    pub systems: Vec<ObservedSystem>,
    /// What was left out and why, in words.
    pub notes: Vec<String>,
}

/// Iterations suggested for point images and for arcs.
pub const POINT_ITERATIONS: usize = 3000;
pub const ARC_ITERATIONS: usize = 2000;
/// Grid cells per side suggested.
pub const SUGGESTED_CELLS: usize = 24;

/// Observes `scene` (module documentation).
pub fn observe(scene: &Scene, options: &ObserveOptions) -> Result<Observation, SceneError> {
    options.validate(scene.fov)?;
    let pg = Playground::new(scene.clone())?;
    let truth = scene.truth_model()?;
    let mut notes = Vec::new();
    let mut systems = Vec::new();
    let sigma = options.position_sigma_arcsec();
    let mut extended = None;
    for (k, s) in scene.sources.iter().enumerate() {
        let id = (k + 1).to_string();
        let z = s.z();
        let system = match s {
            SourceSpec::Point { .. } => {
                let mut rng = Rng::stream(options.seed, 2 * k as u64 + 1);
                let images: Vec<[f64; 2]> = pg
                    .images_of(s.position(), z)
                    .iter()
                    .filter(|im| im.magnification.abs() >= options.min_abs_magnification)
                    .map(|im| [im.x + sigma * rng.normal(), im.y + sigma * rng.normal()])
                    .collect();
                let pixels = vec![1; images.len()];
                ObservedSystem {
                    id,
                    source: k,
                    z,
                    kind: "point",
                    images,
                    pixels,
                    arc_pixels: Vec::new(),
                }
            }
            SourceSpec::Gaussian { .. } | SourceSpec::Sersic { .. } => {
                let grid = extended.get_or_insert_with(|| ObservedGrid::new(&pg, options));
                let f = pg.built().source_f[k];
                let mut rng = Rng::stream(options.seed, 2 * k as u64 + 2);
                let groups = grid.detect(s, f, options, &mut rng);
                let images = groups.iter().map(|g| centroid(g).to_array()).collect();
                ObservedSystem {
                    id,
                    source: k,
                    z,
                    kind: "arcs",
                    images,
                    pixels: groups.iter().map(Vec::len).collect(),
                    arc_pixels: groups.iter().flatten().map(|p| p.to_array()).collect(),
                }
            }
            SourceSpec::Image { .. } => {
                notes.push(format!(
                    "source {} (a picture) is not observed: only Gaussian, Sérsic and point \
                     sources are",
                    k + 1
                ));
                continue;
            }
        };
        match system.images.len() {
            n @ (0 | 1) => notes.push(format!(
                "system {} (z = {z}) is left out: {} detected image{} (a system needs two)",
                system.id,
                if n == 0 { "no" } else { "one" },
                if n == 0 { "s" } else { "" }
            )),
            _ => systems.push(system),
        }
    }
    if systems.is_empty() {
        notes.push("nothing multiply imaged was detected: move a source onto a caustic".into());
    }
    let points: Vec<&ObservedSystem> = systems.iter().filter(|s| s.kind == "point").collect();
    let has_arcs = systems.iter().any(|s| s.kind == "arcs");
    let images_cat = (!points.is_empty()).then(|| image_catalog_text(&points, options));
    let arcs_json = has_arcs.then(|| arcs_json_text(&systems));
    let members_cat = member_catalog_text(scene)?;
    let mode = if has_arcs { "arcs" } else { "point" };
    let iterations = if has_arcs {
        ARC_ITERATIONS
    } else {
        POINT_ITERATIONS
    };
    let z_source = systems.iter().map(|s| s.z).fold(f64::NAN, f64::max);
    let z_source = if z_source.is_finite() {
        z_source
    } else {
        super::DEFAULT_Z_SOURCE
    };
    let settings = [
        ("reconstruct.solver.method", json!("qadp")),
        ("reconstruct.constraints.mode", json!(mode)),
        ("reconstruct.solver.iterations", json!(iterations)),
        ("reconstruct.grid.cells", json!(SUGGESTED_CELLS)),
        ("reconstruct.grid.center_arcsec", json!([0.0, 0.0])),
        ("reconstruct.grid.width_arcsec", json!(scene.fov)),
        ("reconstruct.products.size_arcsec", json!(scene.fov)),
        ("reconstruct.products.z_source", json!(z_source)),
        ("reconstruct.objective.regulariser", json!("none")),
        ("reconstruct.objective.strength", json!(0)),
        ("reconstruct.objective.image_plane_iterations", json!(0)),
        ("reconstruct.members.c_prior_sigma_unmeasured", Value::Null),
    ]
    .map(|(path, value)| (path.to_string(), value))
    .to_vec();
    Ok(Observation {
        images_cat,
        arcs_json,
        members_cat,
        model_json: truth.to_json_string(),
        z_lens: scene.z_lens,
        settings,
        systems,
        notes,
    })
}

fn header(what: &str) -> String {
    format!("#REFERENCE 3 {OBSERVED_RA_DEG:.6} {OBSERVED_DEC_DEG:.6}\n# lensing playground, observed: {what}\n")
}

/// `id x y a b theta z mag`: the ellipse is a circle of half the PSF's FWHM (at least a
/// pixel), the magnitude `25 - 2.5 log10 |mu|` is of the unjittered image.
fn image_catalog_text(points: &[&ObservedSystem], options: &ObserveOptions) -> String {
    let a = (0.5 * options.psf_fwhm_arcsec).max(options.pixel_arcsec);
    let mut out = header("point images (jittered positions)\n# id x y a b theta z mag");
    for s in points {
        for (k, p) in s.images.iter().enumerate() {
            let _ = writeln!(
                out,
                "{}.{} {:.4} {:.4} {a:.3} {a:.3} 0.0 {:.4} {:.2}",
                s.id,
                k + 1,
                p[0],
                p[1],
                s.z,
                POINT_MAG_ZERO
            );
        }
    }
    out
}

/// Arcs JSON, one system a line (as `wslap simulate` writes it): arcs by their pixels, point
/// images as one pixel each.
fn arcs_json_text(systems: &[ObservedSystem]) -> String {
    let lines: Vec<String> = systems
        .iter()
        .map(|s| {
            let images: Vec<Vec<[f64; 2]>> = if s.kind == "point" {
                s.images.iter().map(|p| vec![round4(*p)]).collect()
            } else {
                let mut rest = s.arc_pixels.as_slice();
                s.pixels
                    .iter()
                    .map(|&n| {
                        let (image, tail) = rest.split_at(n);
                        rest = tail;
                        image.iter().map(|p| round4(*p)).collect()
                    })
                    .collect()
            };
            json!({"id": s.id, "z": s.z, "images": images}).to_string()
        })
        .collect();
    format!("{{\"systems\": [\n{}\n]}}\n", lines.join(",\n"))
}

fn round4(p: [f64; 2]) -> [f64; 2] {
    p.map(|v| (v * 1e4).round() / 1e4)
}

/// `id x y a b theta mag lum` of the member galaxies (`lum = L / L*` of the default member
/// scaling); None without members.
fn member_catalog_text(scene: &Scene) -> Result<Option<String>, SceneError> {
    let members: Vec<_> = scene
        .lenses
        .iter()
        .filter_map(|l| match l {
            SceneLens::Member(m) => Some(*m),
            SceneLens::Component(_) => None,
        })
        .collect();
    if members.is_empty() {
        return Ok(None);
    }
    let plane = crate::cosmology::LensPlane::new(scene.cosmology, scene.z_lens)?;
    let mag_star = MemberConfig::default().mag_star_on(&plane);
    let mut out = header(&format!(
        "member galaxies (mag* = {mag_star:.3} for the default member scaling)\n\
         # id x y a b theta mag lum"
    ));
    for (k, m) in members.iter().enumerate() {
        let lum = 10f64.powf(-0.4 * (m.mag - mag_star));
        let _ = writeln!(
            out,
            "{} {:.4} {:.4} 0.5 0.5 0.0 {:.4} {lum:.5}",
            k + 1,
            m.x,
            m.y,
            m.mag
        );
    }
    Ok(Some(out))
}

fn centroid(pixels: &[DVec2]) -> DVec2 {
    pixels.iter().copied().sum::<DVec2>() / pixels.len().max(1) as f64
}

/// The view's pixel grid and the lens's deflection at each pixel centre.
struct ObservedGrid {
    geometry: MapGeometry,
    maps: LensMaps,
}

impl ObservedGrid {
    fn new(pg: &Playground, options: &ObserveOptions) -> Self {
        let fov = pg.scene().fov;
        let n = ((fov / options.pixel_arcsec).round() as usize).clamp(8, MAX_OBSERVE_PIXELS);
        let geometry = MapGeometry::centered(n as f64 * options.pixel_arcsec, n);
        let maps = LensMaps::from_lens(&pg.built().lens, geometry);
        Self { geometry, maps }
    }

    /// The detected images of source `s` (distance ratio `f`): groups of pixel centres.
    fn detect(
        &self,
        s: &SourceSpec,
        f: f64,
        options: &ObserveOptions,
        rng: &mut Rng,
    ) -> Vec<Vec<DVec2>> {
        let n = self.geometry.pixels;
        let mut light: Vec<f64> = (0..n * n)
            .map(|k| {
                let theta = self.geometry.pixel_center(k % n, k / n);
                let alpha = DVec2::new(self.maps.alpha_x.data[k], self.maps.alpha_y.data[k]);
                surface_brightness(s, theta - f * alpha)
            })
            .collect();
        let sigma_px = options.psf_fwhm_arcsec / (8.0 * 2f64.ln()).sqrt() / options.pixel_arcsec;
        blur(&mut light, n, sigma_px);
        let cut = options.threshold_sigma * options.noise;
        let detected: Vec<bool> = light
            .iter()
            .map(|v| v + options.noise * rng.normal() > cut)
            .collect();
        groups(&detected, n)
            .into_iter()
            .filter(|g| g.len() >= MIN_IMAGE_PIXELS)
            .map(|g| {
                g.into_iter()
                    .map(|k| self.geometry.pixel_center(k % n, k / n))
                    .collect()
            })
            .collect()
    }
}

/// Surface brightness of an extended source at `beta` (arcsec), 1 at its centre: a Gaussian
/// `exp(-r^2 / 2 sigma^2)` or a Sérsic `exp(-b_n (r / r_eff)^(1/n))`, `r` the elliptical
/// radius (major-axis distance); 0 for other sources.
pub fn surface_brightness(s: &SourceSpec, beta: DVec2) -> f64 {
    let radius = |x: f64, y: f64, q: f64, pa: f64| {
        let d = beta - DVec2::new(x, y);
        let (sn, cs) = pa.to_radians().sin_cos();
        let u = cs * d.x + sn * d.y;
        let v = (-sn * d.x + cs * d.y) / q;
        (u * u + v * v).sqrt()
    };
    match *s {
        SourceSpec::Gaussian {
            x, y, sigma, q, pa, ..
        } => {
            let r = radius(x, y, q, pa) / sigma;
            (-0.5 * r * r).exp()
        }
        SourceSpec::Sersic {
            x,
            y,
            r_eff,
            n,
            q,
            pa,
            ..
        } => {
            let r = radius(x, y, q, pa) / r_eff;
            (-sersic_b(n) * r.powf(1.0 / n)).exp()
        }
        SourceSpec::Point { .. } | SourceSpec::Image { .. } => 0.0,
    }
}

/// Separable Gaussian blur of the `n x n` image by `sigma_px` pixels (out to 3 sigma; the
/// image is zero outside).
fn blur(image: &mut [f64], n: usize, sigma_px: f64) {
    if sigma_px < 0.05 {
        return;
    }
    let reach = (3.0 * sigma_px).ceil() as isize;
    let kernel: Vec<f64> = (-reach..=reach)
        .map(|d| (-0.5 * (d as f64 / sigma_px).powi(2)).exp())
        .collect();
    let norm: f64 = kernel.iter().sum();
    let mut tmp = vec![0.0; n * n];
    let pass = |src: &[f64], dst: &mut [f64], along_rows: bool| {
        for j in 0..n {
            for i in 0..n {
                let mut acc = 0.0;
                for (t, w) in kernel.iter().enumerate() {
                    let d = t as isize - reach;
                    let (a, b) = if along_rows {
                        (i as isize + d, j as isize)
                    } else {
                        (i as isize, j as isize + d)
                    };
                    if (0..n as isize).contains(&a) && (0..n as isize).contains(&b) {
                        acc += w * src[b as usize * n + a as usize];
                    }
                }
                dst[j * n + i] = acc / norm;
            }
        }
    };
    pass(image, &mut tmp, true);
    pass(&tmp, image, false);
}

/// The 8-connected groups of `true` pixels of an `n x n` mask (row-major indices), in the
/// order of their first pixel.
fn groups(mask: &[bool], n: usize) -> Vec<Vec<usize>> {
    let mut seen = vec![false; mask.len()];
    let mut out = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut group = Vec::new();
        let mut stack = vec![start];
        while let Some(k) = stack.pop() {
            group.push(k);
            let (i, j) = ((k % n) as isize, (k / n) as isize);
            for dj in -1..=1 {
                for di in -1..=1 {
                    let (a, b) = (i + di, j + dj);
                    if !(0..n as isize).contains(&a) || !(0..n as isize).contains(&b) {
                        continue;
                    }
                    let m = b as usize * n + a as usize;
                    if mask[m] && !seen[m] {
                        seen[m] = true;
                        stack.push(m);
                    }
                }
            }
        }
        group.sort_unstable();
        out.push(group);
    }
    out
}

#[cfg(test)]
mod tests;

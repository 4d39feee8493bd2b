//! The simulation's text and image outputs (catalogues, arc file, PNG) and, natively, the
//! output folder of `wslap simulate`.

use std::fmt::Write as _;

use glam::DVec2;
use tiny_skia::{IntSize, Pixmap};

use super::raytrace::pixel_ellipse;
use super::{flux, SimulateError, Simulation};
use crate::inversion::MemberConfig;
use crate::model::ComponentSpec;

/// Magnitude zero point of the image catalogue: `mag = ZP - 2.5 log10(flux)`, flux being the
/// summed brightness (peak 0.5-1 per source) times the pixel area in arcsec^2.
const IMAGE_MAG_ZERO_POINT: f64 = 26.0;
/// Semi-major axis (arcsec) of the light ellipse of a 1e12 Msun member, scaled as `M^(1/3)`.
const MEMBER_A_1E12_ARCSEC: f64 = 1.0;
/// Brightness at which the arc image saturates white, relative to the brightest pixel, and
/// the softening of the asinh stretch (same units).
const PNG_SOFTENING: f64 = 0.03;
/// Smallest side of `arcs.png` in pixels (small maps are enlarged by pixel repetition).
const PNG_MIN_SIDE: usize = 600;
/// Peak of a galaxy's glow in `arcs.png` for the BCG (relative to the arcs' white) and its
/// exponential scale length for a 1e12 Msun galaxy, arcsec (scaled as `M^(1/3)`).
const GALAXY_GLOW_PEAK: f64 = 0.6;
const GALAXY_GLOW_SCALE_ARCSEC: f64 = 1.0;

impl Simulation {
    /// `#REFERENCE 3` header line and a comment naming the simulation.
    fn catalog_header(&self, what: &str) -> String {
        format!(
            "#REFERENCE 3 {:.6} {:.6}\n# wslap simulate (seed {}): {what}\n",
            self.reference.ra_deg, self.reference.dec_deg, self.config.seed
        )
    }

    /// Lenstool member catalogue (`id x y a b theta mag lum`, arcsec relative to the BCG) of
    /// the 94 galaxies with galaxy-model masses turned into magnitudes for the default member
    /// settings of [`MemberConfig`]: `mag = mag* - 2.5 log10(M200 / (Upsilon L*))`, so the
    /// members' fiducial masses `Upsilon L` equal the galaxy-model `M200`. The light ellipse has
    /// the halo's axis ratio and angle and `a = 1 arcsec (M200/1e12 Msun)^(1/3)`; `lum` is L/L*.
    pub fn member_catalog_text(&self) -> String {
        let cfg = MemberConfig::default();
        let mag_star = cfg.mag_star_on(&self.plane);
        let m_star = cfg.mass_to_light * cfg.l_star_lsun;
        let mut out = self.catalog_header(&format!(
            "member galaxies, magnitudes from the galaxy-model M200 with Upsilon = {} and \
             L* = {:e} Lsun (mag* = {mag_star:.3})\n# id x y a b theta mag lum",
            cfg.mass_to_light, cfg.l_star_lsun
        ));
        for (k, spec) in self.galaxies_model.iter().enumerate() {
            let ComponentSpec::Nfw {
                x, y, m200, q, pa, ..
            } = *spec
            else {
                continue;
            };
            let l = m200 / m_star;
            let a = MEMBER_A_1E12_ARCSEC * (m200 / 1e12).cbrt();
            let mag = mag_star - 2.5 * l.log10();
            let _ = writeln!(
                out,
                "{} {x:.4} {y:.4} {a:.4} {:.4} {pa:.2} {mag:.4} {l:.5}",
                k + 1,
                a * q
            );
        }
        out
    }

    /// Lenstool image catalogue (`id x y a b theta z mag`, arcsec relative to the BCG): one row
    /// per image, id `system.image`, at the centroid of its pixels with the ellipse of their
    /// second moments (see `raytrace::pixel_ellipse`); `mag = 26 - 2.5 log10(flux)`.
    pub fn image_catalog_text(&self) -> String {
        let pixel = self.image.geometry.pixel_arcsec();
        let mut out = self.catalog_header(
            "multiple images (pixel centroids and second moments)\n# id x y a b theta z mag",
        );
        for system in &self.arcs.systems {
            let z = system.z.unwrap_or(0.0);
            for (k, im) in system.images.iter().enumerate() {
                let (c, a, b, theta) = pixel_ellipse(im, pixel);
                let mag = IMAGE_MAG_ZERO_POINT - 2.5 * flux(&self.image, im).max(1e-12).log10();
                let _ = writeln!(
                    out,
                    "{}.{} {:.4} {:.4} {a:.4} {b:.4} {theta:.2} {z:.4} {mag:.3}",
                    system.id,
                    k + 1,
                    c.x,
                    c.y
                );
            }
        }
        out
    }

    /// The arcs in the format of `parse_arcs`: one pixel list per image, arcsec; one system
    /// per line.
    pub fn arcs_json(&self) -> String {
        let systems: Vec<String> = self
            .arcs
            .systems
            .iter()
            .map(|s| {
                let images: Vec<Vec<[f64; 2]>> = s
                    .images
                    .iter()
                    .map(|im| im.iter().map(|p| [p.x, p.y]).collect())
                    .collect();
                serde_json::json!({"id": s.id, "z": s.z, "images": images}).to_string()
            })
            .collect();
        // One system per line, so that an error naming a line points at one system.
        format!("{{\"systems\": [\n{}\n]}}\n", systems.join(",\n"))
    }

    /// Grey-scale PNG of the lensed image (asinh stretch; North up, East left), with a faint
    /// warm glow at each true galaxy so the cluster can be seen.
    pub fn arcs_png(&self) -> Result<Vec<u8>, SimulateError> {
        let g = self.image.geometry;
        let n = g.pixels;
        let (_, max) = self.image.min_max();
        let max = if max > 0.0 { max } else { 1.0 };
        let stretch = |v: f64| {
            ((v / (PNG_SOFTENING * max)).asinh() / (1.0 / PNG_SOFTENING).asinh()).clamp(0.0, 1.0)
        };
        let glow = self.galaxy_glow();
        let zoom = PNG_MIN_SIDE.div_ceil(n).max(1);
        let side = n * zoom;
        let mut rgba = vec![0u8; side * side * 4];
        for row in 0..side {
            // PNG rows go down; map rows (j, +y North) go up.
            let j = n - 1 - row / zoom;
            for col in 0..side {
                let i = col / zoom;
                let k = j * n + i;
                let arc = stretch(self.image.data[k]);
                let gl = glow[k];
                let rgb = [arc + gl, arc + 0.8 * gl, arc + 0.55 * gl]
                    .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8);
                let o = (row * side + col) * 4;
                rgba[o..o + 3].copy_from_slice(&rgb);
                rgba[o + 3] = 255;
            }
        }
        let size = IntSize::from_wh(side as u32, side as u32)
            .ok_or_else(|| SimulateError::Png(format!("bad image size {side}")))?;
        let pm = Pixmap::from_vec(rgba, size)
            .ok_or_else(|| SimulateError::Png("pixel buffer of the wrong size".into()))?;
        pm.encode_png()
            .map_err(|e| SimulateError::Png(e.to_string()))
    }

    /// Glow of the galaxies on the image grid: `peak (M/M_bcg)^0.35 exp(-r/s)` with
    /// `s ∝ M^(1/3)`, out to 8 scale lengths.
    fn galaxy_glow(&self) -> Vec<f64> {
        let g = self.image.geometry;
        let n = g.pixels;
        let mut out = vec![0.0; n * n];
        let m_max = self
            .galaxies_true
            .iter()
            .filter_map(nfw_mass)
            .fold(0.0_f64, f64::max);
        for spec in &self.galaxies_true {
            let (Some(m), ComponentSpec::Nfw { x, y, .. }) = (nfw_mass(spec), spec) else {
                continue;
            };
            let c = DVec2::new(*x, *y);
            let peak = GALAXY_GLOW_PEAK * (m / m_max).powf(0.35);
            let s = GALAXY_GLOW_SCALE_ARCSEC * (m / 1e12).cbrt();
            let lo = g.arcsec_to_pixel(c - 8.0 * s).floor().max(DVec2::ZERO);
            let hi = g
                .arcsec_to_pixel(c + 8.0 * s)
                .ceil()
                .min(DVec2::splat((n - 1) as f64));
            for j in lo.y as usize..=hi.y as usize {
                for i in lo.x as usize..=hi.x as usize {
                    let r = g.pixel_center(i, j).distance(c);
                    out[j * n + i] += peak * (-r / s).exp();
                }
            }
        }
        out
    }
}

fn nfw_mass(spec: &ComponentSpec) -> Option<f64> {
    match spec {
        ComponentSpec::Nfw { m200, .. } => Some(*m200),
        _ => None,
    }
}

/// Writes the simulation into `dir` (created if missing) and returns the paths written:
/// `truth/model.json` (soft + galaxy-true), `truth/soft.json`, `truth/galaxies-true.json`,
/// `truth/galaxies-model.json`, the truth products at `z_s = 3` on the simulation's pixel grid
/// (`truth/kappa.fits`, `gamma1/2.fits`, `x/y-arcsec-deflect.fits`, `psi.fits`, `magnif.fits`,
/// `critical-curves.json`, `critical-curves.reg`, `kappa.png`, `summary.json`), `arcs.json`,
/// `arcs.png`, `images.cat`, `members.cat` and `simulation.json`.
#[cfg(not(target_arch = "wasm32"))]
pub fn write_simulation(
    sim: &Simulation,
    dir: &std::path::Path,
) -> Result<Vec<std::path::PathBuf>, SimulateError> {
    use super::GalaxySet;
    use crate::products::Products;
    use crate::render::ColorScale;

    let truth = dir.join("truth");
    std::fs::create_dir_all(&truth).map_err(|e| SimulateError::Io {
        path: truth.display().to_string(),
        message: e.to_string(),
    })?;
    let mut written = Vec::new();
    let mut write = |path: std::path::PathBuf, bytes: &[u8]| -> Result<(), SimulateError> {
        std::fs::write(&path, bytes).map_err(|e| SimulateError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        written.push(path);
        Ok(())
    };
    let model = sim.truth_model();
    write(truth.join("model.json"), model.to_json_string().as_bytes())?;
    write(
        truth.join("soft.json"),
        sim.soft_model().to_json_string().as_bytes(),
    )?;
    write(
        truth.join("galaxies-true.json"),
        sim.galaxies_model_file(GalaxySet::True)
            .to_json_string()
            .as_bytes(),
    )?;
    write(
        truth.join("galaxies-model.json"),
        sim.galaxies_model_file(GalaxySet::Model)
            .to_json_string()
            .as_bytes(),
    )?;
    // The maps the sources were ray-shot through: not computed again.
    let products = Products::from_lens_maps(
        sim.truth_maps.clone(),
        &model.build_lens()?,
        sim.plane,
        model.reference,
        super::SUMMARY_Z_SOURCE,
    )?;
    for (name, bytes) in products.fits_files()? {
        write(truth.join(name), &bytes)?;
    }
    write(
        truth.join("critical-curves.json"),
        products.curves_json().as_bytes(),
    )?;
    write(
        truth.join("critical-curves.reg"),
        products.regions().as_bytes(),
    )?;
    write(
        truth.join("kappa.png"),
        &products.kappa_png(ColorScale::Log)?,
    )?;
    let summary = serde_json::to_string_pretty(&products.summary()).unwrap_or_default();
    write(truth.join("summary.json"), summary.as_bytes())?;
    write(dir.join("arcs.json"), sim.arcs_json().as_bytes())?;
    write(dir.join("arcs.png"), &sim.arcs_png()?)?;
    write(dir.join("images.cat"), sim.image_catalog_text().as_bytes())?;
    write(
        dir.join("members.cat"),
        sim.member_catalog_text().as_bytes(),
    )?;
    let summary = serde_json::to_string_pretty(&sim.summary()).unwrap_or_default();
    write(dir.join("simulation.json"), summary.as_bytes())?;
    Ok(written)
}

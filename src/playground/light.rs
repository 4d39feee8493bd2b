//! Source brightness and the colours the playground paints with.
//!
//! Surface brightness is conserved by lensing, so a lensed pixel shows the source's brightness
//! at `beta = theta - f alpha(theta)`. Each source has a colour; brightness is tone-mapped by
//! `1 - exp(-I)` and the sources add.

use glam::DVec2;

use super::scene::SourceSpec;

/// Pixels uploaded for an image source: `width x height` RGBA, rows from the top.
#[derive(Debug, Clone, PartialEq)]
pub struct SourcePixels {
    pub width: usize,
    pub height: usize,
    pub rgba: Vec<u8>,
}

/// Colours of the analytic sources, in turn (linear RGB in [0, 1]).
pub const SOURCE_RGB: [[f32; 3]; 6] = [
    [0.35, 0.75, 1.0],
    [1.0, 0.55, 0.25],
    [0.55, 1.0, 0.45],
    [1.0, 0.4, 0.85],
    [1.0, 0.9, 0.35],
    [0.6, 0.55, 1.0],
];

/// The background of both views (dark blue), RGB in [0, 1].
pub const BACKGROUND_RGB: [f32; 3] = [0.03, 0.04, 0.08];

/// `b_n` of the Sérsic profile (Ciotti & Bertin 1999, good to 1e-4 for `n > 0.36`; MacArthur
/// et al. 2003 below): half the light is inside `r_eff`.
pub fn sersic_b(n: f64) -> f64 {
    if n > 0.36 {
        2.0 * n - 1.0 / 3.0 + 4.0 / (405.0 * n) + 46.0 / (25515.0 * n * n)
    } else {
        0.01945 - 0.8902 * n + 10.95 * n * n - 19.67 * n.powi(3) + 13.43 * n.powi(4)
    }
}

/// Elliptical radius of offset `d` (arcsec) for axis ratio `q` and major axis at the angle
/// whose `(sin, cos)` is `sc`: `sqrt(x'^2 + (y'/q)^2)`, equal to the major-axis distance, and
/// never less than `|d|` (`q <= 1`).
#[inline]
fn elliptical_radius(d: DVec2, q: f64, (s, c): (f64, f64)) -> f64 {
    let x = c * d.x + s * d.y;
    let y = (-s * d.x + c * d.y) / q;
    (x * x + y * y).sqrt()
}

/// Elliptical radii, in units of the source's scale, beyond which a Gaussian and a Sérsic
/// source add nothing.
const GAUSSIAN_CUT: f64 = 6.0;
const SERSIC_CUT: f64 = 8.0;

/// A source ready to be sampled: its brightness (tone-mapped intensity times colour) at a
/// source-plane position.
pub struct Painter<'a> {
    pub spec: SourceSpec,
    pub rgb: [f32; 3],
    pub pixels: Option<&'a SourcePixels>,
    /// `b_n` of a Sérsic source.
    b_n: f64,
    /// `(sin, cos)` of the position angle.
    sin_cos: (f64, f64),
    /// Centre (arcsec) and the square of the distance from it (arcsec^2) beyond which the
    /// source adds nothing.
    center: DVec2,
    reach2: f64,
}

impl<'a> Painter<'a> {
    pub fn new(spec: SourceSpec, index: usize, pixels: Option<&'a SourcePixels>) -> Self {
        let b_n = match spec {
            SourceSpec::Sersic { n, .. } => sersic_b(n),
            _ => 0.0,
        };
        let (pa, reach) = match spec {
            SourceSpec::Gaussian { sigma, pa, .. } => (pa, GAUSSIAN_CUT * sigma),
            SourceSpec::Sersic { r_eff, pa, .. } => (pa, SERSIC_CUT * r_eff),
            // The picture's half-diagonal is at most `size / sqrt(2)`.
            SourceSpec::Image { size, .. } => (0.0, size),
            SourceSpec::Point { .. } => (0.0, -1.0),
        };
        Self {
            spec,
            rgb: SOURCE_RGB[index % SOURCE_RGB.len()],
            pixels,
            b_n,
            sin_cos: pa.to_radians().sin_cos(),
            center: spec.position(),
            reach2: reach * reach.abs(),
        }
    }

    /// Adds this source's colour at `beta` (arcsec) to `out`.
    #[inline]
    pub fn add(&self, beta: DVec2, out: &mut [f32; 3]) {
        // The elliptical radius is never less than the distance: far pixels need no more.
        if beta.distance_squared(self.center) > self.reach2 {
            return;
        }
        let intensity = match self.spec {
            SourceSpec::Gaussian { x, y, sigma, q, .. } => {
                let r = elliptical_radius(beta - DVec2::new(x, y), q, self.sin_cos) / sigma;
                if r > GAUSSIAN_CUT {
                    return;
                }
                1.6 * (-0.5 * r * r).exp()
            }
            SourceSpec::Sersic {
                x, y, r_eff, n, q, ..
            } => {
                let r = elliptical_radius(beta - DVec2::new(x, y), q, self.sin_cos) / r_eff;
                if r > SERSIC_CUT {
                    return;
                }
                // Twice the half-light brightness reads as "bright"; the core saturates.
                0.7 * (-self.b_n * (r.powf(1.0 / n) - 1.0)).exp()
            }
            SourceSpec::Image { x, y, size, .. } => {
                if let Some(p) = self.pixels {
                    sample_pixels(p, beta - DVec2::new(x, y), size, out);
                }
                return;
            }
            SourceSpec::Point { .. } => return,
        };
        let t = 1.0 - (-intensity as f32).exp();
        for (o, c) in out.iter_mut().zip(self.rgb) {
            *o += t * c;
        }
    }
}

/// Adds the uploaded picture's colour at offset `d` (arcsec) from its centre, the picture
/// spanning `size` arcsec on its longer side (nearest pixel, alpha as coverage).
fn sample_pixels(p: &SourcePixels, d: DVec2, size: f64, out: &mut [f32; 3]) {
    let side = p.width.max(p.height) as f64;
    if side == 0.0 || p.rgba.len() < p.width * p.height * 4 {
        return;
    }
    let scale = side / size;
    let u = d.x * scale + 0.5 * p.width as f64;
    let v = 0.5 * p.height as f64 - d.y * scale;
    if !(u >= 0.0 && v >= 0.0 && u < p.width as f64 && v < p.height as f64) {
        return;
    }
    let k = 4 * (v as usize * p.width + u as usize);
    let a = p.rgba[k + 3] as f32 / 255.0;
    for (o, byte) in out.iter_mut().zip(&p.rgba[k..k + 3]) {
        let srgb = *byte as f32 / 255.0;
        *o += a * srgb * srgb;
    }
}

/// Linear RGB to an sRGB-ish byte (gamma 2).
#[inline]
pub fn to_byte(v: f32) -> u8 {
    (v.clamp(0.0, 1.0).sqrt() * 255.0 + 0.5) as u8
}

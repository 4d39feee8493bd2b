//! Ray shooting through the truth lens: every pixel centre `theta` of the field is mapped to
//! `beta = theta - f alpha_ref(theta)` ([method §1]), the source's surface brightness is
//! read there, and the pixels above a threshold are grouped into images.
//!
//! Sources are elliptical Sérsic profiles normalised to their peak,
//! `I(R) = I_0 exp(-b_n (R/R_e)^(1/n))`, `R^2 = q x'^2 + y'^2/q` (`x'` along the major axis at
//! `pa`; the ellipse of radius `R` has the area of the circle), `b_n = 2n - 1/3 + 4/(405 n)`
//! (Ciotti & Bertin 1999), so `R_e` is the half-light radius. A pixel belongs to a system when
//! its brightness is at least [`THRESHOLD_FRACTION`] of the source's peak, i.e. when
//! `R <= R_thr = R_e (ln(1/THRESHOLD_FRACTION) / b_n)^n` (2.74 `R_e` for n = 1).
//!
//! [method §1]: crate::method#1-frames-and-units

use glam::DVec2;

use crate::map::LensMaps;
use crate::map::MapGeometry;

/// Fraction of a source's peak surface brightness above which a lensed pixel is a constraint.
pub const THRESHOLD_FRACTION: f64 = 0.01;
/// The brightness map holds each source out to this many threshold radii (`I/I_0 < 1e-4` at
/// n = 1).
const WING_RADII: f64 = 3.0;

/// An elliptical Sérsic source (arcsec, degrees CCW from +x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SourceShape {
    pub(crate) center: DVec2,
    pub(crate) r_e_arcsec: f64,
    pub(crate) q: f64,
    pub(crate) pa_deg: f64,
    pub(crate) sersic_n: f64,
    /// Peak surface brightness (arbitrary units).
    pub(crate) peak: f64,
}

impl SourceShape {
    /// `b_n` of the Sérsic profile (Ciotti & Bertin 1999 asymptotic expansion).
    fn b_n(&self) -> f64 {
        let n = self.sersic_n;
        2.0 * n - 1.0 / 3.0 + 4.0 / (405.0 * n)
    }

    /// Elliptical radius `R = sqrt(q x'^2 + y'^2/q)` of `beta` about the centre, arcsec.
    pub(crate) fn elliptical_radius(&self, beta: DVec2) -> f64 {
        let axis = DVec2::from_angle(self.pa_deg.to_radians());
        let d = beta - self.center;
        let (x, y) = (d.dot(axis), axis.perp_dot(d));
        (self.q * x * x + y * y / self.q).sqrt()
    }

    /// Threshold radius `R_thr` in arcsec (module documentation).
    pub(crate) fn threshold_radius_arcsec(&self) -> f64 {
        self.r_e_arcsec * ((1.0 / THRESHOLD_FRACTION).ln() / self.b_n()).powf(self.sersic_n)
    }

    /// Surface brightness at elliptical radius `r` (arcsec) relative to the peak, in (0, 1].
    fn relative_brightness(&self, r: f64) -> f64 {
        (-self.b_n() * (r / self.r_e_arcsec).powf(1.0 / self.sersic_n)).exp()
    }
}

/// The truth lens sampled at the pixel centres of the field, at `D_ls/D_s = 1`.
#[derive(Debug, Clone)]
pub(crate) struct RayGrid {
    pub(crate) geometry: MapGeometry,
    theta: Vec<DVec2>,
    alpha: Vec<DVec2>,
    kappa: Vec<f64>,
    gamma: Vec<f64>,
}

impl RayGrid {
    /// Pixel centres, deflections, convergence and `|gamma|` from `maps`.
    pub(crate) fn new(maps: &LensMaps) -> Self {
        let geometry = maps.geometry();
        let n = geometry.pixels;
        let theta = (0..n * n)
            .map(|k| geometry.pixel_center(k % n, k / n))
            .collect();
        let alpha = maps
            .alpha_x
            .data
            .iter()
            .zip(&maps.alpha_y.data)
            .map(|(&x, &y)| DVec2::new(x, y))
            .collect();
        let gamma = maps
            .gamma1
            .data
            .iter()
            .zip(&maps.gamma2.data)
            .map(|(&a, &b)| (a * a + b * b).sqrt())
            .collect();
        Self {
            geometry,
            theta,
            alpha,
            kappa: maps.kappa.data.clone(),
            gamma,
        }
    }

    /// Pixels a side.
    pub(crate) fn side(&self) -> usize {
        self.geometry.pixels
    }

    /// Centre of pixel `k` (row-major index) in arcsec.
    pub(crate) fn position(&self, k: usize) -> DVec2 {
        self.theta[k]
    }

    /// `lambda_r = 1 - f (kappa - |gamma|)` at pixel `k` (negative inside the radial critical
    /// curve).
    pub(crate) fn lambda_r(&self, k: usize, f: f64) -> f64 {
        1.0 - f * (self.kappa[k] - self.gamma[k])
    }

    /// Adds the lensed surface brightness of `shape` (out to [`WING_RADII`] threshold radii) to
    /// `image` (row-major over the field).
    pub(crate) fn add_brightness(&self, f: f64, shape: &SourceShape, image: &mut [f64]) {
        let r_max = WING_RADII * shape.threshold_radius_arcsec();
        let reach2 = r_max * r_max / shape.q;
        for ((&t, &a), out) in self.theta.iter().zip(&self.alpha).zip(image.iter_mut()) {
            let beta = t - f * a;
            if beta.distance_squared(shape.center) <= reach2 {
                let r = shape.elliptical_radius(beta);
                if r <= r_max {
                    *out += shape.peak * shape.relative_brightness(r);
                }
            }
        }
    }

    /// Whether pixel `k` touches the border of the field.
    pub(crate) fn on_border(&self, k: usize) -> bool {
        let n = self.side();
        let (i, j) = (k % n, k / n);
        i == 0 || j == 0 || i + 1 == n || j + 1 == n
    }
}

/// The pixel centres of a [`RayGrid`] mapped to the source plane of one distance ratio `f`,
/// bucketed on a square lattice of [`BUCKET_ARCSEC`] cells, so that the pixels whose `beta`
/// falls inside a small source are found without scanning the whole field.
#[derive(Debug, Clone)]
pub(crate) struct SourcePlane {
    f: f64,
    beta: Vec<DVec2>,
    origin: DVec2,
    side: usize,
    /// `start[c]..start[c + 1]` indexes `order` for cell `c` (counting sort).
    start: Vec<u32>,
    order: Vec<u32>,
}

/// Cell of the source-plane buckets, arcsec.
const BUCKET_ARCSEC: f64 = 1.0;

impl SourcePlane {
    /// `beta = theta - f alpha` of every pixel of `grid`, bucketed. Pixels whose `beta` leaves
    /// the field (grown by a quarter on each side) are never inside a placed source and are
    /// left out of the buckets.
    pub(crate) fn new(grid: &RayGrid, f: f64) -> Self {
        let half = 0.75 * grid.geometry.size_arcsec;
        let origin = grid.geometry.center - DVec2::splat(half);
        let side = (2.0 * half / BUCKET_ARCSEC).ceil() as usize;
        let beta: Vec<DVec2> = grid
            .theta
            .iter()
            .zip(&grid.alpha)
            .map(|(&t, &a)| t - f * a)
            .collect();
        let cell_of = |b: DVec2| -> Option<usize> {
            let c = ((b - origin) / BUCKET_ARCSEC).floor();
            let ok = c.x >= 0.0 && c.y >= 0.0 && c.x < side as f64 && c.y < side as f64;
            ok.then(|| c.y as usize * side + c.x as usize)
        };
        let mut start = vec![0u32; side * side + 1];
        for &b in &beta {
            if let Some(c) = cell_of(b) {
                start[c + 1] += 1;
            }
        }
        for c in 0..side * side {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; start[side * side] as usize];
        for (k, &b) in beta.iter().enumerate() {
            if let Some(c) = cell_of(b) {
                order[fill[c] as usize] = k as u32;
                fill[c] += 1;
            }
        }
        Self {
            f,
            beta,
            origin,
            side,
            start,
            order,
        }
    }

    /// The distance ratio of this source plane.
    pub(crate) fn f(&self) -> f64 {
        self.f
    }

    /// The pixels (row-major indices, ascending) whose source-plane position lies inside the
    /// threshold ellipse of `shape`.
    pub(crate) fn trace(&self, shape: &SourceShape) -> Vec<usize> {
        let r_thr = shape.threshold_radius_arcsec();
        // R >= sqrt(q) |d| for q <= 1, so |d| <= R_thr / sqrt(q) bounds the ellipse.
        let reach = r_thr / shape.q.sqrt();
        let lo = ((shape.center - DVec2::splat(reach) - self.origin) / BUCKET_ARCSEC).floor();
        let hi = ((shape.center + DVec2::splat(reach) - self.origin) / BUCKET_ARCSEC).floor();
        let max = (self.side - 1) as f64;
        let inside = |r: f64| {
            self.beta
                .iter()
                .enumerate()
                .filter(move |(_, b)| shape.elliptical_radius(**b) <= r)
        };
        if lo.x < 0.0 || lo.y < 0.0 || hi.x > max || hi.y > max {
            // The source reaches beyond the buckets: scan every pixel.
            return inside(r_thr).map(|(k, _)| k).collect();
        }
        let (x0, x1, y0, y1) = (lo.x as usize, hi.x as usize, lo.y as usize, hi.y as usize);
        let mut out = Vec::new();
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                let c = cy * self.side + cx;
                for &k in &self.order[self.start[c] as usize..self.start[c + 1] as usize] {
                    if shape.elliptical_radius(self.beta[k as usize]) <= r_thr {
                        out.push(k as usize);
                    }
                }
            }
        }
        out.sort_unstable();
        out
    }
}

/// Groups `pixels` (ascending row-major indices on an `n`-pixel-wide grid) into connected
/// components: two pixels are neighbours when both their column and row differ by at most
/// `reach` (1: the usual 8-connectivity). Components come in order of their first pixel, each
/// sorted.
pub(crate) fn components(pixels: &[usize], n: usize, reach: usize) -> Vec<Vec<usize>> {
    let mut label = vec![usize::MAX; pixels.len()];
    let mut out: Vec<Vec<usize>> = Vec::new();
    let r = reach as isize;
    for start in 0..pixels.len() {
        if label[start] != usize::MAX {
            continue;
        }
        let id = out.len();
        label[start] = id;
        let mut members = vec![pixels[start]];
        let mut stack = vec![start];
        while let Some(p) = stack.pop() {
            let (i, j) = ((pixels[p] % n) as isize, (pixels[p] / n) as isize);
            for dj in -r..=r {
                for di in -r..=r {
                    let (ii, jj) = (i + di, j + dj);
                    if (di, dj) == (0, 0)
                        || ii < 0
                        || jj < 0
                        || ii >= n as isize
                        || jj >= n as isize
                    {
                        continue;
                    }
                    let k = jj as usize * n + ii as usize;
                    if let Ok(q) = pixels.binary_search(&k) {
                        if label[q] == usize::MAX {
                            label[q] = id;
                            members.push(k);
                            stack.push(q);
                        }
                    }
                }
            }
        }
        members.sort_unstable();
        out.push(members);
    }
    out
}

/// Shape of a pixel set from its moments: `(centroid, a, b, theta_deg)` with `a >= b` the
/// semi-axes (arcsec) of the uniform ellipse of the same second moments (`a = 2 sqrt(lambda_1)`,
/// each pixel counted as a uniform square, adding `pixel^2/12` to the variance) and `theta` the
/// major axis in degrees CCW from +x, in `[0, 180)`.
pub(crate) fn pixel_ellipse(points: &[DVec2], pixel_arcsec: f64) -> (DVec2, f64, f64, f64) {
    let n = points.len().max(1) as f64;
    let c = points.iter().copied().sum::<DVec2>() / n;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in points {
        let d = *p - c;
        sxx += d.x * d.x;
        syy += d.y * d.y;
        sxy += d.x * d.y;
    }
    let own = pixel_arcsec * pixel_arcsec / 12.0;
    let (sxx, syy, sxy) = (sxx / n + own, syy / n + own, sxy / n);
    let mean = 0.5 * (sxx + syy);
    let diff = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
    let (l1, l2) = (mean + diff, (mean - diff).max(0.0));
    let theta = (0.5 * (2.0 * sxy).atan2(sxx - syy))
        .to_degrees()
        .rem_euclid(180.0);
    (c, 2.0 * l1.sqrt(), 2.0 * l2.sqrt(), theta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_eight_connected_and_reach() {
        // 5-wide grid: a diagonal pair (one component) and a pixel two columns away.
        let n = 5;
        let pixels = vec![0, 6, 8];
        assert_eq!(components(&pixels, n, 1).len(), 2);
        assert_eq!(components(&pixels, n, 2).len(), 1);
    }

    #[test]
    fn pixel_ellipse_of_a_line() {
        let pts: Vec<DVec2> = (0..11).map(|i| DVec2::new(i as f64, i as f64)).collect();
        let (c, a, b, theta) = pixel_ellipse(&pts, 1.0);
        assert!((c - DVec2::splat(5.0)).length() < 1e-12);
        assert!(a > 5.0 * b);
        assert!((theta - 45.0).abs() < 1e-9);
    }
}

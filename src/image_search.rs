//! The lens equation solved forward: every image `theta` of a source at `beta` ([method §1] and [§6]),
//! `beta = theta - f alpha_ref(theta)` with `f = D_ls/D_s`.
//!
//! Method (triangle mapping, Schneider, Ehlers & Falco 1992 section 11; Keeton's gravlens):
//! the pixel centres of a square grid are mapped to the source plane, each grid cell is split
//! into two triangles, and a triangle whose mapped copy contains `beta` holds an image to first
//! order. Near a critical curve (where mapped triangles change orientation) the mapping folds
//! inside a cell and this linear test can miss one image of a magnified pair, so every cell
//! within one cell of a critical curve whose mapped corners come near `beta` also seeds a start
//! at its centre. Each start is refined by damped Newton iterations on the exact lens, with the
//! Jacobian `A = I - f H` from the potential's Hessian `H`; a start is kept if it settles at
//! `|beta(theta) - beta| < tolerance_arcsec` inside the grid, and images of the same parity
//! closer than `duplicate_arcsec` are merged. On the elliptical NFW cluster of the tests every
//! fold pair down to a separation of ~1e-3 arcsec (|mu| ~ 2e5) is resolved from a 2 arcsec grid.
//!
//! Limits (any grid method has them): a critical curve smaller than one grid cell (e.g. of a
//! member galaxy) whose orientation change no grid vertex sees can hide its images, and the
//! central image of a cuspy core, where the deflection varies on scales below a cell, may be
//! missed on a coarse grid: use a grid finer than those features. A source less than
//! `tolerance_arcsec` outside a caustic may give one "image" at the nearly merged pair. Images
//! with `|mu| < min_abs_magnification` are dropped: they are unobservable, and they include the
//! artefact images inside the 1e-8 arcsec cores that keep the SIS and point-mass fields finite.
//!
//! [method §1]: crate::method#1-frames-and-units
//! [§6]: crate::method#6-products

use glam::DVec2;
use thiserror::Error;

use crate::map::MapGeometry;
use crate::map::{LensMaps, MAGNIFICATION_CLAMP};
use crate::profiles::MassComponent;

/// Settings of [`find_images`]; every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageSearch {
    /// Largest accepted `|beta(theta) - beta|` in arcsec (default 1e-4).
    pub tolerance_arcsec: f64,
    /// Newton iterations per candidate (default 60).
    pub max_newton_iterations: usize,
    /// Images closer than this (arcsec) are one image (default 1e-3).
    pub duplicate_arcsec: f64,
    /// Images with `|mu|` below this are dropped as unobservable (default 1e-6, 15 magnitudes).
    pub min_abs_magnification: f64,
}

impl Default for ImageSearch {
    fn default() -> Self {
        Self {
            tolerance_arcsec: 1.0e-4,
            max_newton_iterations: 60,
            duplicate_arcsec: 1.0e-3,
            min_abs_magnification: 1.0e-6,
        }
    }
}

impl ImageSearch {
    /// Checks that every tolerance is finite and positive (`min_abs_magnification` may be 0) and
    /// that at least one Newton iteration is allowed.
    pub fn validate(&self) -> Result<(), ImageError> {
        let positive = [
            ("tolerance_arcsec", self.tolerance_arcsec),
            ("duplicate_arcsec", self.duplicate_arcsec),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(crate::error::BadFieldValue::new(
                    format!("image_search.{name}"),
                    value,
                    "must be finite and positive",
                )
                .into());
            }
        }
        let m = self.min_abs_magnification;
        if !(m.is_finite() && m >= 0.0) {
            return Err(ImageError::from(crate::error::BadFieldValue::new(
                "image_search.min_abs_magnification",
                m,
                "must be finite and not negative",
            )));
        }
        if self.max_newton_iterations == 0 {
            return Err(ImageError::from(crate::error::BadFieldValue::new(
                "image_search.max_newton_iterations",
                0.0,
                "at least one iteration is needed",
            )));
        }
        Ok(())
    }
}

/// What can be wrong with the input of [`find_images`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ImageError {
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error("image search: the distance ratio f = D_ls/D_s = {f} must be finite and positive")]
    BadDistanceRatio { f: f64 },
    #[error("image search: the source position ({x}, {y}) arcsec is not finite")]
    BadSource { x: f64, y: f64 },
    #[error(
        "image search: the grid ({pixels} pixels over {size_arcsec} arcsec, centre ({cx}, {cy})) \
         needs at least 2 pixels a side, a finite positive size and a finite centre"
    )]
    BadGrid {
        pixels: usize,
        size_arcsec: f64,
        cx: f64,
        cy: f64,
    },
    #[error(
        "image search: deflection map {map} has {found} and {len} values; \
         expected {expected} and one value per pixel"
    )]
    BadMaps {
        map: &'static str,
        expected: MapGeometry,
        found: MapGeometry,
        len: usize,
    },
}

/// Where the grid's deflections come from; the Newton refinement always uses the exact lens.
#[derive(Debug, Clone, Copy)]
pub enum SearchGrid<'a> {
    /// Evaluate the lens at the pixel centres of this geometry.
    Lens(MapGeometry),
    /// Use the deflection maps (`D_ls/D_s = 1`) at their own pixel centres: no lens call for the
    /// grid, so a search costs a few ms even for a lens of 100 components (versus ~0.2 s to
    /// evaluate such a lens on a 200x200 grid).
    Maps(&'a LensMaps),
}

/// The sign of `det A`: positive for minima and maxima of the time delay, negative for saddles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Parity {
    Positive,
    Negative,
}

/// The kind of stationary point of the arrival time: a minimum (both eigenvalues of `A`
/// positive), a saddle (`det A < 0`) or a maximum (both negative, e.g. a central image).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ImageKind {
    Minimum,
    Saddle,
    Maximum,
}

/// One image of a point source.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoundImage {
    /// Image position `theta` in arcsec.
    pub position: DVec2,
    /// Signed magnification `1/det A`, `A = I - f H`; `±MAGNIFICATION_CLAMP` on a critical line.
    pub magnification: f64,
    pub parity: Parity,
    pub kind: ImageKind,
    /// `|theta - f alpha(theta) - beta|` in arcsec at `position`.
    pub residual_arcsec: f64,
}

/// `beta = theta - f alpha_ref(theta)` in arcsec (the lens equation, [method §1]).
///
/// [method §1]: crate::method#1-frames-and-units
pub fn source_position(lens: &dyn MassComponent, f: f64, theta: DVec2) -> DVec2 {
    theta - f * lens.deflection(theta)
}

/// The source position of a set of images and how well they agree on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceScatter {
    /// Mean of `theta_i - f alpha(theta_i)` in arcsec (the best common source, [method §5]).
    ///
    /// [method §5]: crate::method#5-the-solver-qadp
    pub beta: DVec2,
    /// Root mean square of `|beta_i - beta|` in arcsec.
    pub rms_arcsec: f64,
    /// Largest `|beta_i - beta|` in arcsec.
    pub max_arcsec: f64,
}

/// Maps every image `theta_i` (arcsec) to `beta_i = theta_i - f alpha(theta_i)` and returns
/// their mean and scatter; `None` for no images.
pub fn source_scatter(lens: &dyn MassComponent, f: f64, thetas: &[DVec2]) -> Option<SourceScatter> {
    if thetas.is_empty() {
        return None;
    }
    let betas: Vec<DVec2> = thetas
        .iter()
        .map(|&t| source_position(lens, f, t))
        .collect();
    let beta = betas.iter().sum::<DVec2>() / betas.len() as f64;
    let d2: Vec<f64> = betas.iter().map(|b| b.distance_squared(beta)).collect();
    Some(SourceScatter {
        beta,
        rms_arcsec: (d2.iter().sum::<f64>() / d2.len() as f64).sqrt(),
        max_arcsec: d2.iter().fold(0.0_f64, |m, &v| m.max(v)).sqrt(),
    })
}

/// All images of a point source at `beta` (arcsec) with `f = D_ls/D_s`, inside the grid of
/// `grid`: solutions of `beta = theta - f alpha_ref(theta)` with `|residual| <
/// opts.tolerance_arcsec`, sorted by decreasing `|magnification|` (see the module docs for the
/// method and its limits). The grid's pixel centres are the vertices of the first triangulation,
/// so its pixel size sets which small features are resolved (1 arcsec is usual for a cluster).
/// A source on a degenerate caustic point (exactly behind a circular lens) images into a ring:
/// the result is then a sample of points on it, at `|mu| = MAGNIFICATION_CLAMP`.
pub fn find_images(
    lens: &dyn MassComponent,
    grid: SearchGrid,
    f: f64,
    beta: DVec2,
    opts: &ImageSearch,
) -> Result<Vec<FoundImage>, ImageError> {
    opts.validate()?;
    if !(f.is_finite() && f > 0.0) {
        return Err(ImageError::BadDistanceRatio { f });
    }
    if !beta.is_finite() {
        return Err(ImageError::BadSource {
            x: beta.x,
            y: beta.y,
        });
    }
    let geometry = match grid {
        SearchGrid::Lens(g) => g,
        SearchGrid::Maps(m) => m.alpha_x.geometry,
    };
    check_geometry(&geometry)?;
    // Source-plane offsets `beta(theta) - beta` of the grid vertices.
    let offsets = match grid {
        SearchGrid::Lens(g) => lens_offsets(lens, &g, f, beta),
        SearchGrid::Maps(m) => map_offsets(m, f, beta)?,
    };
    let search = Search {
        lens,
        f,
        beta,
        opts,
    };
    let candidates = candidates(&geometry, &offsets);
    let half = 0.5 * geometry.size_arcsec;
    let inside = |p: DVec2| (p - geometry.center).abs().max_element() <= half;
    let mut images: Vec<FoundImage> = Vec::new();
    for start in candidates {
        let Some(image) = search.newton(start, geometry.pixel_arcsec()) else {
            continue;
        };
        if !inside(image.position) || image.magnification.abs() < opts.min_abs_magnification {
            continue;
        }
        // Images of opposite parity are distinct however close (a fold pair).
        let same = |o: &&mut FoundImage| {
            o.parity == image.parity && o.position.distance(image.position) < opts.duplicate_arcsec
        };
        match images.iter_mut().find(same) {
            Some(old) if old.residual_arcsec > image.residual_arcsec => *old = image,
            Some(_) => {}
            None => images.push(image),
        }
    }
    images.sort_by(|a, b| b.magnification.abs().total_cmp(&a.magnification.abs()));
    Ok(images)
}

fn check_geometry(g: &MapGeometry) -> Result<(), ImageError> {
    if g.pixels >= 2 && g.size_arcsec.is_finite() && g.size_arcsec > 0.0 && g.center.is_finite() {
        Ok(())
    } else {
        Err(ImageError::BadGrid {
            pixels: g.pixels,
            size_arcsec: g.size_arcsec,
            cx: g.center.x,
            cy: g.center.y,
        })
    }
}

/// `beta(theta) - beta` at every pixel centre from the deflection maps.
fn map_offsets(maps: &LensMaps, f: f64, beta: DVec2) -> Result<Vec<DVec2>, ImageError> {
    let g = maps.alpha_x.geometry;
    let n2 = g.pixels * g.pixels;
    for (map, m) in [("alpha_x", &maps.alpha_x), ("alpha_y", &maps.alpha_y)] {
        if m.geometry != g || m.data.len() != n2 {
            return Err(ImageError::BadMaps {
                map,
                expected: g,
                found: m.geometry,
                len: m.data.len(),
            });
        }
    }
    let n = g.pixels;
    Ok((0..n2)
        .map(|k| {
            let a = DVec2::new(maps.alpha_x.data[k], maps.alpha_y.data[k]);
            g.pixel_center(k % n, k / n) - f * a - beta
        })
        .collect())
}

/// `beta(theta) - beta` at every pixel centre from the lens; natively the rows are shared out
/// over the available threads.
fn lens_offsets(lens: &dyn MassComponent, g: &MapGeometry, f: f64, beta: DVec2) -> Vec<DVec2> {
    let n = g.pixels;
    let mut out = vec![DVec2::ZERO; n * n];
    let fill = |first_row: usize, rows: &mut [DVec2]| {
        for (k, o) in rows.iter_mut().enumerate() {
            let p = g.pixel_center(k % n, first_row + k / n);
            *o = p - f * lens.deflection(p) - beta;
        }
    };
    let threads = crate::threads::available();
    // A few bands per thread balance rows of uneven cost.
    let rows_per_band = n.div_ceil(threads * 4).max(1);
    let bands: Vec<(usize, &mut [DVec2])> = out
        .chunks_mut(rows_per_band * n)
        .enumerate()
        .map(|(b, rows)| (b * rows_per_band, rows))
        .collect();
    crate::threads::for_each(bands, threads, |(row, rows)| fill(row, rows));
    out
}

/// One square cell of the grid: lower-left corner, side, and the source-plane offsets
/// `beta(theta) - beta` of its corners in the order (0,0), (1,0), (0,1), (1,1).
#[derive(Debug, Clone, Copy)]
struct Cell {
    origin: DVec2,
    side_arcsec: f64,
    offsets: [DVec2; 4],
}

impl Cell {
    fn corner(&self, k: usize) -> DVec2 {
        self.origin + DVec2::new((k & 1) as f64, (k >> 1) as f64) * self.side_arcsec
    }
    /// The two triangles (0,0)-(1,0)-(1,1) and (0,0)-(1,1)-(0,1), counter-clockwise.
    const TRIANGLES: [[usize; 3]; 2] = [[0, 1, 3], [0, 3, 2]];

    /// The orientation sign (`+1`, `-1`, `0`) of each mapped triangle: the sign of `det A`.
    fn orientations(&self) -> [i8; 2] {
        Self::TRIANGLES.map(|[a, b, c]| {
            let o = self.offsets;
            sign((o[b] - o[a]).perp_dot(o[c] - o[a]))
        })
    }

    /// Whether the bounding box of the mapped corners, grown by `max(extent, side)`, holds
    /// `beta` (the origin of the offsets); the margin covers the part of a fold that the
    /// corners of a cell on a critical curve do not show.
    fn near_source(&self) -> bool {
        let lo = self.offsets.iter().fold(DVec2::INFINITY, |m, &o| m.min(o));
        let hi = self
            .offsets
            .iter()
            .fold(DVec2::NEG_INFINITY, |m, &o| m.max(o));
        let margin = (hi - lo).max_element().max(self.side_arcsec);
        lo.max_element() <= margin && hi.min_element() >= -margin
    }

    /// Image-plane start points of the triangles whose mapped copy contains `beta`: the point
    /// with the same barycentric coordinates as `beta` in the mapped triangle.
    fn push_candidates(&self, out: &mut Vec<DVec2>) {
        /// Barycentric slack so that a source exactly on a shared edge is not lost.
        const EDGE_SLACK: f64 = 1.0e-9;
        for [a, b, c] in Self::TRIANGLES {
            let (oa, ob, oc) = (self.offsets[a], self.offsets[b], self.offsets[c]);
            let det = (ob - oa).perp_dot(oc - oa);
            if det == 0.0 || !det.is_finite() {
                continue;
            }
            let u = (-oa).perp_dot(oc - oa) / det;
            let v = (ob - oa).perp_dot(-oa) / det;
            if u >= -EDGE_SLACK && v >= -EDGE_SLACK && u + v <= 1.0 + EDGE_SLACK {
                let (ta, tb, tc) = (self.corner(a), self.corner(b), self.corner(c));
                out.push(ta + u * (tb - ta) + v * (tc - ta));
            }
        }
    }
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// `det A = (1 - f H_xx)(1 - f H_yy) - f^2 H_xy^2`.
fn det_a(f: f64, h: [f64; 3]) -> f64 {
    (1.0 - f * h[0]) * (1.0 - f * h[2]) - f * f * h[1] * h[1]
}

/// `1 / det A`, or [`MAGNIFICATION_CLAMP`] with the sign of `det A` on a critical line.
fn clamped_magnification(det: f64) -> f64 {
    if det.abs() >= 1.0 / MAGNIFICATION_CLAMP {
        1.0 / det
    } else {
        MAGNIFICATION_CLAMP.copysign(det)
    }
}

/// The signed magnification `1 / det A` of the lens at `theta` (arcsec) for a source with
/// `f = D_ls/D_s`, clamped to `|mu| <= MAGNIFICATION_CLAMP` on a critical line.
pub fn magnification_at(lens: &dyn MassComponent, f: f64, theta: DVec2) -> f64 {
    clamped_magnification(det_a(f, lens.hessian(theta)))
}

/// Newton start points over the whole grid.
fn candidates(g: &MapGeometry, offsets: &[DVec2]) -> Vec<DVec2> {
    let n = g.pixels;
    let m = n - 1; // cells a side
    let cell = |i: usize, j: usize| Cell {
        origin: g.pixel_center(i, j),
        side_arcsec: g.pixel_arcsec(),
        offsets: [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)].map(|(a, b)| offsets[b * n + a]),
    };
    // Orientation signs of each cell's two mapped triangles, as (has +, has -) flags.
    let flags: Vec<(bool, bool)> = (0..m * m)
        .map(|k| {
            let o = cell(k % m, k / m).orientations();
            (o.iter().any(|&s| s >= 0), o.iter().any(|&s| s <= 0))
        })
        .collect();
    let mut out = Vec::new();
    for j in 0..m {
        for i in 0..m {
            let c = cell(i, j);
            // A critical line runs within one cell if the 3x3 block of cells holds
            // triangles of both orientations.
            let (mut pos, mut neg) = (false, false);
            for jj in j.saturating_sub(1)..(j + 2).min(m) {
                for ii in i.saturating_sub(1)..(i + 2).min(m) {
                    let (p, q) = flags[jj * m + ii];
                    pos |= p;
                    neg |= q;
                }
            }
            // Beside a fold the mapping is far from linear on the scale of the thin mapped
            // triangles, so the containment test can miss an image: a cell near a critical
            // line whose mapped corners come near `beta` also seeds Newton at its centre,
            // which lies on its side of the line (Newton on a fold `beta ~ a t^2` keeps the
            // sign of `t`), so both images of a pair are reached from the cells around it.
            c.push_candidates(&mut out);
            if pos && neg && c.near_source() {
                out.push(c.origin + DVec2::splat(0.5 * c.side_arcsec));
            }
        }
    }
    out
}

/// What one search needs besides the grid: the exact lens, `f`, the source and the settings.
struct Search<'a> {
    lens: &'a dyn MassComponent,
    f: f64,
    beta: DVec2,
    opts: &'a ImageSearch,
}

impl Search<'_> {
    /// Damped Newton iterations from `start` on the exact lens: `theta <- theta - A^-1 r`,
    /// `r = beta(theta) - beta`, each step at most two grid pixels (`2 pixel_arcsec`) long and
    /// halved until `|r|` decreases. `None` unless it settles with `|r| < tolerance_arcsec`.
    fn newton(&self, start: DVec2, pixel_arcsec: f64) -> Option<FoundImage> {
        /// Iterate on to this residual (arcsec), near the rounding of `beta` for `|theta| ~ 100`
        /// arcsec: Newton converges quadratically, so the extra iterations are cheap, and a
        /// magnified image (position error `~ |mu| |r|`) is placed as well as the lens allows.
        const TARGET_ARCSEC: f64 = 1.0e-11;
        /// Step halvings before giving up on a line search.
        const MAX_HALVINGS: usize = 40;
        let max_step = 2.0 * pixel_arcsec;
        let eval = |p: DVec2| {
            let (alpha, h) = self.lens.deflection_hessian(p);
            (p - self.f * alpha - self.beta, h)
        };
        let (mut theta, (mut r, mut h)) = (start, eval(start));
        let target = TARGET_ARCSEC.min(self.opts.tolerance_arcsec);
        // Converged, or stalled at the rounding floor; running out of iterations on the way
        // (a far start) is no answer, as the point may be short of the image.
        let mut settled = false;
        for _ in 0..self.opts.max_newton_iterations {
            // A NaN residual counts as settled and is rejected below.
            if r.length() <= target || r.is_nan() {
                settled = true;
                break;
            }
            let (axx, axy, ayy) = (1.0 - self.f * h[0], -self.f * h[1], 1.0 - self.f * h[2]);
            let det = axx * ayy - axy * axy;
            let mut step = -DVec2::new(ayy * r.x - axy * r.y, axx * r.y - axy * r.x) / det;
            if !step.is_finite() {
                step = -r; // on a critical line: a fixed-point step
            }
            if step.length() > max_step {
                step *= max_step / step.length();
            }
            let mut accepted = false;
            for _ in 0..MAX_HALVINGS {
                let trial = theta + step;
                let (r_new, h_new) = eval(trial);
                if r_new.is_finite() && r_new.length() < r.length() {
                    (theta, r, h, accepted) = (trial, r_new, h_new, true);
                    break;
                }
                step *= 0.5;
            }
            if !accepted {
                settled = true;
                break;
            }
        }
        let residual_arcsec = r.length();
        if !(settled && residual_arcsec < self.opts.tolerance_arcsec && theta.is_finite()) {
            return None;
        }
        let det = det_a(self.f, h);
        let magnification = clamped_magnification(det);
        let trace = 2.0 - self.f * (h[0] + h[2]);
        let (parity, kind) = if det < 0.0 {
            (Parity::Negative, ImageKind::Saddle)
        } else if trace > 0.0 {
            (Parity::Positive, ImageKind::Minimum)
        } else {
            (Parity::Positive, ImageKind::Maximum)
        };
        Some(FoundImage {
            position: theta,
            magnification,
            parity,
            kind,
            residual_arcsec,
        })
    }
}

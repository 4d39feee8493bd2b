//! The 30 background sources: redshifts, sizes, shapes, and their placement so that each is
//! multiply imaged, some give radial arcs, and the arcs of different systems stay apart.
//!
//! Placement (per source, in a fixed order, radial-arc candidates first): a random vertex of
//! the source-redshift caustic (the largest tangential caustic, or for a radial-arc candidate
//! the radial caustic of the central radial critical curve) plus a random offset; the source is
//! ray-traced ([`RayGrid::trace`]) and accepted when
//! - its pixels form at least 3 images (8-connected components; 2 after half the attempts),
//! - the images stay distinct when pixels one pixel apart are joined (no arc broken into
//!   fragments by the pixel sampling),
//! - no pixel touches the field border or lies within [`SYSTEM_GAP_PIXELS`] of another system,
//! - its pixels cover [`MIN_SYSTEM_AREA_ARCSEC2`] to [`MAX_SYSTEM_AREA_ARCSEC2`],
//! - a radial-arc candidate has a radial arc (see [`is_radial_image`]).
//!
//! Later attempts relax the tests (see `Rules::for_attempt`) so that a crowded field or coarse
//! pixels still place every source.

use glam::DVec2;

use super::raytrace::{components, RayGrid, SourcePlane, SourceShape};
use super::rng::Rng;
use super::{SimulateError, SimulatedSource};
use crate::cosmology::LensPlane;
use crate::curves::{critical_curves, signed_area_arcsec2};
use crate::map::LensMaps;
use crate::units::ARCSEC_PER_RAD;

/// Source redshifts, resembling the spectroscopic and photometric redshifts of the ~30
/// multiple-image systems of A1689 (Broadhurst et al. 2005; Limousin et al. 2007): from 1.0 to
/// 5.5, most between 1.5 and 3.5. Rounded values; the order is the system numbering.
pub const SOURCE_REDSHIFTS: [f64; 30] = [
    3.04, 2.54, 5.16, 1.16, 2.60, 4.87, 1.83, 3.05, 2.70, 1.83, 2.53, 3.40, 1.02, 4.00, 1.80, 2.60,
    1.70, 5.50, 2.50, 2.60, 3.00, 1.50, 2.30, 3.80, 1.90, 4.40, 2.00, 3.20, 1.35, 2.90,
];
/// Systems (0-based) placed first on the radial caustic to give radial arcs: high-redshift
/// sources, whose radial critical curve is largest.
const RADIAL_CANDIDATES: [usize; 5] = [2, 5, 17, 13, 25];
/// Half-light radius range in physical kpc (typical z = 1-5 star-forming galaxies).
const R_HALF_KPC: (f64, f64) = (1.2, 3.2);
/// Axis-ratio range and Sérsic index range of the sources.
const SOURCE_Q: (f64, f64) = (0.4, 0.95);
const SERSIC_N: (f64, f64) = (0.8, 1.3);
/// Peak surface brightness range (arbitrary units) for the lensed image.
const PEAK: (f64, f64) = (0.5, 1.0);
/// Largest offset of a source from its caustic vertex, arcsec (tangential sources), and in
/// threshold radii (radial sources, so that they straddle the radial caustic).
const TANGENTIAL_OFFSET_ARCSEC: f64 = 3.0;
const RADIAL_OFFSET_RADII: f64 = 0.6;
/// Radial critical curves and radial arcs count only within this distance of the BCG, arcsec.
pub const RADIAL_ZONE_ARCSEC: f64 = 30.0;
/// Pixels of one system must stay at least this many pixels (Chebyshev) from another's.
pub const SYSTEM_GAP_PIXELS: usize = 2;
/// Smallest and largest area of one system's pixels, arcsec^2 (20 and 1500 pixels of 0.5 arcsec).
pub const MIN_SYSTEM_AREA_ARCSEC2: f64 = 5.0;
pub const MAX_SYSTEM_AREA_ARCSEC2: f64 = 375.0;
/// Attempts per source before giving up.
const MAX_ATTEMPTS: usize = 2000;

/// One accepted source: its public description, shape and images (pixel indices).
#[derive(Debug, Clone)]
pub(crate) struct Placed {
    pub(crate) source: SimulatedSource,
    pub(crate) shape: SourceShape,
    pub(crate) f: f64,
    pub(crate) images: Vec<Vec<usize>>,
}

/// Vertices of the caustics a source at distance ratio `f` is placed on: the caustic of the
/// largest closed tangential critical curve, and that of the longest radial critical curve
/// whose mean position is within [`RADIAL_ZONE_ARCSEC`] of the centre.
fn caustic_vertices(maps: &LensMaps, f: f64, z: f64) -> (Vec<DVec2>, Vec<DVec2>) {
    let curves = critical_curves(maps, f, z, None);
    let tangential = curves
        .tangential
        .iter()
        .enumerate()
        .max_by(|a, b| {
            let (sa, sb) = (
                signed_area_arcsec2(a.1).abs(),
                signed_area_arcsec2(b.1).abs(),
            );
            sa.total_cmp(&sb)
        })
        .and_then(|(k, _)| curves.caustics.tangential.get(k).cloned())
        .unwrap_or_default();
    let radial = curves
        .radial
        .iter()
        .enumerate()
        .filter(|(_, c)| {
            let mean = c.iter().copied().sum::<DVec2>() / c.len().max(1) as f64;
            mean.length() < RADIAL_ZONE_ARCSEC
        })
        .max_by_key(|(_, c)| c.len())
        .and_then(|(k, _)| curves.caustics.radial.get(k).cloned())
        .unwrap_or_default();
    (tangential, radial)
}

/// An image is a radial arc when it crosses the central radial critical curve: it has pixels
/// with `lambda_r = 1 - f (kappa - |gamma|)` of both signs, and its centroid lies within
/// [`RADIAL_ZONE_ARCSEC`] of the centre.
pub(crate) fn is_radial_image(grid: &RayGrid, f: f64, image: &[usize]) -> bool {
    let centroid =
        image.iter().map(|&k| grid.position(k)).sum::<DVec2>() / image.len().max(1) as f64;
    let neg = image.iter().any(|&k| grid.lambda_r(k, f) < 0.0);
    let pos = image.iter().any(|&k| grid.lambda_r(k, f) > 0.0);
    centroid.length() < RADIAL_ZONE_ARCSEC && neg && pos
}

/// Marks the pixels within [`SYSTEM_GAP_PIXELS`] of `pixels` in `taken`.
fn mark_taken(taken: &mut [bool], n: usize, pixels: &[usize]) {
    let g = SYSTEM_GAP_PIXELS as isize;
    for &k in pixels {
        let (i, j) = ((k % n) as isize, (k / n) as isize);
        for dj in -g..=g {
            for di in -g..=g {
                let (ii, jj) = (i + di, j + dj);
                if ii >= 0 && jj >= 0 && ii < n as isize && jj < n as isize {
                    taken[jj as usize * n + ii as usize] = true;
                }
            }
        }
    }
}

/// Places `n_sources` sources (module documentation); `maps` are the truth lens's maps on the
/// same geometry as `grid`.
pub(crate) fn place_sources(
    seed: u64,
    n_sources: usize,
    plane: &LensPlane,
    maps: &LensMaps,
    grid: &RayGrid,
) -> Result<Vec<Placed>, SimulateError> {
    let n = grid.side();
    let mut taken = vec![false; n * n];
    let mut order: Vec<usize> = RADIAL_CANDIDATES
        .iter()
        .copied()
        .filter(|&k| k < n_sources)
        .collect();
    order.extend((0..n_sources).filter(|k| !RADIAL_CANDIDATES.contains(k)));
    let mut placed: Vec<Placed> = Vec::with_capacity(n_sources);
    for &k in &order {
        let mut rng = Rng::stream(seed, 100 + k as u64);
        let z = SOURCE_REDSHIFTS[k % SOURCE_REDSHIFTS.len()];
        let f = plane.distance_ratio(z)?;
        let d_s_mpc = plane.cosmology.angular_diameter_distance_mpc(z);
        let r_half_kpc = rng.range(R_HALF_KPC.0, R_HALF_KPC.1);
        let mut shape = SourceShape {
            center: DVec2::ZERO,
            r_e_arcsec: r_half_kpc * 1e-3 / d_s_mpc * ARCSEC_PER_RAD,
            q: rng.range(SOURCE_Q.0, SOURCE_Q.1),
            pa_deg: rng.range(0.0, 180.0),
            sersic_n: rng.range(SERSIC_N.0, SERSIC_N.1),
            peak: rng.range(PEAK.0, PEAK.1),
        };
        let (tangential, radial) = caustic_vertices(maps, f, z);
        let wants_radial = RADIAL_CANDIDATES.contains(&k) && !radial.is_empty();
        let vertices = if wants_radial { &radial } else { &tangential };
        if vertices.is_empty() {
            return Err(SimulateError::NoCaustic {
                system: (k + 1).to_string(),
                z,
            });
        }
        let plane_f = SourcePlane::new(grid, f);
        let mut accepted = None;
        for attempt in 0..MAX_ATTEMPTS {
            let vertex = vertices[rng.index(vertices.len())];
            let reach = if wants_radial {
                RADIAL_OFFSET_RADII * shape.threshold_radius_arcsec()
            } else {
                TANGENTIAL_OFFSET_ARCSEC
            };
            let offset = reach * rng.uniform().sqrt();
            let angle = rng.range(0.0, std::f64::consts::TAU);
            shape.center = vertex + offset * DVec2::from_angle(angle);
            let rules = Rules::for_attempt(attempt, wants_radial);
            if let Some(images) = try_source(grid, &plane_f, &shape, &taken, &rules) {
                accepted = Some(images);
                break;
            }
        }
        let Some(images) = accepted else {
            return Err(SimulateError::Placement {
                what: format!("source {} (z = {z})", k + 1),
                attempts: MAX_ATTEMPTS,
            });
        };
        for im in &images {
            mark_taken(&mut taken, n, im);
        }
        let radial_arc = images.iter().any(|im| is_radial_image(grid, f, im));
        placed.push(Placed {
            source: SimulatedSource {
                id: (k + 1).to_string(),
                z,
                beta_arcsec: shape.center,
                r_half_arcsec: shape.r_e_arcsec,
                q: shape.q,
                pa_deg: shape.pa_deg,
                n_images: images.len(),
                n_pixels: images.iter().map(Vec::len).sum(),
                radial_arc,
                r_half_kpc,
                sersic_n: shape.sersic_n,
                threshold_radius_arcsec: shape.threshold_radius_arcsec(),
                distance_ratio: f,
            },
            shape,
            f,
            images,
        });
    }
    placed.sort_by_key(|p| p.source.id.parse::<usize>().unwrap_or(usize::MAX));
    Ok(placed)
}

/// The acceptance tests of one attempt: strict first, relaxed in later attempts.
struct Rules {
    min_images: usize,
    need_radial: bool,
    check_fragments: bool,
    min_area_arcsec2: f64,
}

impl Rules {
    /// Attempts `[0, 1/2)`: every test; `[1/2, 3/4)`: 2 images suffice; `[3/4, 1)`: also no
    /// radial arc required, no fragment test, half the minimum area.
    fn for_attempt(attempt: usize, wants_radial: bool) -> Self {
        let late = attempt >= 3 * MAX_ATTEMPTS / 4;
        Self {
            min_images: if attempt < MAX_ATTEMPTS / 2 { 3 } else { 2 },
            need_radial: wants_radial && !late,
            check_fragments: !late,
            min_area_arcsec2: if late { 0.5 } else { 1.0 } * MIN_SYSTEM_AREA_ARCSEC2,
        }
    }
}

/// The images of `shape` if it passes the tests of `rules` (module documentation), largest
/// first.
fn try_source(
    grid: &RayGrid,
    plane_f: &SourcePlane,
    shape: &SourceShape,
    taken: &[bool],
    rules: &Rules,
) -> Option<Vec<Vec<usize>>> {
    let pixels = plane_f.trace(shape);
    let area = pixels.len() as f64 * grid.geometry.pixel_arcsec().powi(2);
    if !(rules.min_area_arcsec2..=MAX_SYSTEM_AREA_ARCSEC2).contains(&area) {
        return None;
    }
    if pixels.iter().any(|&k| taken[k] || grid.on_border(k)) {
        return None;
    }
    let n = grid.side();
    let mut images = components(&pixels, n, 1);
    if images.len() < rules.min_images {
        return None;
    }
    if rules.check_fragments && components(&pixels, n, 2).len() != images.len() {
        return None;
    }
    let f = plane_f.f();
    if rules.need_radial && !images.iter().any(|im| is_radial_image(grid, f, im)) {
        return None;
    }
    images.sort_by_key(|im| std::cmp::Reverse(im.len()));
    Some(images)
}

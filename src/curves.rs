//! Critical curves and caustics ([method §6]).
//!
//! Critical curves are the zero contours of the Jacobian eigenvalues `lambda_t`, `lambda_r`
//! ([`LensMaps::eigen_maps`]), traced by marching squares between pixel centres with linear
//! sub-pixel interpolation. Each crossed cell edge carries one contour vertex, and every segment
//! is oriented with the side `lambda >= 0` on its left, so each vertex has at most one successor:
//! the segments join into polylines after one sort (one scan of the map, then `O(S log S)` in the
//! number of segments `S`). A curve that leaves the map is an open
//! polyline that starts and ends on the map's border; every other curve is a closed loop.
//! Saddle cells (diagonal corners of equal sign) are resolved by the value at the cell centre
//! (mean of the four corners): the corners on the centre's side are joined through the cell.
//!
//! [method §6]: crate::method#6-products

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::cosmology::{CosmologyError, LensPlane};
use crate::map::LensMaps;
use crate::map::{Map, MapGeometry};
use crate::profiles::MassComponent;

/// A polyline in arcsec; closed curves repeat no point (the last joins the first).
pub type Polyline = Vec<DVec2>;

/// Critical curves and caustics for one source redshift, in arcsec.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CriticalCurves {
    pub z_source: f64,
    /// `sqrt(area inside the tangential curves / pi)`, 0 when there is none. A hole inside a
    /// loop (a subcritical island within the critical region) counts against the area, so
    /// `main_curve_radius_arcsec` can exceed it.
    pub einstein_radius_arcsec: f64,
    /// `sqrt(area enclosed by the main tangential curve / pi)`: the largest closed loop of the
    /// lens alone, without the loops of member galaxies or a neighbouring group beside it (which
    /// `einstein_radius_arcsec` counts), the figure published models are usually quoted by; 0
    /// when there is none.
    #[serde(default)]
    pub main_curve_radius_arcsec: f64,
    pub tangential: Vec<Polyline>,
    /// True when the region inside the tangential curves (`lambda_t < 0`) covers more than
    /// [`TANGENTIAL_BORDER_SHARE`] of the map's border pixels, or when the curves open at the
    /// border bound more than [`OPEN_AREA_SHARE`] of the closed loops' area: the Einstein
    /// radius then counts only the closed loops, so it is too small (or 0).
    #[serde(default)]
    pub tangential_leaves_map: bool,
    pub radial: Vec<Polyline>,
    pub caustics: Caustics,
}

/// The critical curves mapped to the source plane.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Caustics {
    pub tangential: Vec<Polyline>,
    pub radial: Vec<Polyline>,
}

/// One zero contour of a map: vertices in arcsec, with the side `value >= 0` on the left.
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    pub points: Polyline,
    /// True for a loop (last vertex joins the first); false for a curve cut by the map border.
    pub closed: bool,
}

/// Vertices closer than this (in pixels) are merged, e.g. where a contour passes exactly
/// through a pixel centre and two cell edges give the same point.
const DUPLICATE_PIXELS: f64 = 1.0e-9;

/// Share of the map's border pixels inside the tangential curves (`lambda_t < 0`) above which
/// the curve counts as leaving the map ([`CriticalCurves::tangential_leaves_map`]). A member
/// galaxy's own small curve cut by the border covers a few pixels (0.2% of the border in the
/// app's example); a cluster curve that leaves the map, much more (7% for AS1063 on its
/// 108 arcsec field).
pub const TANGENTIAL_BORDER_SHARE: f64 = 0.01;

/// Area bounded by the tangential curves open at the border (each closed by the chord between
/// its ends), as a share of the closed loops' area, above which the curve also counts as
/// leaving the map. This catches a cluster curve that leaves through a narrow gap: MACS1931
/// with a prior on C leaves its 99 arcsec map through 5 of 2048 border pixels (0.24%), and
/// measured there the Einstein radius was 6.6 arcsec, from members' loops alone, instead of 28.
/// A member's curve cut by the border bounds a few arcsec^2, against thousands inside a
/// cluster's closed curve.
pub const OPEN_AREA_SHARE: f64 = 0.1;

/// Critical curves and caustics for a source with `f = D_ls/D_s` at `z_source`.
///
/// Tangential curves are the zero contours of `lambda_t = 1 - f (kappa + |gamma|)`, radial
/// curves those of `lambda_r = 1 - f (kappa - |gamma|)`. Caustics map every vertex through
/// `beta = theta - f alpha(theta)` (arcsec), with `alpha` from `lens` when given, else by
/// bilinear interpolation of the deflection maps; a caustic keeps the vertex count of its
/// critical curve (the SIS caustic is many copies of one point).
///
/// The effective Einstein radius is `sqrt(A / pi)` (arcsec), where `A` is the area where
/// `lambda_t < 0` enclosed by the closed tangential loops of the lens at the map's centre: the
/// sum of the loops' shoelace areas, each signed by its orientation, so a loop nested inside
/// another (around an island with `lambda_t > 0`) counts as a hole. Curves open at the map
/// border do not count: enlarge the map if the tangential curve leaves it. The lens at the
/// centre is what lies within half the map's side of it ([`critical_curves_about`]): a loop
/// wholly beyond, in a corner of the map, belongs to another structure. Maps whose
/// `kappa`/`gamma` do not fill their geometry (only possible when built by hand) give no curves.
pub fn critical_curves(
    maps: &LensMaps,
    f: f64,
    z_source: f64,
    lens: Option<&dyn MassComponent>,
) -> CriticalCurves {
    let geometry = maps.geometry();
    let about = LensRegion {
        center: geometry.center,
        radius_arcsec: 0.5 * geometry.size_arcsec,
    };
    critical_curves_about(maps, f, z_source, lens, about)
}

/// Where the lens whose Einstein radius is measured lies: within `radius_arcsec` of `center`.
///
/// A published model can hold a second structure beside the cluster: Abell 2744's CATS model
/// has a group 110 - 150 arcsec north-west of the cluster whose tangential curve is larger than
/// the cluster's (2650 against 1450 arcsec^2 at z_s = 2). Measured over every loop on a map
/// wide enough to hold it, the cluster's Einstein radius came out 41 arcsec instead of 21.5.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensRegion {
    pub center: DVec2,
    pub radius_arcsec: f64,
}

impl LensRegion {
    /// Whether the curve `points` (closed by the chord from its last point to its first) enters
    /// the region: a vertex in it, or the centre inside (a curve around the whole region).
    fn reaches(&self, points: &[DVec2]) -> bool {
        let r2 = self.radius_arcsec * self.radius_arcsec;
        points.iter().any(|p| p.distance_squared(self.center) <= r2)
            || polygon_contains(points, self.center)
    }
}

/// [`critical_curves`] with the lens at `about` (e.g. a wider map's curves, measured for the
/// lens of a narrower one): the Einstein radius counts the closed tangential loops that enter
/// the region (a vertex in it, or around it) and the loops nested inside those (a hole, or a
/// member's loop inside the cluster's curve, may lie beyond); the curve leaves the map
/// ([`CriticalCurves::tangential_leaves_map`]) only where the region `lambda_t < 0` that
/// crosses the border reaches into `about`. Every curve is traced and returned either way.
pub fn critical_curves_about(
    maps: &LensMaps,
    f: f64,
    z_source: f64,
    lens: Option<&dyn MassComponent>,
    about: LensRegion,
) -> CriticalCurves {
    // The eigenvalues are evaluated on the fly (no full-size temporary maps).
    let geometry = maps.geometry();
    let n = geometry.pixels;
    let fields = [&maps.kappa, &maps.gamma1, &maps.gamma2];
    let consistent = fields
        .iter()
        .all(|m| m.geometry == geometry && m.data.len() == n * n);
    let (k, g1, g2) = (&maps.kappa.data, &maps.gamma1.data, &maps.gamma2.data);
    let shear = |i: usize| (g1[i] * g1[i] + g2[i] * g2[i]).sqrt();
    let lambda_t = |i: usize| 1.0 - f * (k[i] + shear(i));
    let (tangential, radial) = if consistent {
        (
            contours_of(geometry, lambda_t),
            contours_of(geometry, |i| 1.0 - f * (k[i] - shear(i))),
        )
    } else {
        (Vec::new(), Vec::new())
    };
    // Tangential loops run clockwise around their lambda_t < 0 interior (negative area).
    // (A hole runs the other way: its area counts against the sum, and is no main curve.)
    let loop_areas: Vec<f64> = lens_loops(&tangential, about)
        .map(|c| -signed_area_arcsec2(&c.points))
        .collect();
    let area: f64 = loop_areas.iter().sum();
    let einstein_radius_arcsec = (area.max(0.0) / std::f64::consts::PI).sqrt();
    let main_area = loop_areas.iter().copied().fold(0.0, f64::max);
    let main_curve_radius_arcsec = (main_area / std::f64::consts::PI).sqrt();
    // The lens's region lambda_t < 0 reaches the border along more than a few pixels (also when
    // no curve crosses the map because the whole map lies inside the critical curve), or its
    // open curves bound a region that matters next to the closed ones.
    let open_area: f64 = tangential
        .iter()
        .filter(|c| !c.closed && about.reaches(&c.points))
        .map(|c| signed_area_arcsec2(&c.points).abs())
        .sum();
    let tangential_leaves_map = consistent && {
        let border = TANGENTIAL_BORDER_SHARE * (4 * n) as f64;
        let negative = |counted: &dyn Fn(usize) -> bool| {
            (0..n)
                .flat_map(|a| [a, (n - 1) * n + a, a * n, a * n + n - 1])
                .filter(|&i| counted(i))
                .count() as f64
        };
        // Only when the border count says so is it worth finding which pixels are the lens's.
        let leaves_border = negative(&|i| lambda_t(i) < 0.0) > border && {
            let lens_pixels = connected_to(geometry, |i| lambda_t(i) < 0.0, about);
            negative(&|i| lens_pixels[i]) > border
        };
        leaves_border || open_area > OPEN_AREA_SHARE * area.max(0.0)
    };
    let to_source = |curves: &[Contour]| -> Vec<Polyline> {
        curves
            .iter()
            .map(|c| {
                c.points
                    .iter()
                    .map(|&p| source_position(maps, f, lens, p))
                    .collect()
            })
            .collect()
    };
    let caustics = Caustics {
        tangential: to_source(&tangential),
        radial: to_source(&radial),
    };
    let points = |curves: Vec<Contour>| curves.into_iter().map(|c| c.points).collect();
    CriticalCurves {
        z_source,
        einstein_radius_arcsec,
        main_curve_radius_arcsec,
        tangential_leaves_map,
        tangential: points(tangential),
        radial: points(radial),
        caustics,
    }
}

/// The closed loops of `contours` that belong to the lens at `about`: those that enter it, and
/// those nested inside one of these.
fn lens_loops(contours: &[Contour], about: LensRegion) -> impl Iterator<Item = &Contour> {
    let closed: Vec<(&Contour, bool)> = contours
        .iter()
        .filter(|c| c.closed)
        .map(|c| (c, about.reaches(&c.points)))
        .collect();
    let near: Vec<&Contour> = closed.iter().filter(|(_, n)| *n).map(|(c, _)| *c).collect();
    closed.into_iter().filter_map(move |(c, reaches)| {
        let nested = || {
            near.iter()
                .any(|outer| polygon_contains(&outer.points, c.points[0]))
        };
        (reaches || nested()).then_some(c)
    })
}

/// Which pixels of `geometry` are `inside` and joined (through side-by-side pixels that are
/// too) to one whose centre lies in `about`.
fn connected_to(
    geometry: MapGeometry,
    inside: impl Fn(usize) -> bool,
    about: LensRegion,
) -> Vec<bool> {
    let n = geometry.pixels;
    let r2 = about.radius_arcsec * about.radius_arcsec;
    let mut reached = vec![false; n * n];
    let mut stack: Vec<usize> = (0..n * n)
        .filter(|&k| {
            inside(k)
                && geometry
                    .pixel_center(k % n, k / n)
                    .distance_squared(about.center)
                    <= r2
        })
        .collect();
    for &k in &stack {
        reached[k] = true;
    }
    while let Some(k) = stack.pop() {
        let (i, j) = (k % n, k / n);
        let sides = [
            (i > 0).then(|| k - 1),
            (i + 1 < n).then(|| k + 1),
            (j > 0).then(|| k - n),
            (j + 1 < n).then(|| k + n),
        ];
        for s in sides.into_iter().flatten() {
            if !reached[s] && inside(s) {
                reached[s] = true;
                stack.push(s);
            }
        }
    }
    reached
}

/// Point in polygon by the even-odd rule (false for an empty polygon).
pub(crate) fn polygon_contains(poly: &[DVec2], p: DVec2) -> bool {
    let mut odd = false;
    let Some(mut j) = poly.len().checked_sub(1) else {
        return false;
    };
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            odd = !odd;
        }
        j = i;
    }
    odd
}

/// The effective Einstein radius in arcsec of `lens` for a source at `z_source`, from the
/// tangential critical curves on a map of `geometry` (see [`critical_curves`]); 0 when no closed
/// tangential curve lies inside the map.
pub fn einstein_radius_for(
    lens: &dyn MassComponent,
    geometry: MapGeometry,
    plane: &LensPlane,
    z_source: f64,
) -> Result<f64, CosmologyError> {
    let f = plane.distance_ratio(z_source)?;
    let maps = LensMaps::from_lens(lens, geometry);
    Ok(critical_curves(&maps, f, z_source, Some(lens)).einstein_radius_arcsec)
}

/// Source-plane position `beta = theta - f alpha(theta)` in arcsec.
fn source_position(maps: &LensMaps, f: f64, lens: Option<&dyn MassComponent>, p: DVec2) -> DVec2 {
    let alpha = match lens {
        Some(l) => l.deflection(p),
        None => DVec2::new(maps.alpha_x.sample(p), maps.alpha_y.sample(p)),
    };
    p - f * alpha
}

/// Shoelace area of a closed polygon in arcsec^2: positive when counter-clockwise.
pub fn signed_area_arcsec2(points: &[DVec2]) -> f64 {
    let Some(&last) = points.last() else {
        return 0.0;
    };
    let mut prev = last;
    let mut twice = 0.0;
    for &p in points {
        twice += prev.perp_dot(p);
        prev = p;
    }
    0.5 * twice
}

/// The zero contours of `field`, traced between pixel centres by marching squares (see the
/// module doc). A map with fewer than 2 pixels a side, or whose data do not fill it, has none.
/// Infinite values count by their sign; cells with a NaN corner (no data) have no contour, so
/// contours end where the data do, as on the map's edge.
pub fn zero_contours(field: &Map) -> Vec<Contour> {
    let n = field.geometry.pixels;
    if field.data.len() != n * n {
        return Vec::new();
    }
    contours_of(field.geometry, |k| field.data[k])
}

/// The zero contours of the field whose value at pixel `k = j n + i` is `value(k)`.
fn contours_of(geometry: MapGeometry, value: impl Fn(usize) -> f64) -> Vec<Contour> {
    let n = geometry.pixels;
    if n < 2 {
        return Vec::new();
    }
    let grid = EdgeGrid { n, value };
    grid.join(grid.link_segments())
        .into_iter()
        .map(|(edges, closed)| {
            let points = edges
                .into_iter()
                .map(|p| geometry.pixel_to_arcsec(p.x, p.y))
                .collect();
            Contour { points, closed }
        })
        .collect()
}

/// The nodes (pixel centres) and cell edges of an `n x n` map. Edge ids: horizontal edge from
/// node `(i, j)` to `(i+1, j)` is `j (n-1) + i`; vertical edge from `(i, j)` to `(i, j+1)` is
/// `n (n-1) + j n + i`.
struct EdgeGrid<F> {
    n: usize,
    /// The field at node `k = j n + i`.
    value: F,
}

impl<F: Fn(usize) -> f64> EdgeGrid<F> {
    fn horizontal(&self, i: usize, j: usize) -> usize {
        j * (self.n - 1) + i
    }

    fn vertical(&self, i: usize, j: usize) -> usize {
        self.n * (self.n - 1) + j * self.n + i
    }

    /// The contour vertex on edge `e` in fractional pixel coordinates: linear interpolation of
    /// the zero between the edge's two nodes.
    fn vertex(&self, e: usize) -> DVec2 {
        let n = self.n;
        let h = n * (n - 1);
        let (a, b) = if e < h {
            let (i, j) = (e % (n - 1), e / (n - 1));
            ((i, j), (i + 1, j))
        } else {
            let (i, j) = ((e - h) % n, (e - h) / n);
            ((i, j), (i, j + 1))
        };
        let (va, vb) = ((self.value)(a.1 * n + a.0), (self.value)(b.1 * n + b.0));
        let t = va / (va - vb);
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.5
        };
        let pa = DVec2::new(a.0 as f64, a.1 as f64);
        let pb = DVec2::new(b.0 as f64, b.1 as f64);
        pa + t * (pb - pa)
    }

    /// One pass over the cells: the oriented segments `(from edge, to edge)` of the contour.
    fn link_segments(&self) -> Vec<(usize, usize)> {
        let n = self.n;
        let mut segments = Vec::new();
        // Two rows of node values, each node evaluated once.
        let mut row0: Vec<f64> = (0..n).map(|i| (self.value)(i)).collect();
        let mut row1 = vec![0.0; n];
        for j in 0..n - 1 {
            for (i, v) in row1.iter_mut().enumerate() {
                *v = (self.value)((j + 1) * n + i);
            }
            for i in 0..n - 1 {
                // Corners counter-clockwise from the bottom left; edge k runs corner k -> k+1.
                let v = [row0[i], row0[i + 1], row1[i + 1], row1[i]];
                // A cell with a corner without data (NaN) is outside the map.
                if v.iter().any(|x| x.is_nan()) {
                    continue;
                }
                let pos = v.map(|x| x >= 0.0);
                let case = pos
                    .iter()
                    .enumerate()
                    .fold(0u8, |c, (k, &p)| c | (u8::from(p) << k));
                if case == 0 || case == 15 {
                    continue;
                }
                let edges = [
                    self.horizontal(i, j),
                    self.vertical(i + 1, j),
                    self.horizontal(i, j + 1),
                    self.vertical(i, j),
                ];
                // An exit edge goes from a positive to a negative corner; the segment runs from
                // an exit edge to an entry edge, which keeps the positive side on its left.
                let is_exit = |k: usize| pos[k] && !pos[(k + 1) % 4];
                let is_entry = |k: usize| !pos[k] && pos[(k + 1) % 4];
                let mut link = |from: usize, to: usize| segments.push((edges[from], edges[to]));
                if case == 0b0101 || case == 0b1010 {
                    // Saddle: entries and exits alternate. A positive centre joins the positive
                    // corners (exit -> next edge); a negative one separates them
                    // (exit -> previous edge).
                    let centre_positive = v.iter().sum::<f64>() >= 0.0;
                    let step = if centre_positive { 1 } else { 3 };
                    for k in (0..4).filter(|&k| is_exit(k)) {
                        link(k, (k + step) % 4);
                    }
                } else {
                    let from = (0..4).find(|&k| is_exit(k));
                    let to = (0..4).find(|&k| is_entry(k));
                    if let (Some(from), Some(to)) = (from, to) {
                        link(from, to);
                    }
                }
            }
            std::mem::swap(&mut row0, &mut row1);
        }
        segments
    }

    /// Joins the segments into curves: first the open chains (from border edges that no segment
    /// enters), then the loops. Every crossed edge starts at most one segment and ends at most
    /// one, so after sorting by start edge each successor is one binary search away
    /// (`O(S log S)` for `S` segments). Returns each curve's vertices (fractional pixels) and
    /// whether it is closed; duplicate consecutive vertices are merged, and degenerate curves
    /// (fewer than 2 vertices, or 3 for a loop) dropped.
    fn join(&self, mut segments: Vec<(usize, usize)>) -> Vec<(Vec<DVec2>, bool)> {
        segments.sort_unstable();
        let mut ends: Vec<usize> = segments.iter().map(|s| s.1).collect();
        ends.sort_unstable();
        let successor = |e: usize| segments.binary_search_by_key(&e, |s| s.0).ok();
        let mut used = vec![false; segments.len()];
        let mut curves = Vec::new();
        for closed in [false, true] {
            for first in 0..segments.len() {
                let start = segments[first].0;
                if used[first] || (!closed && ends.binary_search(&start).is_ok()) {
                    continue;
                }
                let mut points = vec![self.vertex(start)];
                let mut k = first;
                loop {
                    used[k] = true;
                    let to = segments[k].1;
                    if to == start {
                        break;
                    }
                    push_distinct(&mut points, self.vertex(to));
                    match successor(to) {
                        Some(next) if !used[next] => k = next,
                        _ => break,
                    }
                }
                if closed {
                    while points.len() > 1
                        && points[0].distance(points[points.len() - 1]) < DUPLICATE_PIXELS
                    {
                        points.pop();
                    }
                }
                if points.len() >= if closed { 3 } else { 2 } {
                    curves.push((points, closed));
                }
            }
        }
        curves
    }
}

/// Appends `p` unless it repeats the last vertex.
fn push_distinct(points: &mut Vec<DVec2>, p: DVec2) {
    if points
        .last()
        .is_none_or(|q| q.distance(p) >= DUPLICATE_PIXELS)
    {
        points.push(p);
    }
}

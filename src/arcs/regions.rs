//! Arc pixels from a SAOImage DS9 region file: the arcs as people mark them on an HST image,
//! one region per image, labelled with its id (and redshift).
//!
//! ```text
//! # Region file format: DS9 version 4.1
//! fk5
//! polygon(197.8779,-1.3338,197.8781,-1.3335,197.8776,-1.3331) # text={1.1 z=3.04}
//! ellipse(197.8701,-1.3402,2.1",0.6",35) # text={1.2}
//! circle(197.8712,-1.3399,0.4") # text={2.1 z=1.8}
//! point(197.8688,-1.3381) # text={2.2}
//! -circle(197.8700,-1.3401,0.3")
//! ```
//!
//! - Each included region with an inside (`polygon`, `circle`, `ellipse`, `box`) becomes the
//!   centres of the square lattice of pitch `pixel_arcsec` (the `constraints.pixel_arcsec`
//!   setting, aligned on the frame's origin) that fall inside it, or its centre when none does;
//!   a `point` is one pixel at its position. Regions with the same label add up to one image
//!   (each pixel once).
//! - The label is the region's `text={...}`: the image id `system.image` (its system as a
//!   Lenstool catalogue's, [`crate::system_of_image`]: `1.2` and `2.1a` are images
//!   of systems `1` and `2.1`), then optionally `z=VALUE`. The
//!   images of a system must agree on z ([`redshifts_agree`]) and the system's z is the mean
//!   of its labels', as in a catalogue; a system with no z takes it from the caller's lookup (the app: the loaded
//!   image catalogue's system of that id), or is left without one (`--default-z`, or left out
//!   with a warning).
//! - An excluded region (a leading `-`, e.g. a foreground galaxy on the arc) removes its
//!   pixels from every image.
//! - Positions must be sky coordinates (`fk5`, `icrs`, `j2000`): image-pixel regions are
//!   refused, since the image they were drawn on is not at hand. They are taken into the
//!   frame of the given sky reference, or, without one, of the mean position of the regions.
//!   DS9's angles (counter-clockwise from the first axis) are used as angles from +x (West),
//!   which is the same axis for a north-up image.
//!
//! Errors name the file and line. The pixel count is limited like an arcs file's
//! ([`MAX_ARC_PIXELS`]), and checked from each region's area before any pixel is made.

use std::collections::{HashMap, HashSet};

use glam::DVec2;

use super::{ArcCatalog, ArcSystem, ArcsError, MAX_Z};
use crate::catalog::redshifts_agree;
use crate::ds9::{read_regions, Ds9Frame, Region, Shape};
use crate::limits::{InputKind, TooLarge, MAX_ARC_PIXELS};
use crate::sky::SkyReference;

/// Whether `text` is a DS9 region file rather than an arcs JSON file: its first
/// non-blank character is not `{`.
pub fn is_region_file(text: &str) -> bool {
    text.trim_start().chars().next().is_some_and(|c| c != '{')
}

/// Arcs read from a region file, and the frame they are in.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionArcs {
    pub arcs: ArcCatalog,
    /// The frame's sky reference: the one given, or the regions' mean position.
    pub reference: SkyReference,
    /// Whether `reference` is the regions' mean position (no reference was given).
    pub reference_from_regions: bool,
}

/// Reads the arcs of a DS9 region file (see the module's documentation). `reference` is the
/// frame to use (e.g. the image or member catalogue's), `pixel_arcsec` the lattice pitch,
/// `catalog_z` the redshift of a system whose labels give none.
pub fn arcs_from_regions(
    text: &str,
    source_name: &str,
    reference: Option<SkyReference>,
    pixel_arcsec: f64,
    catalog_z: &dyn Fn(&str) -> Option<f64>,
) -> Result<RegionArcs, ArcsError> {
    TooLarge::check_bytes(source_name, InputKind::Arcs, text.len() as u64)?;
    if !(pixel_arcsec.is_finite() && pixel_arcsec > 0.0) {
        return Err(crate::error::BadFieldValue::new(
            "constraints.pixel_arcsec",
            pixel_arcsec,
            "must be finite and > 0",
        )
        .into());
    }
    let at = |line: usize, reason: String| ArcsError::RegionLine {
        source_name: source_name.to_string(),
        line,
        reason,
    };
    let regions = sky_regions(text, source_name, &at)?;
    let (reference, reference_from_regions) = match reference {
        Some(r) => (r, false),
        None => (
            mean_position(&regions).map_err(|(line, e)| at(line, e))?,
            true,
        ),
    };
    let (labelled, excluded) = shapes_in_frame(&regions, reference, &at)?;
    let lattice = Lattice {
        pitch: pixel_arcsec,
    };
    check_pixel_count(&labelled, &lattice, &at)?;
    let systems = group_into_systems(&labelled, &excluded, &lattice, &at)?;
    let mut out = Vec::with_capacity(systems.len());
    for s in systems {
        out.push(s.finish(catalog_z, &at)?);
    }
    Ok(RegionArcs {
        arcs: ArcCatalog {
            source_name: source_name.to_string(),
            systems: out,
        },
        reference,
        reference_from_regions,
    })
}

/// An error on one line of the region file.
type At<'a> = dyn Fn(usize, String) -> ArcsError + 'a;

/// The file's regions, refused when they are in image pixels or none can be an arc.
fn sky_regions(text: &str, source_name: &str, at: &At) -> Result<Vec<Region>, ArcsError> {
    let regions = read_regions(text, source_name).map_err(ArcsError::Regions)?;
    if let Some(r) = regions.iter().find(|r| r.frame == Ds9Frame::Image) {
        return Err(at(
            r.line,
            "is in image pixels: the image it was drawn on is not at hand here; save the \
             regions in sky coordinates (DS9: Region > Save..., coordinate system fk5)"
                .into(),
        ));
    }
    if !regions.iter().any(|r| r.include) {
        return Err(ArcsError::RegionFile {
            source_name: source_name.to_string(),
            reason: "holds no region to use as an arc (polygon, circle, ellipse, box or point)"
                .into(),
        });
    }
    Ok(regions)
}

/// The regions as shapes in the frame of `reference`: the included ones with their labels,
/// and the excluded ones (`-` regions), which cut pixels out.
#[allow(clippy::type_complexity)]
fn shapes_in_frame<'r>(
    regions: &'r [Region],
    reference: SkyReference,
    at: &At,
) -> Result<(Vec<(Label, &'r Region, Shape)>, Vec<Shape>), ArcsError> {
    let mut labelled = Vec::new();
    let mut excluded = Vec::new();
    for r in regions {
        let shape = r
            .to_frame_arcsec(Some(reference), None)
            .map_err(|e| at(r.line, e.to_string()))?;
        if let Shape::Polyline(_) = shape {
            return Err(at(
                r.line,
                "an open line has no inside: draw the arc as a polygon".into(),
            ));
        }
        if r.include {
            let label = Label::parse(r.text.as_deref()).map_err(|e| at(r.line, e))?;
            labelled.push((label, r, shape));
        } else {
            excluded.push(shape);
        }
    }
    Ok((labelled, excluded))
}

/// Refuses the file, before any pixel is made, when its regions would hold more than
/// [`MAX_ARC_PIXELS`] pixels (the error is on the line where the count passes it).
fn check_pixel_count(
    labelled: &[(Label, &Region, Shape)],
    lattice: &Lattice,
    at: &At,
) -> Result<(), ArcsError> {
    let mut total = 0u64;
    for (_, r, shape) in labelled {
        total = total.saturating_add(lattice.estimate(shape));
        if total > MAX_ARC_PIXELS as u64 {
            return Err(at(
                r.line,
                format!(
                    "the regions up to here hold up to {total} pixels of {} arcsec, \
                     more than the limit of {MAX_ARC_PIXELS} for arcs; use a larger \
                     constraints.pixel_arcsec or smaller regions",
                    lattice.pitch
                ),
            ));
        }
    }
    Ok(())
}

/// The labelled regions grouped by system and image, with their lattice pixels (less the
/// excluded shapes) and the redshifts of their labels, which must agree within a system.
fn group_into_systems(
    labelled: &[(Label, &Region, Shape)],
    excluded: &[Shape],
    lattice: &Lattice,
    at: &At,
) -> Result<Vec<SystemBuild>, ArcsError> {
    let mut systems: Vec<SystemBuild> = Vec::new();
    for (label, r, shape) in labelled {
        let k = match systems.iter().position(|s| s.id == label.system) {
            Some(k) => k,
            None => {
                systems.push(SystemBuild::new(&label.system, r.line));
                systems.len() - 1
            }
        };
        let s = &mut systems[k];
        if let Some(z) = label.z {
            s.add_redshift(z, label, r.line, at)?;
        }
        let pixels = lattice.inside(shape, excluded);
        s.add(&label.image, r.line, pixels);
    }
    Ok(systems)
}

/// A region's label: `system.image` and an optional `z=VALUE`.
#[derive(Debug, Clone, PartialEq)]
struct Label {
    system: String,
    image: String,
    z: Option<f64>,
}

impl Label {
    fn parse(text: Option<&str>) -> Result<Self, String> {
        const HOW: &str = "label each arc with its image id, e.g. text={1.1} or text={1.1 z=2.5}";
        let text = text.unwrap_or("").trim();
        let mut tokens = text.split_whitespace();
        let Some(image) = tokens.next() else {
            return Err(format!("a region without a label: {HOW}"));
        };
        let system = match crate::catalog::system_of_image(image) {
            Some(system) if image.contains('.') => system,
            _ => {
                return Err(format!(
                    "label '{text}': '{image}' is not an image id of the form system.image; {HOW}"
                ))
            }
        };
        let mut z = None;
        for t in tokens {
            let value = t
                .strip_prefix("z=")
                .ok_or_else(|| format!("label '{text}': '{t}' is not z=VALUE; {HOW}"))?;
            let v: f64 = value
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| format!("label '{text}': z = '{value}' is not a number"))?;
            z = Some(v);
        }
        Ok(Self {
            system: system.to_string(),
            image: image.to_string(),
            z,
        })
    }
}

/// A system being read: its images (id, first line, pixel positions) in file order.
struct SystemBuild {
    id: String,
    line: usize,
    /// The lowest and the highest z of its labels so far, with their lines.
    z_range: Option<((f64, usize), (f64, usize))>,
    /// Sum and count of the labels' z: the system's z is their mean, as in a catalogue.
    z_sum: f64,
    z_count: usize,
    images: Vec<(String, usize, Vec<DVec2>)>,
    /// The pixels of each image so far (bit patterns: a lattice point is always computed
    /// the same way), so that overlapping regions count each pixel once.
    seen: HashMap<String, HashSet<[u64; 2]>>,
}

impl SystemBuild {
    fn new(id: &str, line: usize) -> Self {
        Self {
            id: id.to_string(),
            line,
            z_range: None,
            z_sum: 0.0,
            z_count: 0,
            images: Vec::new(),
            seen: HashMap::new(),
        }
    }

    /// Adds the redshift `z` of one label (on `line`): in (0, MAX_Z), and agreeing with the
    /// system's others (checked against the lowest and the highest so far: then every pair
    /// agrees).
    fn add_redshift(
        &mut self,
        z: f64,
        label: &Label,
        line: usize,
        at: &At,
    ) -> Result<(), ArcsError> {
        if !(z > 0.0 && z < MAX_Z) {
            return Err(at(line, format!("z = {z} must be in (0, {MAX_Z})")));
        }
        for &(z0, line0) in self.z_range.iter().flat_map(|(lo, hi)| [lo, hi]) {
            if !redshifts_agree(z, z0) {
                return Err(at(
                    line,
                    format!(
                        "image {}: z = {z}, but line {line0} gives system {} z = {z0}",
                        label.image, label.system
                    ),
                ));
            }
        }
        self.z_range = Some(match self.z_range {
            None => ((z, line), (z, line)),
            Some((lo, hi)) => (
                if z < lo.0 { (z, line) } else { lo },
                if z > hi.0 { (z, line) } else { hi },
            ),
        });
        self.z_sum += z;
        self.z_count += 1;
        Ok(())
    }

    /// The system with its images in file order and its redshift: the mean of its labels', or
    /// `catalog_z` of its id. An image that the excluded regions emptied is an error.
    fn finish(
        self,
        catalog_z: &dyn Fn(&str) -> Option<f64>,
        at: &At,
    ) -> Result<ArcSystem, ArcsError> {
        let mut images = Vec::with_capacity(self.images.len());
        let mut image_ids = Vec::with_capacity(self.images.len());
        for (id, line, pixels) in self.images {
            if pixels.is_empty() {
                return Err(at(
                    line,
                    format!("image {id}: an excluded region covers all of its pixels"),
                ));
            }
            images.push(pixels);
            image_ids.push(id);
        }
        let z = if self.z_count > 0 {
            Some(self.z_sum / self.z_count as f64)
        } else {
            catalog_z(&self.id)
        };
        Ok(ArcSystem {
            id: self.id,
            z,
            images,
            image_ids,
            line: self.line,
        })
    }

    /// Adds the pixels of one region to the image `id` (each pixel once).
    fn add(&mut self, id: &str, line: usize, pixels: Vec<DVec2>) {
        let k = match self.images.iter().position(|(i, _, _)| i == id) {
            Some(k) => k,
            None => {
                self.images.push((id.to_string(), line, Vec::new()));
                self.images.len() - 1
            }
        };
        let seen = self.seen.entry(id.to_string()).or_default();
        let image = &mut self.images[k].2;
        image.extend(
            pixels
                .into_iter()
                .filter(|p| seen.insert([p.x.to_bits(), p.y.to_bits()])),
        );
    }
}

/// The square lattice of pixel centres `(i, j) * pitch` in the frame.
struct Lattice {
    pitch: f64,
}

impl Lattice {
    fn position(&self, (i, j): (i64, i64)) -> DVec2 {
        DVec2::new(i as f64, j as f64) * self.pitch
    }

    fn index(&self, p: DVec2) -> (i64, i64) {
        let q = (p / self.pitch).round();
        (q.x as i64, q.y as i64)
    }

    /// Lattice points in the shape's bounding box: an upper bound of its pixel count.
    fn estimate(&self, shape: &Shape) -> u64 {
        let (lo, hi) = bounds(shape);
        let n = ((hi - lo) / self.pitch).ceil() + DVec2::ONE;
        (n.x.max(1.0) * n.y.max(1.0)).min(u64::MAX as f64) as u64
    }

    /// The lattice points inside `shape` and outside every `excluded` shape; the shape's
    /// centre (exactly) when no lattice point is inside (a point, or a region smaller than a
    /// pixel), unless that is excluded.
    fn inside(&self, shape: &Shape, excluded: &[Shape]) -> Vec<DVec2> {
        let kept = |p: DVec2| !excluded.iter().any(|e| contains(e, p));
        let (lo, hi) = bounds(shape);
        let (i0, j0) = self.index(lo);
        let (i1, j1) = self.index(hi);
        let mut out = Vec::new();
        if !matches!(shape, Shape::Point(_)) {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let p = self.position((i, j));
                    if contains(shape, p) && kept(p) {
                        out.push(p);
                    }
                }
            }
        }
        if out.is_empty() {
            let c = match shape {
                Shape::Point(p) => *p,
                _ => 0.5 * (lo + hi),
            };
            if kept(c) {
                out.push(c);
            }
        }
        out
    }
}

/// The bounding box `(min, max)` of a shape (arcsec).
fn bounds(shape: &Shape) -> (DVec2, DVec2) {
    let corners = |pts: &[DVec2]| {
        let lo = pts.iter().copied().fold(DVec2::INFINITY, DVec2::min);
        let hi = pts.iter().copied().fold(DVec2::NEG_INFINITY, DVec2::max);
        (lo, hi)
    };
    match shape {
        Shape::Polygon(v) | Shape::Polyline(v) => corners(v),
        Shape::Point(p) => (*p, *p),
        Shape::Circle { center, radius } => (
            *center - DVec2::splat(*radius),
            *center + DVec2::splat(*radius),
        ),
        Shape::Ellipse {
            center,
            radii,
            angle_deg,
        } => {
            let (s, c) = angle_deg.to_radians().sin_cos();
            let half = DVec2::new(
                (radii.x * c).hypot(radii.y * s),
                (radii.x * s).hypot(radii.y * c),
            );
            (*center - half, *center + half)
        }
        Shape::Box {
            center,
            size,
            angle_deg,
        } => {
            let (s, c) = angle_deg.to_radians().sin_cos();
            let h = 0.5 * *size;
            let half = DVec2::new(
                (h.x * c).abs() + (h.y * s).abs(),
                (h.x * s).abs() + (h.y * c).abs(),
            );
            (*center - half, *center + half)
        }
    }
}

/// Whether `p` lies inside `shape` (polygons by the even-odd rule; lines and points have no
/// inside).
fn contains(shape: &Shape, p: DVec2) -> bool {
    // The offset from `center` in the frame of an axis at `angle_deg`.
    let along = |center: DVec2, angle_deg: f64| {
        let (s, c) = angle_deg.to_radians().sin_cos();
        let d = p - center;
        DVec2::new(d.x * c + d.y * s, -d.x * s + d.y * c)
    };
    match shape {
        Shape::Polygon(v) => {
            let mut inside = false;
            for k in 0..v.len() {
                let (a, b) = (v[k], v[(k + 1) % v.len()]);
                if (a.y > p.y) != (b.y > p.y) {
                    let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                    if p.x < x {
                        inside = !inside;
                    }
                }
            }
            inside
        }
        Shape::Polyline(_) | Shape::Point(_) => false,
        Shape::Circle { center, radius } => p.distance_squared(*center) <= radius * radius,
        Shape::Ellipse {
            center,
            radii,
            angle_deg,
        } => (along(*center, *angle_deg) / *radii).length_squared() <= 1.0,
        Shape::Box {
            center,
            size,
            angle_deg,
        } => {
            let d = along(*center, *angle_deg).abs();
            d.x <= 0.5 * size.x && d.y <= 0.5 * size.y
        }
    }
}

/// The mean sky position of the included regions (their centres, or the mean of a polygon's
/// vertices; fk5 degrees), as a reference, averaged as the catalogues average absolute
/// positions ([`crate::catalog::mean_position`]: RA across 0/360 correctly). A position that is
/// not on the sky is an error with its line.
fn mean_position(regions: &[Region]) -> Result<SkyReference, (usize, String)> {
    let mut points = Vec::new();
    for r in regions.iter().filter(|r| r.include) {
        let p = match &r.shape {
            Shape::Polygon(v) | Shape::Polyline(v) => {
                let c = crate::catalog::mean_position(v);
                DVec2::new(c.ra_deg, c.dec_deg)
            }
            Shape::Point(p)
            | Shape::Circle { center: p, .. }
            | Shape::Ellipse { center: p, .. }
            | Shape::Box { center: p, .. } => *p,
        };
        if SkyReference::new(p.x, p.y).is_none() {
            return Err((
                r.line,
                format!(
                    "({}, {}) is not a sky position (RA, Dec in degrees)",
                    p.x, p.y
                ),
            ));
        }
        points.push(p);
    }
    Ok(crate::catalog::mean_position(&points))
}

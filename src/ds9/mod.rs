//! SAOImage DS9 region files ([method §7]): critical curves and caustics out, regions
//! (e.g. arcs marked by users) in.
//!
//! Written files start with `# Region file format: DS9 version 4.1` and a `global` line, then
//! either `fk5` (when the frame has a sky reference; RA, Dec in degrees from
//! [`SkyReference::offset_to_radec`]) or `image` (1-based FITS pixel coordinates of the map the
//! curves were traced on: the centre of the first pixel is (1, 1)). A closed curve is a
//! `polygon`, a curve cut by the map edge an open `segment` (DS9's multi-point polyline;
//! `line` takes two points only). Colours: tangential critical curves red, radial critical
//! curves cyan, caustics yellow (the radial caustic dashed); each region carries a
//! `tag={...}` and the first of each kind a `text={...}` label.
//!
//! [method §7]: crate::method#7-file-formats

use std::fmt::Write;

use glam::DVec2;
use thiserror::Error;

use crate::curves::{CriticalCurves, Polyline};
use crate::map::MapGeometry;
use crate::sky::SkyReference;

mod parse;

pub use parse::read_regions;

/// What is wrong in a region file; `file` is the name given by the caller, `line` 1-based.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Ds9Error {
    #[error("{file} line {line}: `{token}`: {reason}")]
    Syntax {
        file: String,
        line: usize,
        token: String,
        reason: String,
    },
    #[error("{file} line {line}: coordinate system `{frame}` is not supported (use fk5, icrs, j2000, image or physical)")]
    UnsupportedFrame {
        file: String,
        line: usize,
        frame: String,
    },
    #[error("{file} line {line}: region shape `{shape}` is not supported (polygon, point, circle, ellipse, box, line, segment){hint}")]
    UnsupportedShape {
        file: String,
        line: usize,
        shape: String,
        /// What the file is instead, when that is plain (a Lenstool catalogue's row), or "".
        hint: &'static str,
    },
    #[error("region on line {line} is in fk5: the frame needs a sky reference (RA, Dec of its origin) to use it")]
    NeedsReference { line: usize },
}

/// The coordinate system of a region as written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ds9Frame {
    /// `fk5` / `icrs` / `j2000`: positions are (RA, Dec) in degrees, lengths in arcsec.
    Fk5,
    /// `image` / `physical`: 1-based pixel positions and lengths in pixels.
    Image,
}

/// A region's geometry. Units depend on where it is used: see [`Ds9Frame`] for a parsed
/// [`Region`]; [`Region::to_frame_arcsec`] gives arcsec in the frame of [method §1].
/// Angles are degrees counter-clockwise from the +x axis (DS9's convention).
///
/// [method §1]: crate::method#1-frames-and-units
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    Polygon(Vec<DVec2>),
    /// An open curve (`line` or `segment`).
    Polyline(Vec<DVec2>),
    Point(DVec2),
    Circle {
        center: DVec2,
        radius: f64,
    },
    Ellipse {
        center: DVec2,
        radii: DVec2,
        angle_deg: f64,
    },
    Box {
        center: DVec2,
        size: DVec2,
        angle_deg: f64,
    },
}

/// One region read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    pub frame: Ds9Frame,
    pub shape: Shape,
    /// `text={...}` property, if any.
    pub text: Option<String>,
    /// `color=...` property, if any.
    pub color: Option<String>,
    /// False for excluded regions (a leading `-`).
    pub include: bool,
    /// 1-based line in the file.
    pub line: usize,
}

impl Region {
    /// The shape in arcsec in the frame of [method §1]: fk5 positions through
    /// [`SkyReference::to_offset_arcsec`] (needs `reference`), image positions through
    /// `geometry.pixel_to_arcsec(x - 1, y - 1)` and lengths times the pixel size (needs
    /// `geometry`). Angles are unchanged: +x is West in both cases for HFF maps.
    pub fn to_frame_arcsec(
        &self,
        reference: Option<SkyReference>,
        geometry: Option<&MapGeometry>,
    ) -> Result<Shape, Ds9Error> {
        let (pos, len): (Box<dyn Fn(DVec2) -> DVec2>, f64) = match (self.frame, reference, geometry)
        {
            (Ds9Frame::Fk5, Some(r), _) => {
                (Box::new(move |p: DVec2| r.to_offset_arcsec(p.x, p.y)), 1.0)
            }
            (Ds9Frame::Image, _, Some(g)) => {
                let g = *g;
                (
                    Box::new(move |p: DVec2| g.pixel_to_arcsec(p.x - 1.0, p.y - 1.0)),
                    g.pixel_arcsec(),
                )
            }
            _ => return Err(Ds9Error::NeedsReference { line: self.line }),
        };
        Ok(match &self.shape {
            Shape::Polygon(v) => Shape::Polygon(v.iter().map(|&p| pos(p)).collect()),
            Shape::Polyline(v) => Shape::Polyline(v.iter().map(|&p| pos(p)).collect()),
            Shape::Point(p) => Shape::Point(pos(*p)),
            Shape::Circle { center, radius } => Shape::Circle {
                center: pos(*center),
                radius: radius * len,
            },
            Shape::Ellipse {
                center,
                radii,
                angle_deg,
            } => Shape::Ellipse {
                center: pos(*center),
                radii: *radii * len,
                angle_deg: *angle_deg,
            },
            Shape::Box {
                center,
                size,
                angle_deg,
            } => Shape::Box {
                center: pos(*center),
                size: *size * len,
                angle_deg: *angle_deg,
            },
        })
    }
}

/// Whether `line` is an open curve cut by the edge of the map it was traced on: both ends
/// within 2 pixels of the map border and more than 2 steps (median step, at least a pixel)
/// apart. Closed curves do not repeat their first point, so their ends are one step apart.
pub fn polyline_is_open(line: &[DVec2], geometry: &MapGeometry) -> bool {
    let (Some(&first), Some(&last)) = (line.first(), line.last()) else {
        return false;
    };
    let pixel = geometry.pixel_arcsec();
    let half = geometry.size_arcsec / 2.0;
    let near_edge = |p: DVec2| {
        let d = (p - geometry.center).abs();
        half - d.x.max(d.y) <= 2.0 * pixel
    };
    let mut steps: Vec<f64> = line.windows(2).map(|w| w[0].distance(w[1])).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps.get(steps.len() / 2).copied().unwrap_or(0.0);
    line.len() >= 2
        && near_edge(first)
        && near_edge(last)
        && first.distance(last) > 2.0 * median.max(pixel)
}

/// The start of a written region file (the version line, `comment` lines, the `global` line
/// and the coordinate system) and how positions and lengths are written in it: `fk5` in degrees
/// and arcsec when `reference` is known, else `image` pixels of `geometry`.
struct RegionText<'a> {
    out: String,
    reference: Option<SkyReference>,
    geometry: &'a MapGeometry,
}

impl<'a> RegionText<'a> {
    fn new(comment: &str, reference: Option<SkyReference>, geometry: &'a MapGeometry) -> Self {
        let mut out = String::from("# Region file format: DS9 version 4.1\n");
        for line in comment.lines() {
            let _ = writeln!(out, "# {line}");
        }
        out.push_str(
            "global color=green dashlist=8 3 width=2 font=\"helvetica 10 normal roman\" select=1 \
             highlite=1 dash=0 fixed=0 edit=1 move=1 delete=1 include=1 source=1\n",
        );
        out.push_str(if reference.is_some() {
            "fk5\n"
        } else {
            "image\n"
        });
        Self {
            out,
            reference,
            geometry,
        }
    }

    /// A position (arcsec in the frame) as written: `ra,dec` or `x,y` (1-based pixels).
    fn coord(&self, p: DVec2) -> String {
        match self.reference {
            Some(r) => {
                let (ra, dec) = r.offset_to_radec(p);
                format!("{ra:.8},{dec:.8}")
            }
            None => {
                let q = self.geometry.arcsec_to_pixel(p) + DVec2::ONE;
                format!("{:.4},{:.4}", q.x, q.y)
            }
        }
    }

    /// A length (arcsec) as written: `0.5"` or pixels.
    fn length(&self, arcsec: f64) -> String {
        match self.reference {
            Some(_) => format!("{arcsec}\""),
            None => format!("{:.4}", arcsec / self.geometry.pixel_arcsec()),
        }
    }
}

/// DS9 region text for the critical curves and caustics (module docs): `fk5` in degrees when
/// `reference` is known, else `image` pixels of `geometry` (the map the curves were traced on).
/// Non-finite points are dropped and curves of fewer than 2 points skipped.
pub fn write_regions(
    curves: &CriticalCurves,
    reference: Option<SkyReference>,
    geometry: &MapGeometry,
) -> String {
    let mut text = RegionText::new(
        &format!(
            "WSLAP+ critical curves and caustics, z_source = {}, Einstein radius = {:.3} arcsec",
            curves.z_source, curves.einstein_radius_arcsec
        ),
        reference,
        geometry,
    );
    let z = curves.z_source;
    let groups: [(&[Polyline], &str, String, &str); 4] = [
        (
            &curves.tangential,
            "red",
            format!("tangential critical curve z={z}"),
            "",
        ),
        (
            &curves.radial,
            "cyan",
            format!("radial critical curve z={z}"),
            "",
        ),
        (
            &curves.caustics.tangential,
            "yellow",
            format!("tangential caustic z={z}"),
            "",
        ),
        (
            &curves.caustics.radial,
            "yellow",
            format!("radial caustic z={z}"),
            " dash=1",
        ),
    ];
    for (lines, color, label, dash) in groups {
        let mut first = true;
        for line in lines {
            let line: Vec<DVec2> = line.iter().copied().filter(|p| p.is_finite()).collect();
            if line.len() < 2 {
                continue;
            }
            let open = line.len() < 3 || polyline_is_open(&line, geometry);
            let shape = if open { "segment" } else { "polygon" };
            let coords: Vec<String> = line.iter().map(|&p| text.coord(p)).collect();
            let label_text = if first {
                format!(" text={{{label}}}")
            } else {
                String::new()
            };
            first = false;
            let _ = writeln!(
                text.out,
                "{shape}({}) # color={color}{dash} tag={{{label}}}{label_text}",
                coords.join(",")
            );
        }
    }
    text.out
}

/// One position marked by a circle in [`write_marks`].
#[derive(Debug, Clone, PartialEq)]
pub struct Mark {
    /// Arcsec in the frame of [method §1].
    ///
    /// [method §1]: crate::method#1-frames-and-units
    pub position_arcsec: DVec2,
    /// The `text={...}` label (no braces).
    pub label: String,
    /// A DS9 colour name.
    pub color: &'static str,
    /// The `tag={...}`: what kind of mark it is.
    pub tag: &'static str,
    pub dashed: bool,
}

/// DS9 region text with a circle of `radius_arcsec` about each mark (non-finite positions are
/// skipped), after `comment` lines; frames as in [`write_regions`].
pub fn write_marks(
    comment: &str,
    marks: &[Mark],
    radius_arcsec: f64,
    reference: Option<SkyReference>,
    geometry: &MapGeometry,
) -> String {
    let mut text = RegionText::new(comment, reference, geometry);
    let radius = text.length(radius_arcsec);
    for m in marks.iter().filter(|m| m.position_arcsec.is_finite()) {
        let coord = text.coord(m.position_arcsec);
        let dash = if m.dashed { " dash=1" } else { "" };
        let _ = writeln!(
            text.out,
            "circle({coord},{radius}) # color={}{dash} tag={{{}}} text={{{}}}",
            m.color, m.tag, m.label
        );
    }
    text.out
}

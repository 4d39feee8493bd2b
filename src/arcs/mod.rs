//! Arc files: constraint pixels given explicitly, per system and image, as JSON (arcsec) or
//! as DS9 regions ([`arcs_from_regions`]).
//!
//! Errors name the file and the line where the faulty system's object starts (a syntax error:
//! its own line and column), and the file's size and pixel count are limited
//! ([`crate::limits::MAX_ARCS_BYTES`], [`MAX_ARC_PIXELS`]).

use glam::DVec2;
use serde::Deserialize;
use serde_json::value::RawValue;

use thiserror::Error;

use crate::limits::{json_error_parts, InputKind, TooLarge, MAX_ARC_PIXELS};

mod regions;

pub use regions::{arcs_from_regions, is_region_file, RegionArcs};

/// What is wrong with an arcs file (JSON or DS9 regions); every message names the file and,
/// where there is one, the line.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ArcsError {
    #[error("{source_name}: line {line}, column {column}: {message}")]
    Syntax {
        source_name: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// One system of an arcs file; `line` is where the system's object starts.
    #[error("{source_name}: line {line}: system {system}: {reason}")]
    System {
        source_name: String,
        line: usize,
        system: String,
        reason: String,
    },
    #[error(transparent)]
    TooLarge(#[from] crate::limits::TooLarge),
    /// A DS9 region file that does not parse (the message names the file and line).
    #[error(transparent)]
    Regions(#[from] crate::ds9::Ds9Error),
    /// One region of a DS9 region file used as arcs.
    #[error("{source_name}: line {line}: {reason}")]
    RegionLine {
        source_name: String,
        line: usize,
        reason: String,
    },
    /// A DS9 region file as a whole.
    #[error("{source_name}: {reason}")]
    RegionFile { source_name: String, reason: String },
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
}

/// Explicit arc pixels, from [`parse_arcs`].
#[derive(Debug, Clone, PartialEq)]
pub struct ArcCatalog {
    pub source_name: String,
    pub systems: Vec<ArcSystem>,
}

/// The pixels of one system of an arc file; a flat `pixels` list is one image.
#[derive(Debug, Clone, PartialEq)]
pub struct ArcSystem {
    pub id: String,
    pub z: Option<f64>,
    /// Pixel positions in arcsec, per image.
    pub images: Vec<Vec<DVec2>>,
    /// The images' ids (from a DS9 region file's labels); empty: `system.1`, `system.2`, ...
    /// in order.
    pub image_ids: Vec<String>,
    /// Line of the file where the system's object starts (1-based; 0 when the system was
    /// not read from a file).
    pub line: usize,
}

impl ArcSystem {
    /// The images' ids: the file's labels when every image has one, else `system.1`,
    /// `system.2`, ... in order.
    pub fn image_ids(&self) -> Vec<String> {
        if self.image_ids.len() == self.images.len() {
            self.image_ids.clone()
        } else {
            (1..=self.images.len())
                .map(|k| format!("{}.{k}", self.id))
                .collect()
        }
    }
}

/// Largest source redshift accepted (exclusive).
pub(crate) const MAX_Z: f64 = 20.0;

#[derive(Deserialize)]
#[serde(untagged)]
enum IdJson {
    Text(String),
    Number(serde_json::Number),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ArcSystemJson {
    id: IdJson,
    #[serde(default)]
    z: Option<f64>,
    #[serde(default)]
    pixels: Option<Vec<[f64; 2]>>,
    #[serde(default)]
    images: Option<Vec<Vec<[f64; 2]>>>,
}

/// The file with each system kept as its text, to know where it starts.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ArcsJson<'a> {
    #[serde(borrow)]
    systems: Vec<&'a RawValue>,
}

/// Parses an arc file (`source_name` names it in errors):
///
/// ```json
/// {"systems": [
///   {"id": "1", "z": 2.1, "pixels": [[x, y], ...]},
///   {"id": "2", "z": null, "images": [[[x, y], ...], [[x, y], ...]]}]}
/// ```
///
/// Positions in arcsec in the frame of [method §1]. Each system has either `pixels`
/// (all its pixels, counted as one image) or `images` (one pixel list per image); `z` null,
/// 0 or absent means unknown, otherwise `0 < z < 20`. Ids must be unique, pixel lists
/// non-empty and finite; at most [`MAX_ARC_PIXELS`] pixels in all and
/// [`crate::limits::MAX_ARCS_BYTES`] of text.
///
/// [method §1]: crate::method#1-frames-and-units
pub fn parse_arcs(text: &str, source_name: &str) -> Result<ArcCatalog, ArcsError> {
    TooLarge::check_bytes(source_name, InputKind::Arcs, text.len() as u64)?;
    // `part` is the text serde_json parsed, which starts at `at` in the file.
    let syntax = |e: serde_json::Error, part: &str, at: (usize, usize)| {
        let (line, column, message) = json_error_parts(part, &e);
        // Lines and columns of an error inside one system count from the system's start.
        let (line, column) = match (line, at) {
            (0, _) => at,
            (1, (l, c)) => (l, c + column - 1),
            (n, (l, _)) => (l + n - 1, column),
        };
        ArcsError::Syntax {
            source_name: source_name.to_string(),
            line,
            column,
            message,
        }
    };
    let raw: ArcsJson = serde_json::from_str(text).map_err(|e| syntax(e, text, (1, 1)))?;
    let mut systems: Vec<ArcSystem> = Vec::with_capacity(raw.systems.len());
    let mut total_pixels = 0usize;
    for raw_system in raw.systems {
        let (line, column) = place(text, raw_system.get());
        let s: ArcSystemJson = serde_json::from_str(raw_system.get())
            .map_err(|e| syntax(e, raw_system.get(), (line, column)))?;
        let id = match s.id {
            IdJson::Text(t) => t,
            IdJson::Number(n) => n.to_string(),
        };
        let fail = |reason: String| ArcsError::System {
            source_name: source_name.to_string(),
            line,
            system: id.clone(),
            reason,
        };
        if systems.iter().any(|o| o.id == id) {
            return Err(fail("the id appears twice".into()));
        }
        let images: Vec<Vec<[f64; 2]>> = match (s.pixels, s.images) {
            (Some(p), None) => vec![p],
            (None, Some(i)) => i,
            _ => return Err(fail("give exactly one of \"pixels\" and \"images\"".into())),
        };
        if images.is_empty() {
            return Err(fail("no pixels: \"images\" is an empty list".into()));
        }
        if let Some(k) = images.iter().position(Vec::is_empty) {
            return Err(fail(format!(
                "no pixels in image {k} (from 0): every pixel list must hold at least one pixel"
            )));
        }
        if let Some(p) = images
            .iter()
            .flatten()
            .find(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(fail(format!("pixel [{}, {}] is not finite", p[0], p[1])));
        }
        total_pixels += images.iter().map(Vec::len).sum::<usize>();
        TooLarge::check(
            source_name,
            "pixels",
            total_pixels as u64,
            MAX_ARC_PIXELS as u64,
            "an arcs file",
        )?;
        let z = match s.z {
            Some(0.0) => None,
            Some(z) if !(z.is_finite() && z > 0.0 && z < MAX_Z) => {
                return Err(fail(format!(
                    "z = {z} must be in (0, {MAX_Z}), or 0/null when unknown"
                )));
            }
            z => z,
        };
        systems.push(ArcSystem {
            id,
            z,
            images: images
                .into_iter()
                .map(|i| i.into_iter().map(|[x, y]| DVec2::new(x, y)).collect())
                .collect(),
            image_ids: Vec::new(),
            line,
        });
    }
    Ok(ArcCatalog {
        source_name: source_name.to_string(),
        systems,
    })
}

/// 1-based line and column (in bytes, as serde_json counts) where `part`, a slice of `text`,
/// starts.
fn place(text: &str, part: &str) -> (usize, usize) {
    let offset = (part.as_ptr() as usize)
        .saturating_sub(text.as_ptr() as usize)
        .min(text.len());
    let before = &text.as_bytes()[..offset];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    (line, offset - line_start + 1)
}

//! Lenstool catalogues: multiple images, cluster members and weak-lensing arclets
//! ([method §7]).
//!
//! Positions are brought into the arcsec frame of one sky reference (+x West, +y North).
//! [`parse_image_catalog`] and [`parse_member_catalog`] read Lenstool's text formats; the
//! caller passes the frame it wants (e.g. the members' reference) so that every catalogue of a
//! run shares one frame.
//!
//! [method §7]: crate::method#7-file-formats

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::sky::SkyReference;

mod arclets;
mod error;
mod frame;
mod lenstool;
mod rows;
mod units;

pub use arclets::{
    arclet_ellipticity, parse_arclet_catalog, parse_arclet_catalog_with, Arclet, ArcletCatalog,
    ArcletUnknownZ,
};
pub use error::{CatalogError, CatalogKind, CatalogWarning};
pub(crate) use frame::{mean_position, reframe, sexagesimal};
pub(crate) use lenstool::galaxy_indices;
pub use lenstool::{
    galaxy_of_system, parse_image_catalog, parse_member_catalog, parse_potfile_catalog,
    redshifts_agree, system_of_image, MAG_NO_MEASUREMENT, Z_AGREEMENT_TOL,
};
pub use units::{DEGREE_LOOKALIKE, FIELD_ERROR_DEG, FIELD_WARN_DEG};

/// One observed image of a multiply-lensed source.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Image {
    /// The catalogue id, e.g. `"4.2"`.
    pub id: String,
    /// Position in arcsec in the catalogue's frame.
    pub position: DVec2,
    /// Ellipse semi-axes in arcsec (Lenstool `a`, `b`) and position angle in degrees
    /// counter-clockwise from +x (Lenstool `theta`).
    pub a_arcsec: f64,
    pub b_arcsec: f64,
    pub theta_deg: f64,
    /// Magnitude column (0 when unknown).
    pub mag: f64,
    /// 1-based line of the catalogue it came from (for messages).
    pub line: usize,
}

/// The images of one source, grouped by their ids as Lenstool groups them ([`system_of_image`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageSystem {
    /// System id, e.g. `"4"`.
    pub id: String,
    /// Source redshift (`None` when the catalogue says 0: unknown).
    pub z: Option<f64>,
    pub images: Vec<Image>,
}

/// A parsed multiple-image catalogue.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageCatalog {
    /// File name, for messages.
    pub source_name: String,
    /// The frame's sky origin: the reference the caller asked for, else the `#REFERENCE`
    /// position, else (absolute degrees without one) the mean image position.
    pub reference: Option<SkyReference>,
    /// Systems in the order of first appearance.
    pub systems: Vec<ImageSystem>,
}

/// One cluster member galaxy of a Lenstool potfile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Member {
    pub id: String,
    pub position: DVec2,
    pub a_arcsec: f64,
    pub b_arcsec: f64,
    pub theta_deg: f64,
    /// Magnitude (the mass-to-light scaling uses it).
    pub mag: f64,
    /// The 8th column as written (luminosity, or in some files a redshift); not interpreted.
    pub lum: f64,
    pub line: usize,
}

/// One row of a catalogue, by its 1-based line and id: e.g. a commented-out BCG row a run
/// offers to fit (`BcgFacts::commented`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CatalogRow {
    pub line: usize,
    pub id: String,
}

/// Commented-out member rows that are most likely the cluster's brightest galaxies (BCGs, one
/// per core): near the multiple images, bright enough, where no fitted member is
/// (`missing_bcg_warning` in the inversion). `note` says so in a sentence naming the file and
/// the lines.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CommentedBcgs {
    /// In the file's order; never empty.
    pub rows: Vec<CatalogRow>,
    pub note: String,
}

/// A parsed member (potfile) catalogue.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MemberCatalog {
    pub source_name: String,
    pub reference: Option<SkyReference>,
    pub members: Vec<Member>,
    /// Rows the file comments out (`#` lines that read as members), in the same frame: never
    /// fitted, but named when the members seem to lack their brightest cluster galaxy, which
    /// Lenstool set-ups often comment out because the `.par` models it on its own.
    #[serde(default)]
    pub commented: Vec<Member>,
    /// The commented-out rows a run fits as BCGs, moved from `commented` to `members`
    /// (`Dataset::fit_commented_bcgs`); a run's warnings carry their note.
    #[serde(default)]
    pub fitted_bcgs: Option<CommentedBcgs>,
    /// The members (indices into [`Self::members`]) a Lenstool `.par` models on its own
    /// (`Dataset::add_par_galaxies`: added from it, or named by a galaxy of it without a
    /// `mag`, commented-out rows included; not the potfile members a `best.par` writes out
    /// again): the set-up's own choice of the galaxies that need it, its BCGs among them. One
    /// near the multiple images counts as their BCG, whatever its magnitude: none is then said
    /// to be missing or looked for among the commented rows. Indices, not ids: a `.par` names
    /// its potentials `1`, `2`, ... as a catalogue often numbers its rows, and a catalogue
    /// member that shares a `.par` galaxy's name is not that galaxy.
    #[serde(default)]
    pub par_galaxies: Vec<usize>,
    /// The name of the `.par` whose galaxies were looked for (`Dataset::add_par_galaxies`),
    /// if one was: a missing BCG's warning then says that file models none near the images,
    /// rather than asking for a `.par`.
    #[serde(default)]
    pub par_source: Option<String>,
    /// The `.par` galaxies (indices into [`Self::members`], as [`Self::par_galaxies`]) whose
    /// mass its `limit` blocks leave free (a starting model:
    /// [`crate::lenstool_par::FreeMass`]), made members at the least mass of those priors:
    /// each has a layer of its own rather than sharing the luminosity-scaled members' factor
    /// (one galaxy's mass is no measure of the others'; where the images do not measure its
    /// factor, the prior of an unmeasured layer holds it near 1, the least mass).
    #[serde(default)]
    pub free_mass_galaxies: Vec<usize>,
    /// The `.par` galaxies (indices into [`Self::members`]) without a `mag` that no member
    /// or commented-out row stands for, made members of the magnitude whose halo mass under
    /// the member law is their dPIE's: their `mag` is that law's, not one a file wrote.
    #[serde(default)]
    pub mass_galaxies: Vec<usize>,
}

impl ImageCatalog {
    /// Systems whose source redshift is known (`z` is `Some`), in catalogue order.
    pub fn systems_with_redshift(&self) -> impl Iterator<Item = &ImageSystem> + '_ {
        self.systems.iter().filter(|s| s.z.is_some())
    }

    /// Systems whose source redshift is unknown (`z = 0` in the file), in catalogue order.
    pub fn unknown_redshift_systems(&self) -> impl Iterator<Item = &ImageSystem> + '_ {
        self.systems.iter().filter(|s| s.z.is_none())
    }

    /// The catalogue with `z` given to every system of unknown redshift (known ones are kept).
    /// `z` must be finite and > 0.
    pub fn with_default_z(mut self, z: f64) -> Result<Self, CatalogError> {
        if !(z.is_finite() && z > 0.0) {
            return Err(CatalogError::BadDefaultRedshift {
                source_name: self.source_name,
                z,
            });
        }
        for s in &mut self.systems {
            s.z.get_or_insert(z);
        }
        Ok(self)
    }

    /// Every image, system by system.
    pub fn images(&self) -> impl Iterator<Item = &Image> + '_ {
        self.systems.iter().flat_map(|s| s.images.iter())
    }

    /// Number of images over all systems.
    pub fn image_count(&self) -> usize {
        self.systems.iter().map(|s| s.images.len()).sum()
    }

    /// `(min, max)` corners in arcsec of the box holding every image position;
    /// `(0, 0)`, `(0, 0)` for a catalogue without images.
    pub fn bounding_box_arcsec(&self) -> (DVec2, DVec2) {
        bounding_box(self.images().map(|im| im.position))
    }

    /// The catalogue in the arcsec frame of `to`: every position goes through its sky position,
    /// `p' = to.to_offset_arcsec(from.offset_to_radec(p))`. Fails without a reference or with an
    /// unusable `to` (non-finite, `|Dec| >= 90`).
    pub fn reframed(mut self, to: SkyReference) -> Result<Self, CatalogError> {
        let (from, to) = reframe_pair(self.reference, to, &self.source_name)?;
        for s in &mut self.systems {
            for im in &mut s.images {
                im.position = frame::reframe(im.position, from, to);
            }
        }
        self.reference = Some(to);
        Ok(self)
    }
}

impl MemberCatalog {
    /// Records member `index` (into [`Self::members`]) as one the `.par` models on its own
    /// ([`Self::par_galaxies`]), once.
    pub fn note_par_galaxy(&mut self, index: usize) {
        if !self.par_galaxies.contains(&index) {
            self.par_galaxies.push(index);
        }
    }

    /// The ids of the members at `indices` (into [`Self::members`]; e.g.
    /// [`Self::par_galaxies`]), in that order.
    pub fn ids(&self, indices: &[usize]) -> Vec<&str> {
        indices
            .iter()
            .map(|&k| self.members[k].id.as_str())
            .collect()
    }

    /// The catalogue in the arcsec frame of `to` (see [`ImageCatalog::reframed`]).
    pub fn reframed(mut self, to: SkyReference) -> Result<Self, CatalogError> {
        let (from, to) = reframe_pair(self.reference, to, &self.source_name)?;
        for m in self.members.iter_mut().chain(&mut self.commented) {
            m.position = frame::reframe(m.position, from, to);
        }
        self.reference = Some(to);
        Ok(self)
    }

    /// `(min, max)` corners in arcsec of the box holding every member position;
    /// `(0, 0)`, `(0, 0)` for a catalogue without members.
    pub fn bounding_box_arcsec(&self) -> (DVec2, DVec2) {
        bounding_box(self.members.iter().map(|m| m.position))
    }
}

fn reframe_pair(
    from: Option<SkyReference>,
    to: SkyReference,
    source_name: &str,
) -> Result<(SkyReference, SkyReference), CatalogError> {
    let from = from.ok_or_else(|| CatalogError::NoReference {
        source_name: source_name.into(),
    })?;
    let to = frame::check_requested(Some(to), source_name)?.unwrap_or(to);
    Ok((from, to))
}

fn bounding_box(points: impl Iterator<Item = DVec2>) -> (DVec2, DVec2) {
    points
        .fold(None, |acc: Option<(DVec2, DVec2)>, p| {
            Some(acc.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
        })
        .unwrap_or((DVec2::ZERO, DVec2::ZERO))
}

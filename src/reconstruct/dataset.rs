//! A reconstruction's data read from the user's files, the same way in every shell (the CLI
//! and the app): one frame for every file, DS9 region arcs with the catalogue's redshifts, and
//! one rule for which constraints are fitted.
//!
//! - **Frame.** The image catalogue's `#REFERENCE` sets the frame; the member catalogue is read
//!   in it (or sets it when there is no image catalogue); a member catalogue that is the
//!   potfile of a `.par` given with it may be headerless arcsec from the `.par`'s reference;
//!   DS9 region arcs are read in that frame,
//!   or, with no catalogue at all, in a frame centred on the regions' mean position (a warning
//!   says so).
//! - **Weak lensing.** An arclet catalogue is read in the frame of the others (or sets it when
//!   it is the only catalogue).
//! - **Redshifts of region arcs.** A region labelled without `z=` takes the redshift of the
//!   system of the same id in the image catalogue.
//! - **Which constraints.** With an image catalogue and arcs, the setting
//!   `constraints.mode` chooses: `"arcs"` fits the arc pixels, `"point"` and `"ellipse"` the
//!   catalogue (a warning says that the arcs are not fitted). Arcs alone are fitted as arcs
//!   whatever the mode says.

use std::collections::BTreeMap;

use glam::DVec2;
use thiserror::Error;

use super::{
    bcg_candidates, image_centres, with_luminosity, Inputs, LayerSource, ReconstructConfig,
};
use crate::arcs::{
    arcs_from_regions, is_region_file, parse_arcs, ArcCatalog, ArcsError, RegionArcs,
};
use crate::catalog::{
    parse_arclet_catalog_with, parse_image_catalog, parse_member_catalog, parse_potfile_catalog,
    reframe, system_of_image, ArcletCatalog, ArcletUnknownZ, CatalogError, CatalogRow,
    CommentedBcgs, ImageCatalog, Member, MemberCatalog,
};
use crate::cosmology::LensPlane;
use crate::error::{and_list, line_list};
use crate::inversion::{
    build_constraints, missing_bcg_warning, ConstraintMode, ConstraintSource, RedshiftPrior,
};
use crate::lenstool_par::{
    LenstoolPar, ParError, ParGalaxies, ParHalo, UnknownSourceZ, GALAXY_MAX_CORE_KPC,
};
use crate::sky::SkyReference;

/// One input file: the name used in messages and its text.
#[derive(Debug, Clone, Copy)]
pub struct InputText<'a> {
    pub name: &'a str,
    pub text: &'a str,
}

/// The files a reconstruction can be given; each is optional.
#[derive(Debug, Clone, Copy, Default)]
pub struct InputTexts<'a> {
    /// Lenstool multiple-image catalogue.
    pub images: Option<InputText<'a>>,
    /// Lenstool member catalogue.
    pub members: Option<InputText<'a>>,
    /// Arc pixels: a JSON arcs file or a DS9 region file.
    pub arcs: Option<InputText<'a>>,
    /// Lenstool arclet catalogue (weak lensing).
    pub shear: Option<InputText<'a>>,
    /// The `reference` of a Lenstool `.par` given with the files whose `potfile` the member
    /// catalogue is ([`LenstoolPar::potfile_reference`]): a member catalogue without a header,
    /// in arcsec, is then read in that frame, as Lenstool reads it
    /// ([`crate::catalog::parse_potfile_catalog`]).
    pub potfile_reference: Option<SkyReference>,
    /// What a Lenstool `.par` given with the files says of sources without a redshift
    /// ([`LenstoolPar::unknown_source_z`]): arclet rows with `z = 0` take it, as Lenstool
    /// gives it them. `None` (no `.par`): such rows are refused, with what to do.
    pub unknown_source_z: Option<&'a Result<UnknownSourceZ, String>>,
}

/// The arclet reader's rule for rows without a redshift, from a `.par`'s answer
/// ([`InputTexts::unknown_source_z`]).
pub(crate) fn arclet_unknown_z(
    answer: Option<&Result<UnknownSourceZ, String>>,
) -> ArcletUnknownZ<'_> {
    match answer {
        None => ArcletUnknownZ::Refuse,
        Some(Ok(u)) => ArcletUnknownZ::Take {
            z: u.z,
            origin: &u.origin,
        },
        Some(Err(why)) => ArcletUnknownZ::RefuseBecause(why),
    }
}

/// What went wrong reading the files (each message names the file and, where there is one,
/// the line).
#[derive(Debug, Error)]
pub enum DatasetError {
    #[error(transparent)]
    Catalog(#[from] CatalogError),
    #[error(transparent)]
    Arcs(#[from] ArcsError),
    #[error("give an image catalogue or an arcs file to reconstruct")]
    NoConstraints,
    #[error(transparent)]
    Par(#[from] ParError),
}

/// Two galaxies closer than this (arcsec) are the same one: a `.par` galaxy the member
/// catalogue already lists is not added again ([`Dataset::add_par_galaxies`]).
pub const SAME_GALAXY_ARCSEC: f64 = 1.0;

/// Most luminous (in `L*`, under the member law) a `.par` galaxy without a `mag` may be made
/// a member from its mass ([`Dataset::add_par_galaxies`]): a BCG's dPIE with a long cut
/// radius comes to tens of `L*` (`1e12 Msun` each), a group's or cluster's halo with a small
/// core to hundreds or thousands.
pub const PAR_GALAXY_MAX_LSTAR: f64 = 100.0;

/// The catalogues read into one frame (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct Dataset {
    pub images: Option<ImageCatalog>,
    pub arcs: Option<ArcCatalog>,
    pub members: Option<MemberCatalog>,
    /// Weak-lensing galaxies.
    pub shear: Option<ArcletCatalog>,
    /// The frame of arcs read from a DS9 region file without a catalogue to give one (the
    /// regions' mean position).
    pub arcs_reference: Option<SkyReference>,
    /// What the reading noticed, one sentence each, naming the file.
    pub warnings: Vec<String>,
    /// Redshift priors of the systems by their catalogue id, from a `.par`
    /// ([`Self::add_par`]); [`Self::inputs`] adds them to `constraints.z_priors` (where a
    /// settings file's own prior for a system wins).
    pub z_priors: BTreeMap<String, RedshiftPrior>,
}

impl Dataset {
    /// Reads `files`; DS9 region arcs are sampled at `arc_pixel_arcsec`.
    pub fn read(files: &InputTexts<'_>, arc_pixel_arcsec: f64) -> Result<Self, DatasetError> {
        let mut out = Self::default();
        if let Some(f) = files.images {
            let (c, w) = parse_image_catalog(f.text, f.name, None)?;
            out.warnings.extend(w.iter().map(ToString::to_string));
            out.images = Some(c);
        }
        if let Some(f) = files.members {
            let frame = out.images.as_ref().and_then(|c| c.reference);
            let (m, w) = match (files.potfile_reference, frame, &out.images) {
                // A potfile is read in the `.par`'s frame, then moved into the images'.
                (Some(par), Some(to), _) => {
                    let (m, w) = parse_potfile_catalog(f.text, f.name, Some(par))?;
                    (m.reframed(to)?, w)
                }
                (Some(par), None, None) => parse_potfile_catalog(f.text, f.name, Some(par))?,
                _ => parse_member_catalog(f.text, f.name, frame)?,
            };
            out.warnings.extend(w.iter().map(ToString::to_string));
            out.members = Some(m);
        }
        if let Some(f) = files.shear {
            let frame = out.reference();
            let unknown_z = arclet_unknown_z(files.unknown_source_z);
            let (a, w) = parse_arclet_catalog_with(f.text, f.name, frame, unknown_z)?;
            out.warnings.extend(w.iter().map(ToString::to_string));
            out.shear = Some(a);
        }
        if let Some(f) = files.arcs {
            out.arcs = Some(if is_region_file(f.text) {
                let frame = out.reference();
                let r = region_arcs(f, frame, arc_pixel_arcsec, out.images.as_ref())?;
                if frame.is_none() {
                    out.arcs_reference = Some(r.reference);
                    out.warnings.push(format!(
                        "{}: no catalogue gives a frame, so its origin is the regions' mean position (RA {:.6}, Dec {:.6} deg): the maps are centred there",
                        f.name, r.reference.ra_deg, r.reference.dec_deg
                    ));
                }
                r.arcs
            } else {
                parse_arcs(f.text, f.name)?
            });
        }
        Ok(out)
    }

    /// What a reconstruction takes from a Lenstool `.par` of the same cluster: the galaxies it
    /// models on its own ([`Self::add_par_galaxies`]) and the redshift priors of its `image`
    /// block ([`Self::add_par_redshift_priors`]). One sentence per thing taken or not.
    /// The galaxies' masses are read with the member law of `config` on `plane`.
    pub fn add_par(
        &mut self,
        par: &LenstoolPar,
        plane: &LensPlane,
        config: &ReconstructConfig,
    ) -> Result<Vec<String>, DatasetError> {
        let mut notes = self.add_par_galaxies(par, plane, config)?;
        notes.extend(self.add_par_redshift_priors(par));
        Ok(notes)
    }

    /// Takes the `.par`'s `z_m_limit` priors ([`LenstoolPar::redshift_priors`]) for the
    /// systems of the image catalogue (or arcs) they name, as Lenstool does: over the
    /// catalogue's redshift. An id matches a system's by its text, as a number (`6.0` is
    /// system `6`), or as the id of one of its images (`6.1` or `6a`, grouped as the image
    /// catalogue groups them). A prior that puts the source in front of the `.par`'s lens (a
    /// fixed redshift, the top of a range or a normal's mean at or below `z_lens`: an
    /// optimiser that hit its floor) is not taken. One sentence per line: taken, not taken,
    /// or naming no system.
    pub fn add_par_redshift_priors(&mut self, par: &LenstoolPar) -> Vec<String> {
        let ids: Vec<String> = match (&self.images, &self.arcs) {
            (Some(c), _) => c.systems.iter().map(|s| s.id.clone()).collect(),
            (None, Some(a)) => a.systems.iter().map(|s| s.id.clone()).collect(),
            (None, None) => Vec::new(),
        };
        let number = |id: &str| id.parse::<f64>().ok();
        let name = &par.source_name;
        par.redshift_priors
            .iter()
            .map(|p| {
                let named = |id: &&String| {
                    **id == p.system
                        || matches!((number(id), number(&p.system)), (Some(a), Some(b)) if a == b)
                };
                let Some(id) = ids.iter().find(named).or_else(|| {
                    ids.iter()
                        .find(|id| Some(id.as_str()) == system_of_image(&p.system))
                }) else {
                    return format!(
                        "{name}: line {}: `z_m_limit` names system {}, which no catalogue \
                         loaded has: not used",
                        p.line, p.system
                    );
                };
                let nearest = match p.prior {
                    RedshiftPrior::Fixed(z) => z,
                    RedshiftPrior::Range([_, high]) => high,
                    RedshiftPrior::Normal([mean, _]) => mean,
                };
                if nearest <= par.z_lens {
                    return format!(
                        "{name}: line {}: system {id}'s prior ({}) puts it in front of the lens \
                         (z_lens = {}): not used",
                        p.line,
                        p.prior.describe(),
                        par.z_lens
                    );
                }
                self.z_priors.insert(id.clone(), p.prior);
                format!(
                    "{name}: line {}: system {id}'s redshift {}",
                    p.line,
                    match p.prior {
                        RedshiftPrior::Fixed(z) => format!("is taken as {z}"),
                        other =>
                            format!("is estimated under the model's prior, {}", other.describe()),
                    }
                )
            })
            .collect()
    }

    /// Adds the galaxies a Lenstool `.par` models on its own ([`LenstoolPar::galaxies`]: e.g.
    /// the BCG a potfile catalogue leaves out) to the members, in the data's frame (a member
    /// catalogue is made when there is none); those it adds are recorded in
    /// [`MemberCatalog::par_galaxies`]. A galaxy without a `mag` (a fitted `bestopt.par` lists
    /// each galaxy it modelled so; a starting `.par` gives its BCG a velocity dispersion to
    /// fit) takes the row the member catalogue comments out within 1 arcsec of it, as Lenstool
    /// set-ups do with the galaxies their `.par` models; without one it becomes a member of
    /// the magnitude whose halo mass under the member law of `config` is its dPIE's total mass
    /// ([`crate::inversion::MemberConfig::mag_of_mass`] on `plane`), unless that mass is a group's (over
    /// [`PAR_GALAXY_MAX_LSTAR`] L*, left to the grid even when a member lies at its centre).
    /// One sentence per galaxy says what became of it (one for all of a kind when there are
    /// many): added; already a member (a catalogue member lies within 1 arcsec); its commented
    /// row fitted; or left out. A galaxy the `.par` writes twice is fitted twice, as Lenstool
    /// reads it, with a sentence.
    pub fn add_par_galaxies(
        &mut self,
        par: &LenstoolPar,
        plane: &LensPlane,
        config: &ReconstructConfig,
    ) -> Result<Vec<String>, DatasetError> {
        let ParGalaxies {
            members: mut rows,
            without_mag,
            other_plane,
            halos,
        } = par.galaxies()?;
        let name = &par.source_name;
        let frame = self.reference();
        // A position of the .par's frame in the data's (the same without a reference).
        let to_data = |p: DVec2| match (par.reference, frame) {
            (Some(from), Some(to)) => reframe(p, from, to),
            _ => p,
        };
        let mut notes = Vec::new();
        let law = &config.members;
        let mag_star = law.mag_star_on(plane);
        let mut by_mass = Vec::new();
        // The lines of those taken at their priors' least mass (a layer of their own each).
        let mut free_mass = Vec::new();
        for g in &without_mag {
            // A halo of a group's mass centred on a galaxy (MACS J1149's northern group `O4`
            // on member 1824) is not that galaxy: it is left to the grid, whatever lies there.
            // Its mass, the magnitude of that halo mass under the member law, and its L*.
            let by_law = g.mass_msun.map(|mass| {
                let mag = law.mag_of_mass(mass, mag_star);
                (mass, mag, law.luminosity_lstar(mag, mag_star))
            });
            if let Some((mass, _, lstar)) = by_law.filter(|b| b.2 > PAR_GALAXY_MAX_LSTAR) {
                let on = self
                    .member_near(to_data(g.centre))
                    .map_or(String::new(), |(_, id)| {
                        format!(" (centred on member {id}, which is fitted as a member)")
                    });
                notes.push(format!(
                    "{name}: line {}: `{}` has no `mag` and a dPIE mass of {mass:.2e} Msun \
                     ({lstar:.0} L* under the member law): a group's halo, not a galaxy's: not \
                     fitted as a member{on}; the grid models its mass",
                    g.line, g.block
                ));
                continue;
            }
            if let Some(note) = self.galaxy_without_mag(name, &g.block, g.line, to_data(g.centre)) {
                notes.push(note);
                continue;
            }
            let Some((_, mag, _)) = by_law else {
                notes.push(format!(
                    "{name}: line {}: `{}` has no `mag` and its radii make no dPIE (the cut \
                     radius must exceed the core): not fitted",
                    g.line, g.block
                ));
                continue;
            };
            // A starting `.par`'s galaxy whose mass its `limit` block leaves free: its least
            // mass there ([`crate::lenstool_par::FreeMass`]), in a layer of its own, said.
            if let Some((limit, [sigma, core, cut])) = g.at_prior_low_end {
                notes.push(format!(
                    "{name}: line {}: `{}`'s mass is left free by its `limit` block (line \
                     {limit}), so its written values are where a fit starts, not a mass: it is \
                     taken at the priors' low ends where they are above 0 (v_disp {sigma:.0} \
                     km/s, core {core:.2} kpc, cut {cut:.0} kpc), in a layer of its own: its \
                     factor C is not the members'",
                    g.line, g.block
                ));
                free_mass.push(g.line);
            }
            by_mass.push(Member {
                id: g.id.clone(),
                position: g.centre,
                a_arcsec: 1.0,
                b_arcsec: g.axis_ratio,
                theta_deg: g.pa_deg,
                mag,
                lum: 0.0,
                line: g.line,
            });
        }
        // A best.par lists every galaxy it fitted (hundreds): one sentence for all of them.
        match &by_mass[..] {
            [] => {}
            [g] => notes.push(format!(
                "{name}: line {}: galaxy {} has no `mag`: fitted as a member of mag {:.2}, the \
                 magnitude whose halo mass under the member law is its dPIE's",
                g.line, g.id, g.mag
            )),
            many => notes.push(format!(
                "{name}: {} galaxies without a `mag` (lines {}) are fitted as members of the \
                 magnitudes whose halo masses under the member law are their dPIEs' (mag {:.2} \
                 to {:.2})",
                many.len(),
                line_list(many.iter().map(|g| g.line)),
                many.iter().map(|g| g.mag).fold(f64::INFINITY, f64::min),
                many.iter().map(|g| g.mag).fold(f64::NEG_INFINITY, f64::max),
            )),
        }
        // The galaxies with a `mag` have a sentence each below; those by mass had theirs.
        let with_mag = rows.len();
        rows.extend(by_mass);
        notes.extend(other_plane.iter().map(|(block, line, z)| {
            format!(
                "{name}: line {line}: `{block}` is a galaxy at z = {z}, not at the cluster's \
                 z_lens = {}: not fitted",
                par.z_lens
            )
        }));
        // The blocks with a core too wide for a galaxy (the cluster's halos, groups', a galaxy
        // given a wide core): said last, so that no block of the .par goes unmentioned.
        let wide = |h: &ParHalo| {
            format!(
                "`{}` (line {}, core {:.0} kpc)",
                h.block, h.line, h.core_kpc
            )
        };
        let halo_note = match &halos[..] {
            [] => None,
            [h] => Some(format!(
                "{name}: {} has a core wider than a galaxy's (over {GALAXY_MAX_CORE_KPC} kpc): \
                 not fitted as a member; the grid models its mass",
                wide(h)
            )),
            many => Some(format!(
                "{name}: {} have cores wider than a galaxy's (over {GALAXY_MAX_CORE_KPC} kpc): \
                 not fitted as members; the grid models their mass",
                and_list(many.iter().map(wide))
            )),
        };
        if let Some(members) = self.members.as_mut() {
            members.par_source = Some(name.clone());
        }
        if rows.is_empty() {
            notes.extend(halo_note);
            return Ok(notes);
        }
        if par.reference.is_none() && frame.is_some() {
            notes.push(format!(
                "{name}: no `runmode reference`: its galaxies' positions are taken in the \
                 catalogues' frame"
            ));
        }
        let members = self.members.get_or_insert_with(|| MemberCatalog {
            source_name: name.clone(),
            reference: frame.or(par.reference),
            members: Vec::new(),
            commented: Vec::new(),
            fitted_bcgs: None,
            par_galaxies: Vec::new(),
            par_source: None,
            free_mass_galaxies: Vec::new(),
            mass_galaxies: Vec::new(),
        });
        members.par_source = Some(name.clone());
        // Galaxies the catalogue lists already (a `best.par` writes every potfile member out
        // as a `potentiel` of its own): one sentence for all of them. Only the catalogue's:
        // a `potentiel` the `.par` repeats is two galaxies to Lenstool, and here.
        let catalogued = members.members.len();
        let mut already = Vec::new();
        let mut repeated = Vec::new();
        for (k, mut g) in rows.into_iter().enumerate() {
            g.position = to_data(g.position);
            let (x, y) = (g.position.x, g.position.y);
            let same = |m: &&Member| m.position.distance(g.position) <= SAME_GALAXY_ARCSEC;
            let near = members.members[..catalogued].iter().find(same);
            if let Some(m) = near {
                already.push((
                    g.line,
                    format!(
                        "line {}: galaxy {} at ({x:.2}, {y:.2}) arcsec is member {}",
                        g.line, g.id, m.id
                    ),
                ));
                continue;
            }
            // Added already from the `.par` itself, as written: a repeat.
            if let Some(first) = members.members[catalogued..].iter().find(same) {
                if first.id == g.id && first.mag == g.mag {
                    repeated.push((g.line, first.line));
                }
            }
            if k < with_mag {
                notes.push(format!(
                    "{name}: line {}: galaxy {} at ({x:.2}, {y:.2}) arcsec, mag {:.2}, fitted as \
                     a member",
                    g.line, g.id, g.mag
                ));
            }
            let index = members.members.len();
            members.note_par_galaxy(index);
            if k >= with_mag {
                members.mass_galaxies.push(index);
                if free_mass.contains(&g.line) {
                    members.free_mass_galaxies.push(index);
                }
            }
            members.members.push(g);
        }
        if !repeated.is_empty() {
            let pairs: Vec<String> = repeated
                .iter()
                .map(|(line, first)| format!("{line} repeats line {first}"))
                .collect();
            let (what, mass) = match repeated.len() {
                1 => ("1 galaxy is".to_string(), "its mass; delete one"),
                n => (
                    format!("{n} galaxies are"),
                    "each one's mass; delete one of each",
                ),
            };
            notes.push(format!(
                "{name}: {what} written twice (line {}): both are fitted (as Lenstool reads \
                 them), which doubles {mass} if that is not meant",
                pairs.join(", line ")
            ));
        }
        match &already[..] {
            [] => {}
            [(_, one)] => notes.push(format!(
                "{name}: {one} of {} already: not added twice",
                members.source_name
            )),
            many => notes.push(format!(
                "{name}: {} galaxies (lines {}) are members of {} already: not added twice",
                many.len(),
                line_list(many.iter().map(|(line, _)| *line)),
                members.source_name
            )),
        }
        notes.extend(halo_note);
        Ok(notes)
    }

    /// The index (in [`MemberCatalog::members`]) and id of the member within
    /// [`SAME_GALAXY_ARCSEC`] of `at` (arcsec, the data's frame).
    fn member_near(&self, at: DVec2) -> Option<(usize, String)> {
        let members = self.members.as_ref()?;
        let index = members
            .members
            .iter()
            .position(|m| m.position.distance(at) <= SAME_GALAXY_ARCSEC)?;
        Some((index, members.members[index].id.clone()))
    }

    /// What becomes of the `.par`'s galaxy `block` (at `line`) without a `mag`, centred at `at`
    /// (arcsec, the data's frame): the member there already, or the commented-out row of the
    /// member catalogue there moved to the members (the note says which), or nothing (`None`).
    fn galaxy_without_mag(
        &mut self,
        name: &str,
        block: &str,
        line: usize,
        at: DVec2,
    ) -> Option<String> {
        let near = |m: &&Member| m.position.distance(at) <= SAME_GALAXY_ARCSEC;
        let on_member = self.member_near(at);
        if let Some(members) = self.members.as_mut() {
            if let Some((index, id)) = on_member {
                let note = format!(
                    "{name}: line {line}: `{block}` (no `mag`) is member {id} of {} already",
                    members.source_name
                );
                members.note_par_galaxy(index);
                return Some(note);
            }
            if let Some(k) = members.commented.iter().position(|m| near(&m)) {
                let row = members.commented.remove(k);
                // Its index once pushed below.
                let index = members.members.len();
                members.note_par_galaxy(index);
                let note = format!(
                    "{name}: line {line}: `{block}` has no `mag`; the row {} comments out \
                     there (line {}, galaxy {}, mag {:.2}) is fitted as a member",
                    members.source_name, row.line, row.id, row.mag
                );
                members.members.push(row);
                return Some(note);
            }
        }
        None
    }

    /// Fits the member catalogue's commented-out rows that are most likely the cluster's
    /// brightest galaxies (BCGs, one per core), when `config.members.fit_commented_bcg` is on
    /// (the default): no member near the multiple images is as bright as a BCG and commented
    /// rows there are (`missing_bcg_warning` in the inversion). Lenstool set-ups model the BCGs
    /// as their own `potentiel`s in the `.par` and comment their rows out of the potfile
    /// catalogue; a run without the `.par` has no other way to fit them. The rows move from
    /// [`MemberCatalog::commented`] to the members, [`MemberCatalog::fitted_bcgs`] keeps them
    /// with a note a run's warnings carry, and they are returned (none when nothing is
    /// fitted). Call it after [`Self::add_par_galaxies`]: a BCG the `.par` gives is not
    /// replaced. The multiple images are the constraints `config` fits, every system included.
    pub fn fit_commented_bcgs(
        &mut self,
        plane: &LensPlane,
        config: &ReconstructConfig,
    ) -> Vec<CatalogRow> {
        let (Some(found), Some(members)) =
            (self.commented_bcgs(plane, config), self.members.as_mut())
        else {
            return Vec::new();
        };
        let (fitted, kept): (Vec<Member>, Vec<Member>) = std::mem::take(&mut members.commented)
            .into_iter()
            .partition(|m| found.rows.iter().any(|r| r.line == m.line));
        members.commented = kept;
        members.members.extend(fitted);
        let rows = found.rows.clone();
        members.fitted_bcgs = Some(found);
        rows
    }

    /// The commented-out rows [`Self::fit_commented_bcgs`] would fit, if any.
    fn commented_bcgs(
        &self,
        plane: &LensPlane,
        config: &ReconstructConfig,
    ) -> Option<CommentedBcgs> {
        let members = self.members.as_ref()?;
        if !config.members.fit_commented_bcg
            || members.commented.is_empty()
            || members.fitted_bcgs.is_some()
        {
            return None;
        }
        let (source, _) = self.constraints(config.constraints.mode).ok()?;
        let constraints = build_constraints(source, &config.constraints, &[]).ok()?;
        missing_bcg_warning(
            &members.source_name,
            members.par_source.as_deref(),
            &bcg_candidates(members, &config.members, plane),
            &image_centres(&constraints),
            &with_luminosity(&members.commented, &config.members, plane),
        )?
        .commented
    }

    /// The frame's sky reference: the image catalogue's, else the member catalogue's, else the
    /// arclet catalogue's, else the region file's mean position.
    pub fn reference(&self) -> Option<SkyReference> {
        let images = self.images.as_ref().and_then(|c| c.reference);
        let members = self.members.as_ref().and_then(|m| m.reference);
        let shear = self.shear.as_ref().and_then(|a| a.reference);
        images.or(members).or(shear).or(self.arcs_reference)
    }

    /// The constraints fitted under `mode` and the mode they are fitted with (see the module
    /// documentation).
    pub fn constraints(
        &self,
        mode: ConstraintMode,
    ) -> Result<(ConstraintSource<'_>, ConstraintMode), DatasetError> {
        match (&self.images, &self.arcs) {
            (Some(_), Some(a)) if mode == ConstraintMode::Arcs => {
                Ok((ConstraintSource::Arcs(a), mode))
            }
            (Some(c), _) => Ok((ConstraintSource::Catalog(c), mode)),
            (None, Some(a)) => Ok((ConstraintSource::Arcs(a), ConstraintMode::Arcs)),
            (None, None) => Err(DatasetError::NoConstraints),
        }
    }

    /// The warning that loaded arcs are not fitted under `mode` (a catalogue is, see
    /// [`Self::constraints`]); `None` when they are, or when there are none.
    pub fn unfitted_arcs(&self, mode: ConstraintMode) -> Option<String> {
        match (&self.images, &self.arcs) {
            (Some(c), Some(a)) if mode != ConstraintMode::Arcs => Some(format!(
                "{}: its arc pixels are not fitted: constraints.mode is \"{}\", so the image catalogue {} is (set the mode to \"arcs\" to fit the arcs)",
                a.source_name,
                mode.name(),
                c.source_name
            )),
            _ => None,
        }
    }

    /// The reconstruction's inputs from this data, in lens plane `plane` with the systems
    /// `holdout` left out of the fit. Sets `config.constraints.mode` to the mode the constraints
    /// are fitted with (see [`Self::constraints`]).
    pub fn inputs<'a>(
        &'a self,
        plane: LensPlane,
        holdout: &'a [String],
        config: &mut ReconstructConfig,
    ) -> Result<Inputs<'a>, DatasetError> {
        let (images, mode) = self.constraints(config.constraints.mode)?;
        config.constraints.mode = mode;
        for (id, prior) in &self.z_priors {
            config
                .constraints
                .z_priors
                .entry(id.clone())
                .or_insert(*prior);
        }
        let inputs = Inputs {
            images,
            layers: self
                .members
                .as_ref()
                .map_or(LayerSource::None, LayerSource::Members),
            plane,
            reference: self.reference(),
            holdout,
            catalog: self.images.as_ref(),
            shear: self.shear.as_ref(),
        };
        Ok(inputs)
    }
}

/// Arcs from a DS9 region file in the frame of `reference`, pixels at `pixel_arcsec`; systems
/// without a redshift in their labels take the one of the same system in `images`.
fn region_arcs(
    file: InputText<'_>,
    reference: Option<SkyReference>,
    pixel_arcsec: f64,
    images: Option<&ImageCatalog>,
) -> Result<RegionArcs, ArcsError> {
    let catalog_z = |id: &str| {
        let systems = images.into_iter().flat_map(|c| c.systems.iter());
        systems.filter(|s| s.id == id).find_map(|s| s.z)
    };
    arcs_from_regions(file.text, file.name, reference, pixel_arcsec, &catalog_z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Cosmology;

    /// Two systems at RA 150, Dec 2 (system 2 has no redshift in the catalogue).
    const IMAGES: &str = "#REFERENCE 3 150.0 2.0\n\
        1.1 10.0 5.0 0.5 0.5 0 2.5 25\n\
        1.2 -8.0 3.0 0.5 0.5 0 2.5 25\n\
        2.1 4.0 -9.0 0.5 0.5 0 0 25\n\
        2.2 -4.0 9.0 0.5 0.5 0 0 25\n";
    /// Arc 1 without a redshift in its label, 2 with one; positions in fk5 near RA 150, Dec 2.
    const REGIONS: &str = "fk5\n\
        circle(149.99722,2.00139,0.5\") # text={1.1}\n\
        circle(150.00222,2.00083,0.5\") # text={1.2}\n\
        circle(149.99889,1.99750,0.5\") # text={2.1 z=3.0}\n\
        circle(150.00111,2.00250,0.5\") # text={2.2 z=3.0}\n";

    fn files<'a>(images: bool, arcs: bool) -> InputTexts<'a> {
        InputTexts {
            images: images.then_some(InputText {
                name: "images.cat",
                text: IMAGES,
            }),
            members: None,
            shear: None,
            potfile_reference: None,
            unknown_source_z: None,
            arcs: arcs.then_some(InputText {
                name: "arcs.reg",
                text: REGIONS,
            }),
        }
    }

    fn plane() -> LensPlane {
        LensPlane::new(Cosmology::new(70.0, 0.3).unwrap(), 0.3).unwrap()
    }

    #[test]
    fn region_arcs_take_the_catalogue_frame_and_redshifts() {
        let data = Dataset::read(&files(true, true), 0.1).unwrap();
        let arcs = data.arcs.as_ref().unwrap();
        let z: Vec<_> = arcs.systems.iter().map(|s| (s.id.as_str(), s.z)).collect();
        assert_eq!(z, [("1", Some(2.5)), ("2", Some(3.0))]);
        assert_eq!(data.arcs_reference, None);
        let sky = data.reference().unwrap();
        assert_eq!((sky.ra_deg, sky.dec_deg), (150.0, 2.0));
        // Alone, the regions have no redshift for system 1 and their own frame.
        let alone = Dataset::read(&files(false, true), 0.1).unwrap();
        assert_eq!(alone.arcs.as_ref().unwrap().systems[0].z, None);
        assert!(alone.arcs_reference.is_some());
        assert!(
            alone.warnings[0].contains("mean position"),
            "{:?}",
            alone.warnings
        );
    }

    #[test]
    fn the_mode_chooses_between_catalogue_and_arcs() {
        let both = Dataset::read(&files(true, true), 0.1).unwrap();
        let mut config = ReconstructConfig::default();
        config.constraints.mode = ConstraintMode::Point;
        let note = both.unfitted_arcs(config.constraints.mode);
        let inputs = both.inputs(plane(), &[], &mut config).unwrap();
        assert!(matches!(inputs.images, ConstraintSource::Catalog(_)));
        assert!(note
            .unwrap()
            .contains("arcs.reg: its arc pixels are not fitted"));
        config.constraints.mode = ConstraintMode::Arcs;
        let note = both.unfitted_arcs(config.constraints.mode);
        let inputs = both.inputs(plane(), &[], &mut config).unwrap();
        assert!(matches!(inputs.images, ConstraintSource::Arcs(_)));
        assert_eq!(note, None);
        // Arcs alone are fitted as arcs whatever the mode.
        let arcs = Dataset::read(&files(false, true), 0.1).unwrap();
        config.constraints.mode = ConstraintMode::Ellipse;
        assert_eq!(arcs.unfitted_arcs(config.constraints.mode), None);
        let inputs = arcs.inputs(plane(), &[], &mut config).unwrap();
        assert!(matches!(inputs.images, ConstraintSource::Arcs(_)));
        assert_eq!(config.constraints.mode, ConstraintMode::Arcs);
        let none = Dataset::read(&InputTexts::default(), 0.1).unwrap();
        let err = none.inputs(plane(), &[], &mut config).err().unwrap();
        assert!(matches!(err, DatasetError::NoConstraints));
    }
}

//! Parsers for Lenstool multiple-image and member (potfile) catalogues ([method §7]),
//! as people have them: any whitespace (tabs, runs of spaces, trailing spaces, CRLF), `#`
//! comment lines anywhere (also indented), an optional `#REFERENCE` header before the rows
//! (see [`super::frame`]), and no header meaning absolute degrees.
//!
//! [method §7]: crate::method#7-file-formats

use std::collections::HashMap;

use glam::DVec2;

use super::frame::{self, Coords};
use super::rows::{
    read_table, warn_extra_columns, warn_repeated_id, Fields, Row, Shape, Table, ALL_COLUMNS,
};
use super::units::{check_field, RowPosition};
use super::{
    CatalogError, CatalogKind, CatalogWarning, Image, ImageCatalog, ImageSystem, Member,
    MemberCatalog,
};
use crate::sky::SkyReference;

/// Images of one source agree in redshift when `(z_max - z_min) / (1 + z_min)` is at most this.
/// 1e-3 is a velocity difference of 300 km/s: the spread of redshifts measured from different
/// lines or spectra of one galaxy (e.g. 1.1781 and 1.1783 for system 32 of MACS J1931).
pub const Z_AGREEMENT_TOL: f64 = 1e-3;

/// A member magnitude this far from zero or beyond (99, -99, 99.99, 999, ...) is a
/// catalogue's "no measurement" value, not a magnitude: the member is skipped with a warning.
/// Real apparent magnitudes of cluster members lie between about 10 and 35.
pub const MAG_NO_MEASUREMENT: f64 = 90.0;

const IMAGE_LAYOUT: &str = "id x y a b theta z [mag]";
const MEMBER_LAYOUT: &str = "id x y a b theta mag [lum]";

/// The system an image id names, as Lenstool groups images into families: all but the id's
/// last character (`4b`: `4`; `A3c`: `A3`; `12.6c`: `12.6`, so `12.6c` and `12.5c` are two
/// sources, two knots of one galaxy as Lenstool fits them), without a `.` that would end it
/// (`4.2`: `4`). An id whose text after its last `.` is a number names the text before that
/// `.` (`4.12`: `4`, `14c.1`: `14c`), so that a tenth image stays in its system where Lenstool
/// would start another. `None` when that leaves nothing, or for an id ending in `.`.
pub fn system_of_image(id: &str) -> Option<&str> {
    system_and_rule(id).map(|(system, _)| system)
}

/// The galaxy a system is a source of: the text of its id before the first `.` (systems
/// `2.1` and `2.2`, the knots of images `2.1a` and `2.2a`, are two sources of galaxy `2`), or
/// the whole id. Knots of one galaxy lie a fraction of an arcsec apart behind the lens, so one
/// predicts the other: cross-validation holds them out together.
pub fn galaxy_of_system(system: &str) -> &str {
    match system.split_once('.') {
        Some((galaxy, _)) if !galaxy.is_empty() => galaxy,
        _ => system,
    }
}

/// For each of the system ids `ids`, the index of its galaxy ([`galaxy_of_system`]) among
/// the galaxies in the order of their first system, and how many galaxies there are. Without
/// knots, `0, 1, 2, ...`: one galaxy per system.
pub(crate) fn galaxy_indices(ids: &[String]) -> (Vec<usize>, usize) {
    let mut galaxies: Vec<&str> = Vec::new();
    let indices = ids
        .iter()
        .map(|id| {
            let g = galaxy_of_system(id);
            galaxies.iter().position(|&x| x == g).unwrap_or_else(|| {
                galaxies.push(g);
                galaxies.len() - 1
            })
        })
        .collect();
    (indices, galaxies.len())
}

/// [`system_of_image`], and whether the system is the id but its last character (not the text
/// before a `.` and a number).
pub(super) fn system_and_rule(id: &str) -> Option<(&str, bool)> {
    if id.ends_with('.') {
        return None;
    }
    if let Some((system, image)) = id.rsplit_once('.') {
        if image.bytes().all(|b| b.is_ascii_digit()) {
            return (!system.is_empty()).then_some((system, false));
        }
    }
    let (last, _) = id.char_indices().last()?;
    let system = id[..last].strip_suffix('.').unwrap_or(&id[..last]);
    (!system.is_empty()).then_some((system, true))
}

/// Parses a Lenstool multiple-image catalogue: rows `id x y a b theta z [mag]`.
///
/// Positions end in the arcsec frame (+x West, +y North) of `reference` when given; otherwise
/// of the header's `#REFERENCE` position; otherwise (absolute degrees without one) of the mean
/// image position. With `RA0, Dec0` the frame origin, `x = -(RA - RA0) cos(Dec0) 3600` and
/// `y = (Dec - Dec0) 3600` arcsec; relative catalogues in another frame are re-projected
/// through (RA, Dec). `a`, `b` are arcsec (>= 0), `theta` degrees, `mag` 0 when missing.
///
/// Ids are grouped as Lenstool groups them ([`system_of_image`]): `4.2` and `14c.1` are
/// systems `4` and `14c`; an id not of the form `system.number` is its system and one last
/// character (`1a`, `1b`: system `1`; `A3c`: `A3`; `12.6c`: `12.6`; said in a warning).
/// `z = 0` means unknown (`None`); images of one system must agree within
/// [`Z_AGREEMENT_TOL`] (their mean is used, with a warning when they differ or some are
/// unknown). Warnings: single-image systems, extra columns (ignored). Positions that do not
/// fit one lensing field in the header's unit are refused or warned about (`units.rs`).
pub fn parse_image_catalog(
    text: &str,
    source_name: &str,
    reference: Option<SkyReference>,
) -> Result<(ImageCatalog, Vec<CatalogWarning>), CatalogError> {
    let requested = frame::check_requested(reference, source_name)?;
    let table = read_table(text, source_name)?;
    check_kind(&table, source_name, CatalogKind::Images)?;
    let [c0, c1] = table.coords.column_names();
    let names = ["id", c0, c1, "a", "b", "theta", "z", "mag"];
    let mut warnings = Vec::new();
    let mut extra_lines = Vec::new();
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let mut parsed = Vec::with_capacity(table.rows.len());
    let mut positions = Vec::with_capacity(table.rows.len());
    // The first row whose id's system is the id but its last character.
    let mut undotted: Option<(usize, String, String)> = None;
    for row in &table.rows {
        let f = Fields {
            row,
            names: &names,
            source_name,
        };
        f.require(IMAGE_LAYOUT, &mut extra_lines)?;
        let id = row.fields[0];
        let (system, by_last) = f.system_id()?;
        if by_last && undotted.is_none() {
            undotted = Some((row.line, id.to_string(), system.clone()));
        }
        if let Some(&first_line) = seen.get(id) {
            return Err(CatalogError::DuplicateId {
                source_name: source_name.into(),
                id: id.into(),
                first_line,
                line: row.line,
            });
        }
        seen.insert(id, row.line);
        let shape = f.shape(table.coords)?;
        positions.push(RowPosition::of(row, shape.raw));
        let z = f.redshift(6)?;
        let mag = f.optional(7)?;
        let image = Image {
            id: id.into(),
            position: shape.raw,
            a_arcsec: shape.a,
            b_arcsec: shape.b,
            theta_deg: shape.theta,
            mag,
            line: row.line,
        };
        parsed.push((system, z, image));
    }
    warn_extra_columns(&extra_lines, source_name, &mut warnings);
    if let Some((line, id, system)) = undotted {
        warnings.push(CatalogWarning {
            source_name: source_name.into(),
            line,
            message: format!(
                "image ids not of the form system.number are grouped as Lenstool groups them, \
                 by all but their last character: '{id}' is an image of system {system}"
            ),
        });
    }
    check_field(table.coords, &positions, source_name, &mut warnings)?;
    let raw: Vec<DVec2> = parsed.iter().map(|(_, _, im)| im.position).collect();
    let (frame_ref, positions) = table.coords.into_frame(&raw, requested);
    for ((_, _, image), p) in parsed.iter_mut().zip(positions) {
        image.position = p;
    }
    let systems = group_systems(parsed, source_name, &mut warnings)?;
    warn_same_positions(&systems, source_name, &mut warnings);
    let catalog = ImageCatalog {
        source_name: source_name.into(),
        reference: Some(frame_ref),
        systems,
    };
    Ok((catalog, warnings))
}

/// Parses a Lenstool member catalogue (potfile): rows `id x y a b theta mag [lum]`.
///
/// Same `#REFERENCE` rules and frame as [`parse_image_catalog`]; `a`, `b` arcsec (>= 0),
/// `theta` degrees, `mag` required, `lum` 0 when missing (kept as written, not interpreted).
/// Ids are free text; a repeated id is only a warning. A row whose magnitude says "no
/// measurement" (`|mag| >=` [`MAG_NO_MEASUREMENT`], e.g. 99 or -99, or `nan`) is skipped with a
/// warning: Lenstool would give it a meaningless mass (a catalogue with no other row is
/// refused).
pub fn parse_member_catalog(
    text: &str,
    source_name: &str,
    reference: Option<SkyReference>,
) -> Result<(MemberCatalog, Vec<CatalogWarning>), CatalogError> {
    parse_members(text, source_name, reference, false)
}

/// [`parse_member_catalog`] of the catalogue a `.par`'s `potfile` block names (`filein`), in
/// the frame of the `.par`'s `reference`. Published Lenstool models write such catalogues
/// without a `#REFERENCE` header in arcsec relative to that reference (A1835's of Richard et
/// al., LoCuSS: `199 -70.47 -22.85 ...`), and Lenstool reads them so: a catalogue without a
/// header whose positions cannot be (RA, Dec) in degrees is read that way here too, with a
/// warning that says so. Any other catalogue reads as [`parse_member_catalog`] reads it.
pub fn parse_potfile_catalog(
    text: &str,
    source_name: &str,
    reference: Option<SkyReference>,
) -> Result<(MemberCatalog, Vec<CatalogWarning>), CatalogError> {
    parse_members(text, source_name, reference, true)
}

/// The first data row of `table`, read as a headerless catalogue is (degrees), whose position
/// is numbers that cannot be (RA, Dec): its line and the two values as written.
fn row_not_in_degrees<'a>(table: &Table<'a>) -> Option<(usize, &'a str, &'a str)> {
    let degrees = Coords::AbsoluteDeg { header: None };
    table.rows.iter().find_map(|row| {
        let (x, y) = (row.fields.get(1)?, row.fields.get(2)?);
        let raw = DVec2::new(x.parse().ok()?, y.parse().ok()?);
        degrees.check(raw).is_err().then_some((row.line, *x, *y))
    })
}

fn parse_members(
    text: &str,
    source_name: &str,
    reference: Option<SkyReference>,
    headerless_relative: bool,
) -> Result<(MemberCatalog, Vec<CatalogWarning>), CatalogError> {
    let requested = frame::check_requested(reference, source_name)?;
    let mut table = read_table(text, source_name)?;
    check_kind(&table, source_name, CatalogKind::Members)?;
    let mut warnings = Vec::new();
    if let (true, false, Some(r)) = (headerless_relative, table.has_header, requested) {
        if let Some((line, x, y)) = row_not_in_degrees(&table) {
            table.coords = Coords::RelativeArcsec { reference: r };
            warnings.push(CatalogWarning {
                source_name: source_name.into(),
                line,
                message: format!(
                    "no #REFERENCE header, and positions that are not degrees ({x} {y}): read \
                     as arcsec relative to the .par's reference (RA {}, Dec {} deg), as \
                     Lenstool reads them; write '#REFERENCE 3 ra0 dec0' at the top to say so",
                    crate::error::number(r.ra_deg),
                    crate::error::number(r.dec_deg)
                ),
            });
        }
    }
    let [c0, c1] = table.coords.column_names();
    let names = ["id", c0, c1, "a", "b", "theta", "mag", "lum"];
    let mut extra_lines = Vec::new();
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let mut rows_by_id: HashMap<&str, &Row<'_>> = HashMap::new();
    let mut members = Vec::with_capacity(table.rows.len());
    let mut positions = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let f = Fields {
            row,
            names: &names,
            source_name,
        };
        f.require(MEMBER_LAYOUT, &mut extra_lines)?;
        let id = row.fields[0];
        match rows_by_id.insert(id, row) {
            // A row written twice is two galaxies to Lenstool, and here: say so plainly.
            Some(first) if first.fields == row.fields => warnings.push(CatalogWarning {
                source_name: source_name.into(),
                line: row.line,
                message: format!(
                    "member '{id}' repeats line {} exactly: both rows are fitted (as Lenstool \
                     reads them), which doubles that galaxy's mass; delete one if that is not \
                     meant",
                    first.line
                ),
            }),
            _ => warn_repeated_id(
                &mut seen,
                id,
                row.line,
                "member",
                source_name,
                &mut warnings,
            ),
        }
        let shape = f.shape(table.coords)?;
        let mag_text = row.fields[6];
        let mag = if mag_text.eq_ignore_ascii_case("nan") {
            f64::NAN
        } else {
            f.number(6)?
        };
        if mag.is_nan() || mag.abs() >= MAG_NO_MEASUREMENT {
            warnings.push(CatalogWarning {
                source_name: source_name.into(),
                line: row.line,
                message: format!(
                    "member '{id}': magnitude {mag_text} means no measurement: member skipped"
                ),
            });
            continue;
        }
        positions.push(RowPosition::of(row, shape.raw));
        members.push(member_of(row, &shape, mag, f.optional(7)?));
    }
    if members.is_empty() {
        return Err(CatalogError::NoMeasuredMembers {
            source_name: source_name.into(),
            rows: table.rows.len(),
        });
    }
    warn_extra_columns(&extra_lines, source_name, &mut warnings);
    check_field(table.coords, &positions, source_name, &mut warnings)?;
    let raw: Vec<DVec2> = members.iter().map(|m| m.position).collect();
    let (frame_ref, positions) = table.coords.into_frame(&raw, requested);
    for (m, p) in members.iter_mut().zip(positions) {
        m.position = p;
    }
    let commented = commented_members(&table, &names, source_name, frame_ref);
    let catalog = MemberCatalog {
        source_name: source_name.into(),
        reference: Some(frame_ref),
        members,
        commented,
        fitted_bcgs: None,
        par_galaxies: Vec::new(),
        par_source: None,
        free_mass_galaxies: Vec::new(),
        mass_galaxies: Vec::new(),
    };
    Ok((catalog, warnings))
}

/// The 7th column below which a value reads as a source redshift and from which it reads as
/// a magnitude: no lensed source is known beyond z ~ 13, no cluster member is brighter than
/// magnitude 12 (a nearby BCG is 13 - 14), and the drop zone of the app sorts files so.
const REDSHIFT_BELOW: f64 = 12.0;

/// Refuses a catalogue of the other kind, told by its 7th column (given on at least 3 rows):
/// an image catalogue whose median `z` is a magnitude (at least [`REDSHIFT_BELOW`]), or a
/// member catalogue whose every `mag` is a redshift (in `[0, REDSHIFT_BELOW)`; absolute
/// magnitudes are negative, and a `mag` of 99 that means none is left to the reader). A
/// member catalogue read as images would otherwise give systems of one image each, or
/// redshifts that disagree; an image catalogue read as members, halos of absurd mass.
fn check_kind(table: &Table<'_>, source_name: &str, kind: CatalogKind) -> Result<(), CatalogError> {
    let values: Vec<(usize, &str, f64)> = table
        .rows
        .iter()
        .filter_map(|row| {
            let text = *row.fields.get(6)?;
            let v: f64 = text.parse().ok()?;
            let measured = v.is_finite() && v.abs() < MAG_NO_MEASUREMENT;
            measured.then_some((row.line, text, v))
        })
        .collect();
    if values.len() < 3 {
        return Ok(());
    }
    let mut sorted: Vec<f64> = values.iter().map(|v| v.2).collect();
    sorted.sort_by(f64::total_cmp);
    let (low, high) = (sorted[0], sorted[sorted.len() - 1]);
    let other = match kind {
        CatalogKind::Images => sorted[sorted.len() / 2] >= REDSHIFT_BELOW,
        CatalogKind::Members => low >= 0.0 && high < REDSHIFT_BELOW,
    };
    if !other {
        return Ok(());
    }
    // The first row (in the file's order) whose value shows it.
    let shows = |v: &&(usize, &str, f64)| kind == CatalogKind::Members || v.2 >= REDSHIFT_BELOW;
    let Some(&(line, value, _)) = values.iter().find(shows) else {
        return Ok(());
    };
    Err(CatalogError::OtherKind {
        source_name: source_name.into(),
        read_as: kind,
        low,
        high,
        rows: values.len(),
        line,
        value: value.to_string(),
    })
}

/// The member of a row read as `shape`, `mag` and `lum`, at its position as written.
fn member_of(row: &Row<'_>, shape: &Shape, mag: f64, lum: f64) -> Member {
    Member {
        id: row.fields[0].into(),
        position: shape.raw,
        a_arcsec: shape.a,
        b_arcsec: shape.b,
        theta_deg: shape.theta,
        mag,
        lum,
        line: row.line,
    }
}

/// The members of `table`'s commented rows that read in full (a measured magnitude, a valid
/// ellipse and position), in the frame `frame_ref`; the others are ignored, as comments.
fn commented_members(
    table: &Table<'_>,
    names: &[&'static str; ALL_COLUMNS],
    source_name: &str,
    frame_ref: SkyReference,
) -> Vec<Member> {
    let mut out = Vec::new();
    let mut raw = Vec::new();
    for row in &table.commented {
        let f = Fields {
            row,
            names,
            source_name,
        };
        let (Ok(shape), Ok(mag), Ok(lum)) = (f.shape(table.coords), f.number(6), f.optional(7))
        else {
            continue;
        };
        if mag.abs() >= MAG_NO_MEASUREMENT {
            continue;
        }
        raw.push(shape.raw);
        out.push(member_of(row, &shape, mag, lum));
    }
    if !raw.is_empty() {
        let (_, positions) = table.coords.into_frame(&raw, Some(frame_ref));
        for (m, p) in out.iter_mut().zip(positions) {
            m.position = p;
        }
    }
    out
}

/// The images of one system while grouping, with each image's `(line, z)` as written.
struct Group {
    id: String,
    zs: Vec<(usize, Option<f64>)>,
    images: Vec<Image>,
}

/// Groups images by system in order of first appearance and settles each system's redshift.
fn group_systems(
    parsed: Vec<(String, Option<f64>, Image)>,
    source_name: &str,
    warnings: &mut Vec<CatalogWarning>,
) -> Result<Vec<ImageSystem>, CatalogError> {
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut groups: Vec<Group> = Vec::new();
    for (system, z, image) in parsed {
        let k = *index.entry(system.clone()).or_insert_with(|| {
            groups.push(Group {
                id: system,
                zs: Vec::new(),
                images: Vec::new(),
            });
            groups.len() - 1
        });
        groups[k].zs.push((image.line, z));
        groups[k].images.push(image);
    }
    let mut systems = Vec::with_capacity(groups.len());
    for Group { id, zs, images } in groups {
        let z = system_redshift(&id, &zs, source_name, warnings)?;
        if images.len() == 1 {
            warnings.push(CatalogWarning {
                source_name: source_name.into(),
                line: images[0].line,
                message: format!(
                    "system '{id}' has a single image ('{}'): it constrains nothing by itself",
                    images[0].id
                ),
            });
        }
        systems.push(ImageSystem { id, z, images });
    }
    Ok(systems)
}

/// Images closer than this (arcsec) are taken for one image written twice.
const SAME_IMAGE_ARCSEC: f64 = 0.05;

/// At most this many images written twice are named (the scan stops there: a file of many
/// rows at one place costs no more than a few).
const SAME_IMAGE_NAMED: usize = 5;

/// Warns of two rows at one position (within [`SAME_IMAGE_ARCSEC`]): an image has one source,
/// so in two systems it asks the map for two sources at one place, and in one it is counted
/// twice; in two knots of one galaxy ([`galaxy_of_system`]: `14.1c` and `14.2c`) it is two
/// knots blended, which the catalogue means, and the warning says how it is fitted.
/// Catalogues converted by hand or merged from two lists do this (a helper session found it
/// in two public ones). Positions are bucketed on a lattice of that width, so the scan is
/// linear in the rows.
fn warn_same_positions(
    systems: &[ImageSystem],
    source_name: &str,
    warnings: &mut Vec<CatalogWarning>,
) {
    let cell = |p: DVec2| {
        (
            (p.x / SAME_IMAGE_ARCSEC).floor() as i64,
            (p.y / SAME_IMAGE_ARCSEC).floor() as i64,
        )
    };
    let mut seen: HashMap<(i64, i64), Vec<(&ImageSystem, &Image)>> = HashMap::new();
    let mut named = 0;
    for system in systems {
        for image in &system.images {
            let (cx, cy) = cell(image.position);
            let twin = (-1..=1)
                .flat_map(|dx| (-1..=1).map(move |dy| (cx + dx, cy + dy)))
                .filter_map(|k| seen.get(&k))
                .flatten()
                .find(|(_, other)| other.position.distance(image.position) <= SAME_IMAGE_ARCSEC);
            if let Some((other_system, other)) = twin {
                let knots = other_system.id != system.id
                    && galaxy_of_system(&other_system.id) == galaxy_of_system(&system.id);
                let what = match (other_system.id == system.id, knots) {
                    (true, _) => format!(
                        "in system {}: it is counted twice; delete one row if it is the same \
                         image",
                        system.id
                    ),
                    // Two knots of one galaxy blended in one image: the catalogue means it.
                    (false, true) => format!(
                        "as knots {} and {} of one galaxy blended in one image: it is fitted \
                         as an image of each, as Lenstool fits it",
                        other_system.id, system.id
                    ),
                    (false, false) => format!(
                        "in systems {} and {}: an image has one source, so the map is asked \
                         for two at one place; delete one row if it is the same image",
                        other_system.id, system.id
                    ),
                };
                warnings.push(CatalogWarning {
                    source_name: source_name.into(),
                    line: image.line,
                    message: format!(
                        "image '{}' lies where image '{}' (line {}) does, {what}",
                        image.id, other.id, other.line
                    ),
                });
                named += 1;
                if named == SAME_IMAGE_NAMED {
                    return;
                }
                continue;
            }
            seen.entry((cx, cy)).or_default().push((system, image));
        }
    }
}

/// Whether two images' redshifts can be one source's: `|a - b| <= Z_AGREEMENT_TOL (1 + min)`.
pub fn redshifts_agree(a: f64, b: f64) -> bool {
    (a - b).abs() <= Z_AGREEMENT_TOL * (1.0 + a.min(b))
}

/// The redshift of one system from its images' `(line, z)`: `None` when all are unknown,
/// otherwise the mean of the known ones, which must agree within [`Z_AGREEMENT_TOL`].
fn system_redshift(
    id: &str,
    zs: &[(usize, Option<f64>)],
    source_name: &str,
    warnings: &mut Vec<CatalogWarning>,
) -> Result<Option<f64>, CatalogError> {
    let known: Vec<(usize, f64)> = zs.iter().filter_map(|&(l, z)| z.map(|z| (l, z))).collect();
    let by_z = |a: &&(usize, f64), b: &&(usize, f64)| a.1.total_cmp(&b.1);
    let (Some(&lo), Some(&hi)) = (known.iter().min_by(by_z), known.iter().rev().max_by(by_z))
    else {
        return Ok(None);
    };
    let mut warn = |line: usize, message: String| {
        warnings.push(CatalogWarning {
            source_name: source_name.into(),
            line,
            message,
        });
    };
    let (first, second) = if lo.0 < hi.0 { (lo, hi) } else { (hi, lo) };
    if !redshifts_agree(lo.1, hi.1) {
        return Err(CatalogError::InconsistentRedshift {
            source_name: source_name.into(),
            system: id.into(),
            line_a: first.0,
            z_a: first.1,
            line_b: second.0,
            z_b: second.1,
            tolerance: Z_AGREEMENT_TOL,
        });
    }
    let z = known.iter().map(|k| k.1).sum::<f64>() / known.len() as f64;
    if hi.1 > lo.1 {
        warn(
            first.0,
            format!(
                "system '{id}': line {} gives z = {} and line {} gives z = {} (within the \
                 tolerance); using their mean z = {}",
                first.0,
                first.1,
                second.0,
                second.1,
                crate::error::number((z * 1e6).round() / 1e6)
            ),
        );
    }
    if let Some(&(unknown_line, _)) = zs.iter().find(|(_, z)| z.is_none()) {
        warn(
            unknown_line,
            format!(
                "system '{id}': z = 0 (unknown) here but line {} gives z = {}; using z = {z} \
                 for the whole system",
                known[0].0, known[0].1
            ),
        );
    }
    Ok(Some(z))
}

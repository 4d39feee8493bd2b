//! The files of a session: kept as texts (a project stores them) and checked when loaded, so a
//! bad file is refused with its line and reason and never replaces a good one.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::arcs::{is_region_file, ArcCatalog};
use crate::catalog::{
    parse_arclet_catalog_with, parse_image_catalog, parse_member_catalog, parse_potfile_catalog,
    ArcletUnknownZ, CatalogError, ImageCatalog,
};
use crate::cosmology::LensPlane;
use crate::fits::read_image;
use crate::lenstool_par::{
    parse_par_with, LenstoolPar, ParOptions, UnknownSourceZ, LENSTOOL_DEFAULT_Z_SOURCE,
};
use crate::map::Map;
use crate::model::ModelFile;
use crate::profiles::Lens;
use crate::reconstruct::{arclet_unknown_z, Dataset, InputText, InputTexts};
use crate::sky::SkyReference;

use super::AppError;

/// What a loaded file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DataRole {
    /// Lenstool multiple-image catalogue (`id x y a b theta z mag`).
    Images,
    /// Lenstool member catalogue (`id x y a b theta mag lum`).
    Members,
    /// Arc pixels, JSON or DS9 regions (see [`crate::arcs::parse_arcs`]).
    Arcs,
    /// Parametric model file (forward mode).
    Model,
    /// Lenstool arclet catalogue (`id x y a b theta z`, weak lensing).
    Shear,
}

impl DataRole {
    /// Parses `images`, `members`, `arcs`, `shear` or `model`.
    pub fn parse(s: &str) -> Result<Self, AppError> {
        match s {
            "images" => Ok(Self::Images),
            "members" => Ok(Self::Members),
            "arcs" => Ok(Self::Arcs),
            "model" => Ok(Self::Model),
            "shear" => Ok(Self::Shear),
            other => Err(AppError::File(format!(
                "unknown file role '{other}' (images, members, arcs, shear or model)"
            ))),
        }
    }
}

/// A file as loaded: its name and text.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NamedText {
    pub name: String,
    pub text: String,
}

/// Largest deflection FITS file a project keeps (bytes; a 2048 x 2048 float32 map and its
/// header fit). A larger map is used, but must be loaded again after the page is reloaded.
pub const MAX_STORED_FITS_BYTES: usize = 20 * 1024 * 1024;

/// `values` as a project file stores many numbers: little-endian `f32`, in base64.
pub(super) fn f32_base64(values: impl Iterator<Item = f64>) -> String {
    use base64::Engine as _;
    let bytes: Vec<u8> = values.flat_map(|v| (v as f32).to_le_bytes()).collect();
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// The values of decoded [`f32_base64`] bytes (a last incomplete value is left out).
pub(super) fn f32_values(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(4)
        .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
        .collect()
}

/// A deflection map (HFF convention, arcsec at `D_ls/D_s = 1`) read from FITS.
#[derive(Debug, Clone)]
pub struct NamedMap {
    pub name: String,
    pub map: Map,
    pub reference: Option<SkyReference>,
    /// The file as read, kept for the project file (`None` above [`MAX_STORED_FITS_BYTES`]).
    pub fits: Option<Vec<u8>>,
}

/// What loading a file found, for the line next to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoadReport {
    pub role: String,
    pub name: String,
    /// E.g. "19 systems, 50 images".
    pub summary: String,
    pub warnings: Vec<String>,
}

/// Every file of a session.
#[derive(Debug, Clone, Default)]
pub struct LoadedData {
    pub images: Option<NamedText>,
    pub members: Option<NamedText>,
    pub arcs: Option<NamedText>,
    pub model: Option<NamedText>,
    /// Arclet catalogue (weak lensing).
    pub shear: Option<NamedText>,
    /// Deflection maps along x and y (look-up mode).
    pub deflection: [Option<NamedMap>; 2],
}

/// A loaded model ready to evaluate (see [`LoadedData::model_lens`]).
#[derive(Debug)]
pub struct ModelLens {
    pub lens: Lens,
    pub plane: LensPlane,
    pub reference: Option<SkyReference>,
}

impl LoadedData {
    /// The loaded model file when it is a Lenstool `.par`, read with `par_options`; `None`
    /// without one (or with a JSON model).
    pub fn model_par(&self, par_options: &ParOptions) -> Result<Option<LenstoolPar>, AppError> {
        match &self.model {
            Some(f) if is_lenstool_par(&f.name, &f.text) => {
                parse_par_with(&f.text, &f.name, par_options)
                    .map(Some)
                    .map_err(|e| AppError::File(e.to_string()))
            }
            _ => Ok(None),
        }
    }

    /// The loaded model file's lens redshift (a `.par`'s or a JSON model's); `None` without
    /// one or when it does not read.
    pub fn model_z_lens(&self, par_options: &ParOptions) -> Option<f64> {
        let file = self.model.as_ref()?;
        if is_lenstool_par(&file.name, &file.text) {
            return Some(self.model_par(par_options).ok()??.z_lens);
        }
        let model = ModelFile::from_json_str(&file.text, &file.name).ok()?;
        Some(model.z_lens)
    }

    /// The member catalogue the loaded `.par` needs and that is not loaded: its `potfile`'s
    /// `filein` as written (e.g. `../model/a1835/galsorted.cat`); `None` when nothing is
    /// missing (no `.par`, no potfile, or a member catalogue loaded).
    pub fn missing_potfile(&self, par_options: &ParOptions) -> Option<String> {
        if self.members.is_some() {
            return None;
        }
        let par = self.model_par(par_options).ok().flatten()?;
        par.potfiles.first().map(|p| p.filein.clone())
    }

    /// Whether the model file is a Lenstool `.par` that reads.
    pub fn model_is_par(&self, par_options: &ParOptions) -> bool {
        matches!(self.model_par(par_options), Ok(Some(_)))
    }

    /// The frame of a member catalogue without a header in arcsec: the loaded `.par`'s
    /// reference when it has a potfile ([`LenstoolPar::potfile_reference`]).
    fn potfile_reference(&self, par_options: &ParOptions) -> Option<SkyReference> {
        let par = self.model_par(par_options).ok().flatten()?;
        par.potfile_reference()
    }

    /// What the loaded `.par` says of sources without a redshift
    /// ([`LenstoolPar::unknown_source_z`]); `None` without a `.par`.
    fn unknown_source_z(&self, par_options: &ParOptions) -> Option<Result<UnknownSourceZ, String>> {
        let par = self.model_par(par_options).ok().flatten()?;
        Some(par.unknown_source_z())
    }

    /// What replacing the model file by `name`, whose potfile frame is `after` (none for a
    /// JSON model or a `.par` without a potfile), does to a loaded member catalogue that reads
    /// only in the loaded `.par`'s frame (headerless arcsec, as its potfile): with no frame a
    /// reconstruction refuses it, with another `.par`'s its members move. `None` when the
    /// members do not depend on the model file.
    fn members_frame_note(
        &self,
        name: &str,
        after: Option<SkyReference>,
        par_options: &ParOptions,
    ) -> Option<String> {
        let members = self.members.as_ref()?;
        let before = self.potfile_reference(par_options)?;
        if parse_member_catalog(&members.text, &members.name, None).is_ok() {
            return None;
        }
        let (m, old) = (&members.name, &self.model.as_ref()?.name);
        match after {
            Some(r) if r == before => None,
            Some(_) => Some(format!(
                "{m} was read as {old}'s potfile, in arcsec from its reference; it is read now \
                 from {name}'s, which is another: its members move with it"
            )),
            None => Some(format!(
                "{m} was read as {old}'s potfile, in arcsec from its reference, and {name} \
                 gives none: a reconstruction now refuses {m}. Load {old} again, or a member catalogue \
                 with a '#REFERENCE 3 ra0 dec0' header"
            )),
        }
    }
}

/// Whether a model file's text is a Lenstool parameter file rather than a JSON model file: a
/// `.json` name or JSON's first character (`{`, or `[` / `"` of a file that is JSON but not a
/// model, which must be told so, not read as a `.par` without its blocks) says JSON.
fn is_lenstool_par(name: &str, text: &str) -> bool {
    let json_name = name.to_ascii_lowercase().ends_with(".json");
    let json_start = text.trim_start().starts_with(['{', '[', '"']);
    !(json_name || json_start)
}

/// A member catalogue refused as `error`: [`AppError::WantsPar`], with a hint, when the
/// catalogue would read as a `.par`'s potfile (headerless arcsec from the `.par`'s reference):
/// then the `.par` must be loaded first. Otherwise the catalogue's own error.
fn potfile_hint(error: CatalogError, text: &str, name: &str) -> AppError {
    let anywhere = SkyReference {
        ra_deg: 0.0,
        dec_deg: 0.0,
    };
    let message = error.to_string();
    match parse_potfile_catalog(text, name, Some(anywhere)) {
        Ok((_, w)) if !w.is_empty() => AppError::WantsPar(format!(
            "{message}. If it is the potfile of a Lenstool .par (arcsec from the .par's \
             reference, as Lenstool reads it), load that .par as the model file first: the \
             app then reads this catalogue again"
        )),
        _ => AppError::File(message),
    }
}

/// An arclet catalogue refused as `error`: [`AppError::WantsPar`] when no `.par` is loaded
/// and the catalogue would read with one (rows without a redshift, which Lenstool gives its
/// `.par`'s z_source), so that the app reads it again when a `.par` loads. Otherwise the
/// catalogue's own error.
fn arclets_hint(error: CatalogError, no_par: bool, text: &str, name: &str) -> AppError {
    let take = ArcletUnknownZ::Take {
        z: LENSTOOL_DEFAULT_Z_SOURCE,
        origin: "",
    };
    let message = error.to_string();
    if no_par && parse_arclet_catalog_with(text, name, None, take).is_ok() {
        AppError::WantsPar(format!(
            "{message}. The app reads this catalogue again when a .par is loaded as the model \
             file"
        ))
    } else {
        AppError::File(message)
    }
}

/// Arc pixel side assumed when it cannot be measured (milliarcsec).
pub const DEFAULT_ARC_PIXEL_MAS: u32 = 200;
/// Pixels of one image whose nearest neighbours [`DataViews::arc_pixel_mas`] measures.
const ARC_PIXEL_SAMPLES: usize = 64;
/// Largest arc pixel side drawn (milliarcsec; sparser "pixels" are points, not pixels).
const MAX_ARC_PIXEL_MAS: f64 = 5000.0;

/// The arc pixels of one system.
#[derive(Debug, Clone, PartialEq)]
pub struct ArcPixels {
    pub id: String,
    pub pixels_arcsec: Vec<DVec2>,
}

/// What the views draw of the loaded data (arcsec): catalogue images, the arc pixels of each
/// system with their pixel side, and members.
#[derive(Debug, Clone, PartialEq)]
pub struct DataMarks {
    /// Catalogue image positions (no arc pixels).
    pub observed: Vec<DVec2>,
    pub arcs: Vec<ArcPixels>,
    /// Side of one arc pixel (milliarcsec), see [`DataViews::arc_pixel_mas`].
    pub arc_pixel_mas: u32,
    pub members: Vec<DVec2>,
}

impl Default for DataMarks {
    /// Nothing to draw.
    fn default() -> Self {
        Self {
            observed: Vec::new(),
            arcs: Vec::new(),
            arc_pixel_mas: DEFAULT_ARC_PIXEL_MAS,
            members: Vec::new(),
        }
    }
}

/// The warning for a FITS file of `len` bytes that the project file does not keep.
fn too_large_to_keep(name: &str, len: usize) -> String {
    const MIB: f64 = 1024.0 * 1024.0;
    format!(
        "{name}: {:.1} MB is more than the {:.0} MB a project keeps; it is used now, but load it again after reloading the page",
        len as f64 / MIB,
        MAX_STORED_FITS_BYTES as f64 / MIB
    )
}

/// What the app draws of a session's data (its catalogues read into one frame by
/// [`Dataset::read`], as `wslap reconstruct` reads them).
pub trait DataViews {
    /// Observed image positions (catalogue positions, or every arc pixel), arcsec.
    fn observed_arcsec(&self) -> Vec<DVec2>;
    /// What the views draw of this data.
    fn marks(&self) -> DataMarks;
    /// The arc pixels of each system (all its images together), in file order.
    fn arc_systems(&self) -> Vec<ArcPixels>;
    /// Side of one arc pixel in milliarcsec (see the implementation for [`Dataset`]).
    fn arc_pixel_mas(&self) -> u32;
    /// Member positions, arcsec.
    fn members_arcsec(&self) -> Vec<DVec2>;
}

impl DataViews for Dataset {
    fn observed_arcsec(&self) -> Vec<DVec2> {
        if let Some(c) = &self.images {
            return c.images().map(|i| i.position).collect();
        }
        let arcs = self.arcs.iter().flat_map(|a| a.systems.iter());
        arcs.flat_map(|s| s.images.iter().flatten().copied())
            .collect()
    }

    fn marks(&self) -> DataMarks {
        let catalog = self.images.iter().flat_map(|c| c.images());
        DataMarks {
            observed: catalog.map(|i| i.position).collect(),
            arcs: self.arc_systems(),
            arc_pixel_mas: self.arc_pixel_mas(),
            members: self.members_arcsec(),
        }
    }

    fn arc_systems(&self) -> Vec<ArcPixels> {
        let systems = self.arcs.iter().flat_map(|a| a.systems.iter());
        systems
            .map(|s| ArcPixels {
                id: s.id.clone(),
                pixels_arcsec: s.images.iter().flatten().copied().collect(),
            })
            .collect()
    }

    /// The median distance from a pixel to its nearest
    /// neighbour in the same image (`DEFAULT_ARC_PIXEL_MAS` if no image has two pixels).
    /// Of an image with more than `ARC_PIXEL_SAMPLES` pixels only that many, evenly spaced
    /// in file order, are measured (against all of its pixels), so the cost grows linearly with
    /// the pixel count, not with its square (each view of the data asks again, and arcs of
    /// ten thousands of pixels are common). Arc pixels lie on a regular grid, where the sample's median is the same.
    fn arc_pixel_mas(&self) -> u32 {
        let mut nearest: Vec<f64> = Vec::new();
        let images = self
            .arcs
            .iter()
            .flat_map(|a| &a.systems)
            .flat_map(|s| &s.images);
        for image in images {
            let samples = image.len().min(ARC_PIXEL_SAMPLES);
            for k in (0..samples).map(|i| i * image.len() / samples) {
                let p = image[k];
                let others = image.iter().enumerate().filter(|&(j, _)| j != k);
                let d = others
                    .map(|(_, q)| p.distance(*q))
                    .fold(f64::INFINITY, f64::min);
                if d.is_finite() && d > 0.0 {
                    nearest.push(d);
                }
            }
        }
        if nearest.is_empty() {
            return DEFAULT_ARC_PIXEL_MAS;
        }
        nearest.sort_by(f64::total_cmp);
        let median_mas = nearest[nearest.len() / 2] * 1000.0;
        median_mas.round().clamp(1.0, MAX_ARC_PIXEL_MAS) as u32
    }

    fn members_arcsec(&self) -> Vec<DVec2> {
        let members = self.members.iter().flat_map(|m| m.members.iter());
        members.map(|m| m.position).collect()
    }
}

fn describe_images(c: &ImageCatalog) -> String {
    format!("{} systems, {} images", c.systems.len(), c.image_count())
}

/// An arcs file read on its own (DS9 regions in their own frame), to check it.
fn arcs_alone(name: &str, text: &str, pixel_arcsec: f64) -> Result<ArcCatalog, AppError> {
    let files = InputTexts {
        arcs: Some(InputText { name, text }),
        ..InputTexts::default()
    };
    let data = Dataset::read(&files, pixel_arcsec).map_err(|e| AppError::File(e.to_string()))?;
    data.arcs
        .ok_or_else(|| AppError::File(format!("{name}: no arcs were read")))
}

impl LoadedData {
    /// The loaded model file as a lens with its plane and sky reference: a JSON model file, or
    /// a Lenstool parametric model (`.par`, e.g. a published `bestopt.par`) whose potfile
    /// members are the loaded member catalogue's, read with `par_options`. `None` without a
    /// model file; an error names what is missing (a `.par` with a potfile and no member
    /// catalogue).
    pub fn model_lens(&self, par_options: &ParOptions) -> Result<Option<ModelLens>, AppError> {
        let Some(file) = &self.model else {
            return Ok(None);
        };
        let err = |e: &dyn std::fmt::Display| AppError::File(e.to_string());
        if !is_lenstool_par(&file.name, &file.text) {
            let model = ModelFile::from_json_str(&file.text, &file.name).map_err(|e| err(&e))?;
            return Ok(Some(ModelLens {
                lens: model.build_lens().map_err(|e| err(&e))?,
                plane: model.lens_plane().map_err(|e| err(&e))?,
                reference: model.reference,
            }));
        }
        let par = parse_par_with(&file.text, &file.name, par_options).map_err(|e| err(&e))?;
        let mut texts = Vec::new();
        if let Some(potfile) = par.potfiles.first() {
            let members = self.members.as_ref().ok_or_else(|| {
                AppError::Missing(format!(
                    "{}: its potfile ({}) needs the member catalogue: load it as the member \
                     catalogue",
                    file.name, potfile.filein
                ))
            })?;
            texts.push((members.name.as_str(), members.text.as_str()));
        }
        let (model, _) = par.build_from_texts(&texts).map_err(|e| err(&e))?;
        Ok(Some(ModelLens {
            lens: model.lens,
            plane: model.plane,
            reference: model.reference,
        }))
    }

    /// Checks `text` as a file of `role` and keeps it; an error leaves everything as it was.
    /// `arc_pixel_arcsec` is the pixel of arcs drawn as DS9 regions; a Lenstool `.par` model is
    /// read with `par_options` (its warnings are the report's).
    pub fn load_text(
        &mut self,
        role: DataRole,
        name: &str,
        text: &str,
        arc_pixel_arcsec: f64,
        par_options: &ParOptions,
    ) -> Result<LoadReport, AppError> {
        let text = &*crate::limits::with_line_feeds(text);
        let file = |e: &dyn std::fmt::Display| AppError::File(e.to_string());
        let (summary, warnings) = match role {
            DataRole::Images => {
                let (c, w) = parse_image_catalog(text, name, None).map_err(|e| file(&e))?;
                (
                    describe_images(&c),
                    w.iter().map(|w| w.to_string()).collect(),
                )
            }
            DataRole::Members => {
                let read = match self.potfile_reference(par_options) {
                    Some(r) => parse_potfile_catalog(text, name, Some(r)),
                    None => parse_member_catalog(text, name, None),
                };
                let (c, w) = read.map_err(|e| potfile_hint(e, text, name))?;
                let n = c.members.len();
                (
                    format!("{n} members"),
                    w.iter().map(|w| w.to_string()).collect(),
                )
            }
            DataRole::Shear => {
                let answer = self.unknown_source_z(par_options);
                let rule = arclet_unknown_z(answer.as_ref());
                let (c, w) = parse_arclet_catalog_with(text, name, None, rule)
                    .map_err(|e| arclets_hint(e, answer.is_none(), text, name))?;
                let n = c.arclets.len();
                (
                    format!("{n} arclets (weak lensing)"),
                    w.iter().map(|w| w.to_string()).collect(),
                )
            }
            DataRole::Arcs => {
                let regions = is_region_file(text);
                let a = arcs_alone(name, text, arc_pixel_arcsec)?;
                let pixels: usize = a.systems.iter().flat_map(|s| &s.images).map(Vec::len).sum();
                let n = a.systems.len();
                let from = if regions {
                    format!(" (DS9 regions at {arc_pixel_arcsec} arcsec)")
                } else {
                    String::new()
                };
                (
                    format!("{n} systems, {pixels} arc pixels{from}"),
                    Vec::new(),
                )
            }
            DataRole::Model if is_lenstool_par(name, text) => {
                let par = parse_par_with(text, name, par_options).map_err(|e| file(&e))?;
                let members = match par.potfiles.len() {
                    0 => String::new(),
                    1 => ", and its potfile's members from the member catalogue".to_string(),
                    n => {
                        return Err(AppError::File(format!(
                            "{name}: {n} potfile blocks; the app takes one member catalogue"
                        )))
                    }
                };
                let mut warnings: Vec<String> =
                    par.warnings.iter().map(|w| w.to_string()).collect();
                warnings.extend(self.members_frame_note(
                    name,
                    par.potfile_reference(),
                    par_options,
                ));
                (
                    format!(
                        "Lenstool model: {} potential{}{members}, at z_lens = {}",
                        par.potentials.len(),
                        if par.potentials.len() == 1 { "" } else { "s" },
                        par.z_lens
                    ),
                    warnings,
                )
            }
            DataRole::Model => {
                let m = ModelFile::from_json_str(text, name).map_err(|e| file(&e))?;
                let n = m.components.len();
                (
                    format!("{n} components at z_lens = {}", m.z_lens),
                    self.members_frame_note(name, None, par_options)
                        .into_iter()
                        .collect(),
                )
            }
        };
        *self.slot(role) = Some(NamedText {
            name: name.to_string(),
            text: text.to_string(),
        });
        Ok(LoadReport {
            role: format!("{role:?}").to_lowercase(),
            name: name.to_string(),
            summary,
            warnings,
        })
    }

    /// Whether loaded DS9 region arcs can be sampled at `pixel_arcsec` (within the arcs' pixel
    /// limit); `Ok` when the arcs are not a region file.
    pub fn check_region_arcs(&self, pixel_arcsec: f64) -> Result<(), AppError> {
        match &self.arcs {
            Some(f) if is_region_file(&f.text) => {
                arcs_alone(&f.name, &f.text, pixel_arcsec).map(|_| ())
            }
            _ => Ok(()),
        }
    }

    /// Loads the kept file of `role` again (see [`Self::load_text`]); `None` when there is
    /// none.
    pub fn reload(
        &mut self,
        role: DataRole,
        arc_pixel_arcsec: f64,
        par_options: &ParOptions,
    ) -> Result<Option<LoadReport>, AppError> {
        let Some(NamedText { name, text }) = self.slot(role).clone() else {
            return Ok(None);
        };
        self.load_text(role, &name, &text, arc_pixel_arcsec, par_options)
            .map(Some)
    }

    /// Makes the commented-out rows on `lines` (1-based) of the loaded member catalogue members
    /// (e.g. the BCGs a result's verdict names, one per core): the lines' leading `#`s go and
    /// the catalogue is checked and kept as [`Self::load_text`] does. Each line must be
    /// commented out and read as one more member once it is not; on an error the catalogue
    /// stays as it was, every line included.
    pub fn uncomment_members(
        &mut self,
        lines: &[usize],
        arc_pixel_arcsec: f64,
        par_options: &ParOptions,
    ) -> Result<LoadReport, AppError> {
        let Some(NamedText { name, text }) = self.members.clone() else {
            return Err(AppError::Missing(
                "load a member catalogue first".to_string(),
            ));
        };
        if lines.is_empty() {
            return Err(AppError::File(format!("{name}: no line to uncomment")));
        }
        let count = |t: &str| parse_member_catalog(t, &name, None).map(|(c, _)| c.members.len());
        let mut edited = text.clone();
        let mut members = count(&text).map_err(|e| AppError::File(e.to_string()))?;
        for &line in lines {
            let rows: Vec<&str> = edited.split('\n').collect();
            let at = line.checked_sub(1).and_then(|i| rows.get(i).copied());
            let Some(old) = at.filter(|l| l.trim_start().starts_with('#')) else {
                return Err(AppError::File(format!(
                    "{name}: line {line} is not a commented-out row"
                )));
            };
            // Every leading `#` goes, as the catalogue reader strips them (`##7 ...` reads
            // as 7).
            let body = old.trim_start();
            let new = format!(
                "{}{}",
                &old[..old.len() - body.len()],
                body.trim_start_matches('#')
            );
            let next = rows
                .iter()
                .enumerate()
                .map(|(i, l)| if i + 1 == line { new.as_str() } else { l })
                .collect::<Vec<&str>>()
                .join("\n");
            members += 1;
            if count(&next).ok() != Some(members) {
                return Err(AppError::File(format!(
                    "{name}: line {line} does not read as a member without its '#': {}",
                    old.trim()
                )));
            }
            edited = next;
        }
        let mut report = self.load_text(
            DataRole::Members,
            &name,
            &edited,
            arc_pixel_arcsec,
            par_options,
        )?;
        let which = crate::error::and_list(lines.iter().map(|l| l.to_string()));
        let s = if lines.len() == 1 { "" } else { "s" };
        report.summary = format!("{} (line{s} {which} uncommented)", report.summary);
        Ok(report)
    }

    /// Forgets the file of `role`.
    pub fn clear(&mut self, role: DataRole) {
        *self.slot(role) = None;
    }

    /// Where the file of `role` is kept.
    fn slot(&mut self, role: DataRole) -> &mut Option<NamedText> {
        match role {
            DataRole::Images => &mut self.images,
            DataRole::Members => &mut self.members,
            DataRole::Arcs => &mut self.arcs,
            DataRole::Model => &mut self.model,
            DataRole::Shear => &mut self.shear,
        }
    }

    /// Reads a deflection FITS map for axis 0 (x) or 1 (y); an error changes nothing.
    pub fn load_fits(
        &mut self,
        axis: usize,
        name: &str,
        bytes: &[u8],
    ) -> Result<LoadReport, AppError> {
        if axis > 1 {
            return Err(AppError::File(format!(
                "{name}: axis {axis} is not 0 (x) or 1 (y)"
            )));
        }
        let file = |e: &dyn std::fmt::Display| AppError::File(e.to_string());
        let image = read_image(bytes, name).map_err(|e| file(&e))?;
        let (_, reference) = image.geometry().map_err(|e| file(&e))?;
        let (map, no_data) = image.to_map_no_data().map_err(|e| file(&e))?;
        let n = map.geometry.pixels;
        let mut warnings = Vec::new();
        if no_data.total() > 0 {
            warnings.push(format!(
                "{name}: {} pixels have no data ({} NaN or blank, {} in borders of zeros): \
                 blank in the views, \"no data\" in read-outs",
                no_data.total(),
                no_data.blank,
                no_data.zero_border
            ));
        }
        let fits = (bytes.len() <= MAX_STORED_FITS_BYTES).then(|| bytes.to_vec());
        if fits.is_none() {
            warnings.push(too_large_to_keep(name, bytes.len()));
        }
        let summary = format!(
            "{n} x {n} pixels, {:.1} arcsec wide",
            map.geometry.size_arcsec
        );
        self.deflection[axis] = Some(NamedMap {
            name: name.to_string(),
            map,
            reference,
            fits,
        });
        Ok(LoadReport {
            role: ["deflection_x", "deflection_y"][axis].to_string(),
            name: name.to_string(),
            summary,
            warnings,
        })
    }

    /// The loaded files read into one frame (see [`Dataset::read`]); DS9 region arcs are
    /// sampled at `arc_pixel_arcsec`. A member catalogue that is the potfile of the loaded
    /// `.par` (read with `par_options`) may be in the `.par`'s frame.
    pub fn parse(
        &self,
        arc_pixel_arcsec: f64,
        par_options: &ParOptions,
    ) -> Result<Dataset, AppError> {
        fn text(f: &Option<NamedText>) -> Option<InputText<'_>> {
            f.as_ref().map(|f| InputText {
                name: &f.name,
                text: &f.text,
            })
        }
        let unknown_source_z = self.unknown_source_z(par_options);
        let files = InputTexts {
            images: text(&self.images),
            members: text(&self.members),
            arcs: text(&self.arcs),
            shear: text(&self.shear),
            potfile_reference: self.potfile_reference(par_options),
            unknown_source_z: unknown_source_z.as_ref(),
        };
        Dataset::read(&files, arc_pixel_arcsec).map_err(|e| AppError::File(e.to_string()))
    }
}

//! Constraint pixels: the positions `theta_i` of the rows of the linear system ([method §3]).
//!
//! Each image of a multiple-image system becomes pixels in one of three modes:
//! - `point`: its catalogue position;
//! - `ellipse` (default): the centres of a square lattice of pitch `pixel_arcsec` (default
//!   0.2 arcsec, an HST drizzled pixel scale) centred on the image that fall inside its
//!   catalogue ellipse (`a`, `b` semi-axes in arcsec, `theta` degrees counter-clockwise from
//!   +x), about `pi a b / pixel^2` of them and always at least the centre;
//! - `arcs`: pixels given explicitly in an arc file (see [`super::parse_arcs`]).
//!
//! Weights (the diagonal of `W`, in 1/arcsec^2) are `w / sigma_pos^2` with `w` from the
//! weighting scheme: `equal_per_image` (default) gives each image a total `w` of 1 shared by
//! its pixels, so a large arc counts as much as a compact image and `point` mode gets `w = 1`
//! everywhere; `equal_per_pixel` gives every pixel `w = 1`; `equal_per_system` gives each
//! system a total of 1. `sigma_pos_arcsec` (default 0.5, a common image-plane position error)
//! scales all weights alike, which changes chi^2 but not the solution.
//!
//! Systems without a redshift (and those named in `free_z_systems`) have it estimated when
//! `free_z_prior` is set (the default): they are left out of a first fit and their redshift
//! is then found on its lens (`crate::reconstruct`'s `free_z` module), after which they are
//! fitted at it (`z_estimates`). A system's own prior in `z_priors` (a `.par`'s `z_m_limit`
//! lines) overrides its catalogue redshift as Lenstool does: a range or a normal prior makes
//! it estimated within that prior, a fixed value fits it at that redshift. With `default_z`
//! given instead, systems without a redshift take it; with neither, they are left out.
//! Systems with a single image and held-out systems are left out too. Each system left out is
//! listed in [`ConstraintSet::excluded`].
//!
//! [method §3]: crate::method#3-the-linear-system

use std::collections::BTreeMap;

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::catalog::ImageCatalog;

use crate::arcs::ArcCatalog;

/// What can be wrong with constraint settings or inputs.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ConstraintError {
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error("constraints: mode \"{mode}\" cannot use {given}")]
    ModeMismatch {
        mode: &'static str,
        given: &'static str,
    },
    #[error("{source_name}: line {line}: image {id}: {field} = {} is not allowed ({reason})", crate::error::number(*.value))]
    BadImage {
        source_name: String,
        line: usize,
        id: String,
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error("{source_name}: image {id}: its ellipse holds about {pixels} pixels, more than max_pixels_per_image = {max}")]
    TooManyPixels {
        source_name: String,
        id: String,
        pixels: f64,
        max: usize,
    },
    #[error("constraints: hold-out system \"{id}\" is not in {source_name}")]
    UnknownHoldOut { source_name: String, id: String },
    #[error("constraints: free_z_systems: system \"{id}\" is not in {source_name}")]
    UnknownFreeZ { source_name: String, id: String },
    #[error("constraints: z_priors: system \"{id}\" is not in {source_name}")]
    UnknownZPrior { source_name: String, id: String },
    #[error("{source_name}: no system is left to constrain the model (excluded: {excluded})")]
    NoSystems {
        source_name: String,
        excluded: String,
    },
}

/// How images become pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConstraintMode {
    Point,
    Ellipse,
    Arcs,
}

impl ConstraintMode {
    /// The mode's name in settings files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Point => "point",
            Self::Ellipse => "ellipse",
            Self::Arcs => "arcs",
        }
    }
}

/// How the rows of pixels are weighted against each other (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Weighting {
    EqualPerPixel,
    EqualPerImage,
    EqualPerSystem,
}

/// Constraint settings (the `constraints` block of an inversion configuration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ConstraintConfig {
    /// "point", "ellipse" (default) or "arcs".
    pub mode: ConstraintMode,
    /// Lattice pitch of `ellipse` mode in arcsec (default 0.2). Allowed [1e-3, 10].
    pub pixel_arcsec: f64,
    /// "equal_per_image" (default), "equal_per_pixel" or "equal_per_system".
    pub weighting: Weighting,
    /// Image-plane position error in arcsec (default 0.5). Allowed [1e-4, 100].
    pub sigma_pos_arcsec: f64,
    /// Redshift given to systems whose redshift is unknown (default none: estimated, see
    /// `free_z_prior`).
    pub default_z: Option<f64>,
    /// Systems whose catalogue redshift is set aside and estimated like an unknown one (ids;
    /// default none).
    pub free_z_systems: Vec<String>,
    /// The range an unknown redshift is estimated in, `[low, high]` (default `[0.5, 8]`; the
    /// low end is raised to just behind the lens). `null`: systems without a redshift are left
    /// out (unless `default_z` is given), and only a system with a range or normal prior of
    /// its own in `z_priors` is estimated, under that prior alone. Allowed 0 < low < high <=
    /// 20.
    pub free_z_prior: Option<[f64; 2]>,
    /// A redshift prior of a system's own, by id, overriding its catalogue redshift (default
    /// none; a `.par`'s `z_m_limit` lines give them): `{"range": [low, high]}` estimates it
    /// within that range (and within `free_z_prior`), `{"normal": [mean, sigma]}` weighs the
    /// estimate by that normal, `{"fixed": z}` fits the system at `z` (also when
    /// `free_z_systems` names it). Redshifts allowed (0, 20).
    pub z_priors: BTreeMap<String, RedshiftPrior>,
    /// At most how many times the estimated redshifts are made again on the map fitted to
    /// every system, and the systems fitted again at them, until no estimate moves (default
    /// 2; 0 keeps the first estimates, made on the lens of the systems with a redshift).
    /// Allowed 0 to 10.
    pub free_z_passes: usize,
    /// Redshifts estimated for the systems above, by id: these systems are fitted at them
    /// (set by the reconstruction, never read from a settings file).
    #[serde(skip)]
    pub z_estimates: Vec<(String, f64)>,
    /// The image-plane error (arcsec) each estimated redshift's uncertainty adds to its
    /// system's images, by id (set by the reconstruction, never read from a settings file):
    /// their weights are `1 / (sigma_pos_arcsec^2 + error^2)`.
    #[serde(skip)]
    pub z_estimate_errors: Vec<(String, f64)>,
    /// Largest number of pixels one ellipse may hold (default 10000). Allowed 1 to
    /// [`crate::limits::MAX_ARC_PIXELS`].
    pub max_pixels_per_image: usize,
}

impl Default for ConstraintConfig {
    fn default() -> Self {
        Self {
            mode: ConstraintMode::Ellipse,
            pixel_arcsec: 0.2,
            weighting: Weighting::EqualPerImage,
            sigma_pos_arcsec: 0.5,
            default_z: None,
            free_z_systems: Vec::new(),
            free_z_prior: Some(DEFAULT_FREE_Z_PRIOR),
            z_priors: BTreeMap::new(),
            free_z_passes: DEFAULT_FREE_Z_PASSES,
            z_estimates: Vec::new(),
            z_estimate_errors: Vec::new(),
            max_pixels_per_image: 10_000,
        }
    }
}

/// A system's own redshift prior (`constraints.z_priors`), as a Lenstool `z_m_limit` line
/// gives it (its flag 1, 3 and 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum RedshiftPrior {
    /// Uniform over `[low, high]`.
    Range([f64; 2]),
    /// A normal of `[mean, sigma]`.
    Normal([f64; 2]),
    /// Known: the system is fitted at it.
    Fixed(f64),
}

impl RedshiftPrior {
    /// Whether the system's redshift is estimated under this prior (not fixed).
    pub fn is_estimated(self) -> bool {
        !matches!(self, Self::Fixed(_))
    }

    /// In words, for messages: "uniform 2.5 - 4", "normal 2.91 +- 0.35", "fixed at 2.82".
    pub fn describe(self) -> String {
        match self {
            Self::Range([lo, hi]) => format!("uniform {lo} - {hi}"),
            Self::Normal([mean, sigma]) => format!("normal {mean} +- {sigma}"),
            Self::Fixed(z) => format!("fixed at {z}"),
        }
    }

    /// The first value that cannot be used, and what is allowed, if any.
    fn invalid(self) -> Option<(f64, &'static str)> {
        let z_ok = |z: f64| z.is_finite() && z > 0.0 && z < 20.0;
        let (values, reason) = match self {
            Self::Range([lo, hi]) => (
                [(lo, z_ok(lo)), (hi, z_ok(hi) && hi > lo)],
                "a range [low, high] with 0 < low < high < 20",
            ),
            Self::Normal([mean, sigma]) => (
                [
                    (mean, z_ok(mean)),
                    (sigma, sigma.is_finite() && sigma > 0.0),
                ],
                "a normal [mean, sigma] with 0 < mean < 20 and sigma > 0",
            ),
            Self::Fixed(z) => ([(z, z_ok(z)); 2], "a source redshift in (0, 20)"),
        };
        values
            .iter()
            .find(|(_, ok)| !ok)
            .map(|&(value, _)| (value, reason))
    }
}

/// The default range of an estimated redshift: from the nearest sources lensed into
/// arcs by clusters to the most distant lensed galaxies catalogued (the prior).
pub const DEFAULT_FREE_Z_PRIOR: [f64; 2] = [0.5, 8.0];

/// `free_z_passes`'s default: measured on the synthetic clusters with five redshifts kept
/// (BENCHMARKS.md, "Estimated redshifts made consistent with the map").
pub const DEFAULT_FREE_Z_PASSES: usize = 2;

impl ConstraintConfig {
    /// Whether the system `id` with catalogue redshift `z` has its redshift estimated: under
    /// a range or normal prior of its own (`z_priors`, which also decide when they fix it),
    /// or named in `free_z_systems`, or without one while neither `default_z` is given nor
    /// estimation switched off (`free_z_prior` null).
    pub fn is_free_z(&self, id: &str, z: Option<f64>) -> bool {
        if let Some(p) = self.z_priors.get(id) {
            return p.is_estimated();
        }
        self.free_z_prior.is_some()
            && (self.free_z_systems.iter().any(|s| s == id)
                || (z.is_none() && self.default_z.is_none()))
    }

    /// The redshift given for the system `id` (catalogue redshift `z`), and whether it is
    /// assumed: the one its own prior fixes (a `.par`'s `z_m_limit` with flag 0, whatever the
    /// catalogue says), else the catalogue's, else `default_z` (assumed); `None` when none is
    /// given. A fit takes it unless the redshift is estimated ([`Self::is_free_z`]); a system
    /// held out of a fit (`--holdout`, a fold) is predicted at it.
    pub fn given_z(&self, id: &str, z: Option<f64>) -> Option<(f64, bool)> {
        match self.z_fixed(id).or(z) {
            Some(z) => Some((z, false)),
            None => self.default_z.map(|z| (z, true)),
        }
    }

    /// The redshift `z_priors` fixes for `id`, if it does.
    fn z_fixed(&self, id: &str) -> Option<f64> {
        match self.z_priors.get(id) {
            Some(&RedshiftPrior::Fixed(z)) => Some(z),
            _ => None,
        }
    }

    /// The redshift estimated for `id`, once there is one.
    fn z_estimate(&self, id: &str) -> Option<f64> {
        self.z_estimates
            .iter()
            .find(|(s, _)| s == id)
            .map(|&(_, z)| z)
    }

    /// Checks every field against the range in its documentation.
    pub fn validate(&self) -> Result<(), ConstraintError> {
        let bad = |field: &str, value, reason| {
            ConstraintError::from(crate::error::BadFieldValue::new(
                format!("constraints.{field}"),
                value,
                reason,
            ))
        };
        if !(self.pixel_arcsec.is_finite() && (1e-3..=10.0).contains(&self.pixel_arcsec)) {
            return Err(bad(
                "pixel_arcsec",
                self.pixel_arcsec,
                "must be in [1e-3, 10] arcsec",
            ));
        }
        if !(self.sigma_pos_arcsec.is_finite() && (1e-4..=100.0).contains(&self.sigma_pos_arcsec)) {
            return Err(bad(
                "sigma_pos_arcsec",
                self.sigma_pos_arcsec,
                "must be in [1e-4, 100] arcsec",
            ));
        }
        if let Some(z) = self.default_z {
            if !(z.is_finite() && z > 0.0 && z < 20.0) {
                return Err(bad("default_z", z, "a source redshift must be in (0, 20)"));
            }
        }
        if self.free_z_passes > 10 {
            return Err(bad(
                "free_z_passes",
                self.free_z_passes as f64,
                "must be 0 to 10",
            ));
        }
        if let Some([low, high]) = self.free_z_prior {
            if !(low.is_finite() && low > 0.0) {
                return Err(bad(
                    "free_z_prior[0]",
                    low,
                    "a source redshift must be in (0, 20)",
                ));
            }
            if !(high.is_finite() && high > low && high <= 20.0) {
                return Err(bad(
                    "free_z_prior[1]",
                    high,
                    "the upper end must lie above the lower and at most at 20",
                ));
            }
        }
        for (id, prior) in &self.z_priors {
            if let Some((value, reason)) = prior.invalid() {
                return Err(bad(&format!("z_priors.{id}"), value, reason));
            }
        }
        if !(1..=crate::limits::MAX_ARC_PIXELS).contains(&self.max_pixels_per_image) {
            return Err(bad(
                "max_pixels_per_image",
                self.max_pixels_per_image as f64,
                "must be 1 to 10^6, the most arc pixels of all systems together",
            ));
        }
        Ok(())
    }
}

/// One constraint position: two rows (x and y) of the linear system.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConstraintPixel {
    /// Index into [`ConstraintSet::systems`].
    pub system: usize,
    /// Index of the image within its system.
    pub image: usize,
    /// `theta` in arcsec.
    pub position: DVec2,
    /// Row weight in 1/arcsec^2 (both rows).
    pub weight: f64,
}

/// One source system that is used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstraintSystem {
    pub id: String,
    /// Source redshift.
    pub z: f64,
    /// True when `z` is `default_z` (the catalogue did not know it).
    pub z_assumed: bool,
    /// Image ids, in order (`image` of a pixel indexes this).
    pub images: Vec<String>,
    pub n_pixels: usize,
}

/// Why a system was left out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Exclusion {
    UnknownRedshift,
    /// Its redshift is to be estimated from a fit of the other systems.
    FreeRedshift,
    SingleImage,
    HeldOut,
}

/// In words, for messages and `summary.json` ("1 (no redshift)").
impl std::fmt::Display for Exclusion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::UnknownRedshift => "no redshift",
            Self::FreeRedshift => "redshift to be estimated",
            Self::SingleImage => "a single image",
            Self::HeldOut => "held out",
        })
    }
}

/// A system left out, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExcludedSystem {
    pub id: String,
    pub reason: Exclusion,
}

/// All constraint pixels, grouped by system (pixels of a system are contiguous, in system
/// order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstraintSet {
    pub systems: Vec<ConstraintSystem>,
    pub pixels: Vec<ConstraintPixel>,
    pub excluded: Vec<ExcludedSystem>,
    pub warnings: Vec<String>,
}

/// Where the constraints come from.
#[derive(Debug, Clone, Copy)]
pub enum ConstraintSource<'a> {
    /// Catalogue images, as points or ellipses.
    Catalog(&'a ImageCatalog),
    /// Explicit arc pixels (mode `arcs`).
    Arcs(&'a ArcCatalog),
}

/// Lattice points `center + (i, j) * pixel` (arcsec) inside the ellipse of semi-axes `a`, `b`
/// (arcsec) with the `a` axis at `theta_deg` counter-clockwise from +x; the centre is always
/// included. `a` or `b` <= 0 gives the centre alone. Each lattice row is scanned only over
/// the chord of the ellipse, so the work is that of the pixels found.
pub fn ellipse_pixels(center: DVec2, a: f64, b: f64, theta_deg: f64, pixel: f64) -> Vec<DVec2> {
    if a <= 0.0 || b <= 0.0 {
        return vec![center];
    }
    let (sin, cos) = theta_deg.to_radians().sin_cos();
    let inside = |d: DVec2| {
        let along = d.x * cos + d.y * sin;
        let across = -d.x * sin + d.y * cos;
        (along / a).powi(2) + (across / b).powi(2) <= 1.0
    };
    // The ellipse as q_xx x^2 + q_xy x y + q_yy y^2 <= 1.
    let (ia2, ib2) = (1.0 / (a * a), 1.0 / (b * b));
    let q_xx = cos * cos * ia2 + sin * sin * ib2;
    let q_xy = 2.0 * cos * sin * (ia2 - ib2);
    let q_yy = sin * sin * ia2 + cos * cos * ib2;
    let half_height = (a * a * sin * sin + b * b * cos * cos).sqrt();
    let rows = (half_height / pixel).ceil() as i64;
    let mut out = Vec::new();
    for j in -rows..=rows {
        let y = j as f64 * pixel;
        let disc = q_xy * q_xy * y * y - 4.0 * q_xx * (q_yy * y * y - 1.0);
        if disc < 0.0 {
            continue;
        }
        let root = disc.sqrt();
        let lo = ((-q_xy * y - root) / (2.0 * q_xx * pixel)).floor() as i64 - 1;
        let hi = ((-q_xy * y + root) / (2.0 * q_xx * pixel)).ceil() as i64 + 1;
        for i in lo..=hi {
            let d = DVec2::new(i as f64 * pixel, y);
            if inside(d) {
                out.push(center + d);
            }
        }
    }
    if out.is_empty() {
        out.push(center);
    }
    out
}

/// A system on its way into the set: id, redshift, images as pixel lists, image ids.
struct Candidate {
    id: String,
    z: Option<f64>,
    image_ids: Vec<String>,
    images: Vec<Vec<DVec2>>,
    /// Whether a single pixel list is one image (catalogue: the system is left out) rather than
    /// an arc whose pixels must all map to one source position (arc file: kept).
    single_is_one_image: bool,
}

/// Catalogue images to candidate systems, as points or ellipse pixels.
fn catalog_candidates(
    catalog: &ImageCatalog,
    config: &ConstraintConfig,
) -> Result<Vec<Candidate>, ConstraintError> {
    let mut out = Vec::with_capacity(catalog.systems.len());
    for system in &catalog.systems {
        let mut images = Vec::with_capacity(system.images.len());
        for im in &system.images {
            let bad =
                |field: &'static str, value: f64, reason: &'static str| ConstraintError::BadImage {
                    source_name: catalog.source_name.clone(),
                    line: im.line,
                    id: im.id.clone(),
                    field,
                    value,
                    reason,
                };
            let fields = [
                ("x", im.position.x),
                ("y", im.position.y),
                ("a", im.a_arcsec),
                ("b", im.b_arcsec),
                ("theta", im.theta_deg),
            ];
            if let Some((field, value)) = fields.iter().find(|(_, v)| !v.is_finite()) {
                return Err(bad(field, *value, "must be finite"));
            }
            if let Some(z) = system.z {
                if !(z.is_finite() && z > 0.0) {
                    return Err(bad("z", z, "a source redshift must be positive"));
                }
            }
            images.push(match config.mode {
                ConstraintMode::Point => vec![im.position],
                _ => {
                    let estimate =
                        std::f64::consts::PI * im.a_arcsec.max(0.0) * im.b_arcsec.max(0.0)
                            / (config.pixel_arcsec * config.pixel_arcsec);
                    if estimate > config.max_pixels_per_image as f64 {
                        return Err(ConstraintError::TooManyPixels {
                            source_name: catalog.source_name.clone(),
                            id: im.id.clone(),
                            pixels: estimate.round(),
                            max: config.max_pixels_per_image,
                        });
                    }
                    ellipse_pixels(
                        im.position,
                        im.a_arcsec,
                        im.b_arcsec,
                        im.theta_deg,
                        config.pixel_arcsec,
                    )
                }
            });
        }
        out.push(Candidate {
            id: system.id.clone(),
            z: system.z,
            image_ids: system.images.iter().map(|i| i.id.clone()).collect(),
            images,
            single_is_one_image: true,
        });
    }
    Ok(out)
}

/// The first of `ids` that names none of `candidates`' systems.
fn first_unknown<'a>(
    ids: impl IntoIterator<Item = &'a String>,
    candidates: &[Candidate],
) -> Option<String> {
    ids.into_iter()
        .find(|id| !candidates.iter().any(|c| &c.id == *id))
        .cloned()
}

/// Constraint pixels and weights from `source` (see the module documentation). Systems whose
/// id is in `hold_out` are left out (every id must exist).
pub fn build_constraints(
    source: ConstraintSource<'_>,
    config: &ConstraintConfig,
    hold_out: &[String],
) -> Result<ConstraintSet, ConstraintError> {
    config.validate()?;
    let (source_name, candidates) = match (source, config.mode) {
        (ConstraintSource::Catalog(c), ConstraintMode::Point | ConstraintMode::Ellipse) => {
            (c.source_name.clone(), catalog_candidates(c, config)?)
        }
        (ConstraintSource::Arcs(a), ConstraintMode::Arcs) => (
            a.source_name.clone(),
            a.systems
                .iter()
                .map(|s| Candidate {
                    id: s.id.clone(),
                    z: s.z,
                    image_ids: s.image_ids(),
                    images: s.images.clone(),
                    single_is_one_image: false,
                })
                .collect(),
        ),
        (ConstraintSource::Catalog(_), mode) => {
            return Err(ConstraintError::ModeMismatch {
                mode: mode.name(),
                given: "an image catalogue (give an arc file)",
            })
        }
        (ConstraintSource::Arcs(_), mode) => {
            return Err(ConstraintError::ModeMismatch {
                mode: mode.name(),
                given: "an arc file (use mode \"arcs\")",
            })
        }
    };
    // Every system the settings name must be one of the data's.
    if let Some(id) = first_unknown(hold_out, &candidates) {
        return Err(ConstraintError::UnknownHoldOut { source_name, id });
    }
    if let Some(id) = first_unknown(&config.free_z_systems, &candidates) {
        return Err(ConstraintError::UnknownFreeZ { source_name, id });
    }
    if let Some(id) = first_unknown(config.z_priors.keys(), &candidates) {
        return Err(ConstraintError::UnknownZPrior { source_name, id });
    }
    let mut set = ConstraintSet {
        systems: Vec::new(),
        pixels: Vec::new(),
        excluded: Vec::new(),
        warnings: Vec::new(),
    };
    for id in &config.free_z_systems {
        if let Some(z) = config.z_fixed(id) {
            set.warnings.push(format!(
                "{source_name}: system {id} is named to have its redshift estimated, but its \
                 own prior fixes it at z = {z}: fitted at {z}"
            ));
        }
    }
    for c in candidates {
        let free = config.is_free_z(&c.id, c.z);
        let estimate = config.z_estimate(&c.id).filter(|_| free);
        let given = config.given_z(&c.id, c.z);
        let z = if free {
            estimate
        } else {
            given.map(|(z, _)| z)
        };
        let exclusion = if hold_out.contains(&c.id) {
            // Predicted at the given redshift (`given_z`), whether or not the fit estimates it.
            if given.is_none() && estimate.is_none() {
                set.warnings.push(format!(
                    "{source_name}: system {} is held out but has no redshift to predict its \
                     images at (none in the catalogue, no prior of its own fixes one, no \
                     default_z): it is left out and not predicted",
                    c.id
                ));
            }
            Err(Exclusion::HeldOut)
        } else if c.images.len() < 2 && c.single_is_one_image {
            set.warnings.push(format!(
                "{source_name}: system {} has a single image: not used",
                c.id
            ));
            Err(Exclusion::SingleImage)
        } else if let Some(z) = z {
            Ok(z)
        } else if free {
            Err(Exclusion::FreeRedshift)
        } else {
            set.warnings.push(format!(
                "{source_name}: system {} has no redshift and no default_z is set: not used",
                c.id
            ));
            Err(Exclusion::UnknownRedshift)
        };
        match exclusion {
            Ok(z) => {
                let assumed = !free && given.is_some_and(|(_, assumed)| assumed);
                if assumed {
                    set.warnings.push(format!(
                        "{source_name}: system {} has no redshift: default_z = {z} assumed",
                        c.id
                    ));
                }
                add_system(&mut set, c, z, assumed, config);
            }
            Err(reason) => set.excluded.push(ExcludedSystem { id: c.id, reason }),
        }
    }
    if set.systems.is_empty() {
        let excluded: Vec<String> = set
            .excluded
            .iter()
            .map(|e| match first_line(source, &e.id) {
                Some(line) => format!("{} ({}, line {line})", e.id, e.reason),
                None => format!("{} ({})", e.id, e.reason),
            })
            .collect();
        return Err(ConstraintError::NoSystems {
            source_name,
            excluded: if excluded.is_empty() {
                "none".into()
            } else {
                excluded.join(", ")
            },
        });
    }
    Ok(set)
}

/// The catalogue line of a system's first image (`None` for arc files).
fn first_line(source: ConstraintSource<'_>, id: &str) -> Option<usize> {
    match source {
        ConstraintSource::Catalog(c) => c
            .systems
            .iter()
            .find(|s| s.id == id)
            .and_then(|s| s.images.first())
            .map(|i| i.line),
        ConstraintSource::Arcs(_) => None,
    }
}

/// Appends one system's pixels with their weights (module documentation).
fn add_system(
    set: &mut ConstraintSet,
    c: Candidate,
    z: f64,
    z_assumed: bool,
    config: &ConstraintConfig,
) {
    let system = set.systems.len();
    let n_pixels: usize = c.images.iter().map(Vec::len).sum();
    let added = config
        .z_estimate_errors
        .iter()
        .find(|(id, _)| *id == c.id)
        .map_or(0.0, |&(_, e)| e);
    let inv_var = 1.0 / (config.sigma_pos_arcsec * config.sigma_pos_arcsec + added * added);
    for (image, pixels) in c.images.iter().enumerate() {
        let w = match config.weighting {
            Weighting::EqualPerPixel => 1.0,
            Weighting::EqualPerImage => 1.0 / pixels.len() as f64,
            Weighting::EqualPerSystem => 1.0 / n_pixels as f64,
        };
        set.pixels
            .extend(pixels.iter().map(|&position| ConstraintPixel {
                system,
                image,
                position,
                weight: w * inv_var,
            }));
    }
    set.systems.push(ConstraintSystem {
        id: c.id,
        z,
        z_assumed,
        images: c.image_ids,
        n_pixels,
    });
}

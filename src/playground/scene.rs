//! The scene: what the playground shows, as versioned JSON (format in [`super`]), validated
//! and built into one lens and its source planes.

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::cosmology::{Cosmology, CosmologyError, LensPlane};
use crate::inversion::{member_halo, MemberConfig};
use crate::model::{ComponentSpec, ModelFile};
use crate::profiles::{Lens, MassComponent, ProfileError};

/// The scene format version this build reads and writes.
pub const SCENE_VERSION: u32 = 1;
/// Most lenses and most sources a scene may hold (a playground, not a cluster catalogue).
pub const MAX_SCENE_ITEMS: usize = 64;
/// Source redshift for the curves of a scene without sources.
pub const DEFAULT_Z_SOURCE: f64 = 2.0;

/// What can be wrong with a scene; every variant names the field.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SceneError {
    /// Malformed JSON or a field of the wrong shape.
    #[error("scene: line {line}, column {column}: {message}")]
    Syntax {
        line: usize,
        column: usize,
        message: String,
    },
    /// A version other than [`SCENE_VERSION`].
    #[error("scene: version v = {found} is not supported (this build reads v = {SCENE_VERSION})")]
    Version { found: u32 },
    /// A number out of range.
    #[error("scene: {field} = {} is not allowed ({reason})", crate::error::number(*.value))]
    BadField {
        field: String,
        value: f64,
        reason: &'static str,
    },
    /// A lens whose profile refuses its parameters.
    #[error("scene: lenses[{index}] ({kind}): {source}")]
    Lens {
        index: usize,
        kind: &'static str,
        #[source]
        source: ProfileError,
    },
    /// Bad cosmology or lens redshift.
    #[error("scene: {0}")]
    Cosmology(#[from] CosmologyError),
}

/// A member galaxy: a halo whose mass and size follow its magnitude by the inversion's
/// luminosity scaling ([`MemberConfig::default`]), so an inversion given the same catalogue
/// finds `C = 1` as the truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemberGalaxy {
    /// Position in arcsec.
    pub x: f64,
    pub y: f64,
    /// Apparent magnitude.
    pub mag: f64,
}

/// One lens of a scene: a model-file component or a member galaxy (`"type": "member"`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "serde_json::Value", into = "serde_json::Value")]
pub enum SceneLens {
    Component(ComponentSpec),
    Member(MemberGalaxy),
}

impl TryFrom<serde_json::Value> for SceneLens {
    type Error = serde_json::Error;
    fn try_from(mut v: serde_json::Value) -> Result<Self, Self::Error> {
        if v.get("type").and_then(|t| t.as_str()) == Some("member") {
            if let Some(obj) = v.as_object_mut() {
                obj.remove("type");
            }
            return serde_json::from_value(v).map(Self::Member);
        }
        serde_json::from_value(v).map(Self::Component)
    }
}

impl From<SceneLens> for serde_json::Value {
    fn from(lens: SceneLens) -> Self {
        match lens {
            SceneLens::Component(c) => serde_json::to_value(c).unwrap_or_default(),
            SceneLens::Member(m) => {
                let mut v = serde_json::to_value(m).unwrap_or_default();
                if let Some(obj) = v.as_object_mut() {
                    obj.insert("type".into(), "member".into());
                }
                v
            }
        }
    }
}

impl SceneLens {
    /// The `"type"` tag.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Component(c) => c.kind(),
            Self::Member(_) => "member",
        }
    }
}

fn one() -> f64 {
    1.0
}

/// One source (units in [`super`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum SourceSpec {
    /// Gaussian of width `sigma` (arcsec along the major axis).
    Gaussian {
        x: f64,
        y: f64,
        z: f64,
        sigma: f64,
        #[serde(default = "one")]
        q: f64,
        #[serde(default)]
        pa: f64,
    },
    /// Sérsic profile of half-light radius `r_eff` (arcsec, major axis) and index `n`.
    Sersic {
        x: f64,
        y: f64,
        z: f64,
        r_eff: f64,
        n: f64,
        #[serde(default = "one")]
        q: f64,
        #[serde(default)]
        pa: f64,
    },
    /// A point source: its images are found, not drawn as pixels.
    Point { x: f64, y: f64, z: f64 },
    /// An uploaded picture `size` arcsec on its longer side; `slot` names the pixels the
    /// playground holds for it (not part of a shared scene).
    Image {
        x: f64,
        y: f64,
        z: f64,
        size: f64,
        #[serde(default)]
        slot: u32,
    },
}

impl SourceSpec {
    /// Position in arcsec.
    pub fn position(&self) -> DVec2 {
        match *self {
            Self::Gaussian { x, y, .. }
            | Self::Sersic { x, y, .. }
            | Self::Point { x, y, .. }
            | Self::Image { x, y, .. } => DVec2::new(x, y),
        }
    }
    /// Redshift.
    pub fn z(&self) -> f64 {
        match *self {
            Self::Gaussian { z, .. }
            | Self::Sersic { z, .. }
            | Self::Point { z, .. }
            | Self::Image { z, .. } => z,
        }
    }
}

/// A playground scene (format in [`super`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Format version, [`SCENE_VERSION`].
    pub v: u32,
    /// Flat ΛCDM (default H0 = 70, Ωm = 0.3).
    #[serde(default, skip_serializing_if = "is_default_cosmology")]
    pub cosmology: Cosmology,
    /// Lens redshift.
    pub z_lens: f64,
    /// Side of the image-plane view in arcsec, centred on the origin.
    pub fov: f64,
    /// Side of the source-plane view in arcsec (default `fov / 2`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source_fov: Option<f64>,
    pub lenses: Vec<SceneLens>,
    pub sources: Vec<SourceSpec>,
}

fn is_default_cosmology(c: &Cosmology) -> bool {
    *c == Cosmology::default()
}

/// One source plane of a built scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SourcePlane {
    pub z: f64,
    /// `D_ls/D_s`.
    pub f: f64,
}

/// A scene built: its lens and the distance ratio of every source.
#[derive(Debug)]
pub struct BuiltScene {
    pub plane: LensPlane,
    pub lens: Lens,
    /// `D_ls/D_s` of each source, in the order of [`Scene::sources`].
    pub source_f: Vec<f64>,
    /// The distinct source redshifts, ascending ([`DEFAULT_Z_SOURCE`] when there is no source).
    pub planes: Vec<SourcePlane>,
}

impl Scene {
    /// Parses and validates a scene.
    pub fn from_json_str(text: &str) -> Result<Self, SceneError> {
        let scene: Self = serde_json::from_str(text).map_err(|e| {
            let (line, column, message) = crate::limits::json_error_parts(text, &e);
            SceneError::Syntax {
                line,
                column,
                message,
            }
        })?;
        scene.build()?;
        Ok(scene)
    }

    /// The scene as compact JSON.
    pub fn to_json_string(&self) -> String {
        // Numbers and strings only: serde_json cannot fail on them.
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Side of the source-plane view in arcsec.
    pub fn source_fov(&self) -> f64 {
        self.source_fov.unwrap_or(0.5 * self.fov)
    }

    /// The model-file components of the lenses, member galaxies expanded into their halos
    /// (truncated NFW, as the inversion builds them).
    pub fn components(&self, plane: &LensPlane) -> Result<Vec<ComponentSpec>, SceneError> {
        let config = MemberConfig::default();
        let mag_star = config.mag_star_on(plane);
        self.lenses
            .iter()
            .enumerate()
            .map(|(index, lens)| match *lens {
                SceneLens::Component(c) => Ok(c),
                SceneLens::Member(m) => member_component(index, m, &config, mag_star, plane),
            })
            .collect()
    }

    /// The truth as a model file: the scene's cosmology, lens redshift and every lens, member
    /// galaxies expanded into their halos. A scene with no lens gives a model with no
    /// component, which [`ModelFile::validate`] refuses.
    pub fn truth_model(&self) -> Result<ModelFile, SceneError> {
        let plane = LensPlane::new(self.cosmology, self.z_lens)?;
        Ok(ModelFile {
            cosmology: self.cosmology,
            z_lens: self.z_lens,
            reference: None,
            components: self.components(&plane)?,
            source_name: "scene".to_string(),
        })
    }

    /// Validates every field and builds the lens and the source planes.
    pub fn build(&self) -> Result<BuiltScene, SceneError> {
        if self.v != SCENE_VERSION {
            return Err(SceneError::Version { found: self.v });
        }
        self.cosmology.validate()?;
        let plane = LensPlane::new(self.cosmology, self.z_lens)?;
        positive("fov", self.fov, 1e4)?;
        if let Some(s) = self.source_fov {
            positive("source_fov", s, 1e4)?;
        }
        for (what, n) in [
            ("lenses", self.lenses.len()),
            ("sources", self.sources.len()),
        ] {
            if n > MAX_SCENE_ITEMS {
                return Err(SceneError::BadField {
                    field: format!("{what} (count)"),
                    value: n as f64,
                    reason: "a scene holds at most 64 lenses and 64 sources",
                });
            }
        }
        let mut parts: Vec<Box<dyn MassComponent>> = Vec::new();
        for (index, spec) in self.components(&plane)?.iter().enumerate() {
            let kind = self.lenses[index].kind();
            parts.push(spec.build(&plane).map_err(|source| SceneError::Lens {
                index,
                kind,
                source,
            })?);
        }
        let mut source_f = Vec::with_capacity(self.sources.len());
        for (k, s) in self.sources.iter().enumerate() {
            check_source(k, s)?;
            source_f.push(plane.distance_ratio(s.z())?);
        }
        let mut zs: Vec<f64> = self.sources.iter().map(|s| s.z()).collect();
        if zs.is_empty() {
            zs.push(DEFAULT_Z_SOURCE);
        }
        zs.sort_by(f64::total_cmp);
        zs.dedup();
        let planes = zs
            .into_iter()
            .map(|z| {
                Ok(SourcePlane {
                    z,
                    f: plane.distance_ratio(z)?,
                })
            })
            .collect::<Result<Vec<_>, SceneError>>()?;
        Ok(BuiltScene {
            plane,
            lens: Lens::new(parts),
            source_f,
            planes,
        })
    }
}

/// The truncated NFW halo the inversion's member scaling gives galaxy `m`.
fn member_component(
    index: usize,
    m: MemberGalaxy,
    config: &MemberConfig,
    mag_star: f64,
    plane: &LensPlane,
) -> Result<ComponentSpec, SceneError> {
    let field = |name: &str| format!("lenses[{index}].{name}");
    for (name, v) in [("x", m.x), ("y", m.y)] {
        if !v.is_finite() {
            return Err(SceneError::BadField {
                field: field(name),
                value: v,
                reason: "a position in arcsec must be finite",
            });
        }
    }
    if !(m.mag.is_finite() && (m.mag - mag_star).abs() <= 20.0) {
        return Err(SceneError::BadField {
            field: field("mag"),
            value: m.mag,
            reason: "must be within 20 magnitudes of an L* galaxy's",
        });
    }
    let position = DVec2::new(m.x, m.y);
    let mass = config.mass_msun(m.mag, mag_star);
    let (_, m200, c200, r_trunc) =
        member_halo(config, position, mass, plane).map_err(|source| SceneError::Lens {
            index,
            kind: "member",
            source,
        })?;
    Ok(ComponentSpec::Tnfw {
        x: m.x,
        y: m.y,
        m200,
        c200,
        // The default member profile is truncated.
        r_trunc: r_trunc.unwrap_or(f64::INFINITY),
    })
}

fn positive(field: &str, value: f64, max: f64) -> Result<(), SceneError> {
    if value.is_finite() && value > 0.0 && value <= max {
        Ok(())
    } else {
        Err(SceneError::BadField {
            field: field.to_string(),
            value,
            reason: "must be positive and at most 1e4",
        })
    }
}

fn check_source(k: usize, s: &SourceSpec) -> Result<(), SceneError> {
    let bad = |name: &str, value: f64, reason| SceneError::BadField {
        field: format!("sources[{k}].{name}"),
        value,
        reason,
    };
    let p = s.position();
    for (name, v) in [("x", p.x), ("y", p.y)] {
        if !v.is_finite() {
            return Err(bad(name, v, "a position in arcsec must be finite"));
        }
    }
    let (q, pa) = match *s {
        SourceSpec::Gaussian { q, pa, sigma, .. } => {
            positive(&format!("sources[{k}].sigma"), sigma, 1e4)?;
            (q, pa)
        }
        SourceSpec::Sersic {
            q, pa, r_eff, n, ..
        } => {
            positive(&format!("sources[{k}].r_eff"), r_eff, 1e4)?;
            if !(n.is_finite() && (0.2..=10.0).contains(&n)) {
                return Err(bad("n", n, "the Sersic index must be in [0.2, 10]"));
            }
            (q, pa)
        }
        SourceSpec::Image { size, .. } => {
            positive(&format!("sources[{k}].size"), size, 1e4)?;
            (1.0, 0.0)
        }
        SourceSpec::Point { .. } => (1.0, 0.0),
    };
    if !(q.is_finite() && (0.05..=1.0).contains(&q)) {
        return Err(bad("q", q, "the axis ratio must be in [0.05, 1]"));
    }
    if !pa.is_finite() {
        return Err(bad(
            "pa",
            pa,
            "the position angle in degrees must be finite",
        ));
    }
    Ok(())
}

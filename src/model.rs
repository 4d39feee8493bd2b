//! The model file: a parametric lens written as JSON, the input of `wslap maps` and of the
//! app's forward mode.
//!
//! ```json
//! {"cosmology": {"h0": 70.0, "omega_m": 0.3}, "z_lens": 0.3, "reference": {"ra": 3.586, "dec": -30.4},
//!  "components": [
//!    {"type": "nfw", "x": 0.0, "y": 0.0, "m200": 1.0e15, "c200": 5.0, "q": 0.8, "pa": 30.0},
//!    {"type": "tnfw", "x": 20.0, "y": 3.0, "m200": 1.0e12, "c200": 10.0, "r_trunc": 15.0},
//!    {"type": "sis", "x": 10.0, "y": -5.0, "sigma_v": 250.0},
//!    {"type": "point", "x": 0.0, "y": 0.0, "mass": 1.0e12},
//!    {"type": "gaussian", "x": 0.0, "y": 0.0, "mass": 1.0e13, "sigma": 5.0},
//!    {"type": "sie", "x": -4.0, "y": 2.0, "sigma_v": 300.0, "q": 0.7, "pa": 45.0},
//!    {"type": "shear", "gamma1": 0.05, "gamma2": -0.02},
//!    {"type": "sheet", "kappa": 0.1}]}
//! ```
//!
//! Positions `x`, `y`, widths `sigma` and `r_trunc` are arcsec in the frame of [method §1];
//! masses are Msun (`m200` with respect to 200 `rho_crit(z_lens)`); `sigma_v` is
//! km/s; `q` (axis ratio, `0 < q <= 1`, default 1) and `pa` (degrees counter-clockwise from +x,
//! default 0) are optional on `nfw` and `sie`. The `sie` has the Einstein radius of the `sis` of
//! the same `sigma_v` (product-averaged over the axes, lenstronomy's `SIE`). `shear` is an
//! external shear with sky-frame components `gamma1`, `gamma2`, and `sheet` a uniform
//! convergence `kappa`, both about the frame origin. Like every field of the crate, `kappa`,
//! `gamma1` and `gamma2` are for `D_ls/D_s = 1` (see [`crate::MassComponent`]): a source at
//! `z_s` sees them times `D_ls/D_s`. `cosmology` defaults to H0 = 70, Ωm = 0.3; `reference`
//! (the sky position of the frame origin, degrees) is optional. Unknown fields are errors.
//! Components are numbered from 0 in error messages, as in the JSON array.
//!
//! [method §1]: crate::method#1-frames-and-units

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::cosmology::{Cosmology, CosmologyError, LensPlane};
use crate::limits::{json_error_parts, InputKind, TooLarge};
use crate::profiles::{
    ExternalShear, Gaussian, Lens, MassComponent, MassSheet, Nfw, NfwEllipse, PointMass,
    ProfileError, Sie, Sis, TruncatedNfw,
};
pub use crate::sky::SkyReference;

/// What can be wrong with a model file. Every variant names the file (`source_name`).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModelError {
    /// Malformed JSON or a field of the wrong shape outside the component list.
    #[error("{source_name}: line {line}, column {column}: {message}")]
    Syntax {
        source_name: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// A component that does not parse (unknown type or field, missing field, wrong type).
    #[error("{source_name}: line {line}, column {column}: component {index} ({kind}): {message}")]
    ComponentSyntax {
        source_name: String,
        line: usize,
        column: usize,
        index: usize,
        kind: String,
        message: String,
    },
    /// A component parameter out of range.
    #[error(
        "{source_name}: component {index} ({kind}): {field} = {} is not allowed ({reason})", crate::error::number(*.value)
    )]
    BadComponent {
        source_name: String,
        index: usize,
        kind: &'static str,
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// Bad cosmology or lens redshift.
    #[error("{source_name}: {source}")]
    Cosmology {
        source_name: String,
        #[source]
        source: CosmologyError,
    },
    /// A bad sky reference position.
    #[error("{source_name}: reference: {field} = {} is not allowed ({reason})", crate::error::number(*.value))]
    BadReference {
        source_name: String,
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// A text over [`crate::limits::MAX_JSON_BYTES`].
    #[error(transparent)]
    TooLarge(#[from] crate::limits::TooLarge),
    /// The component list is empty.
    #[error("{source_name}: the model has no components (\"components\" must list at least one)")]
    NoComponents { source_name: String },
}

/// One mass component as written in the file (units in the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ComponentSpec {
    /// NFW halo, elliptical in the convergence when `q < 1`.
    Nfw {
        x: f64,
        y: f64,
        m200: f64,
        c200: f64,
        #[serde(default = "default_q")]
        q: f64,
        #[serde(default)]
        pa: f64,
    },
    /// Truncated NFW halo (truncation radius `r_trunc` in arcsec).
    Tnfw {
        x: f64,
        y: f64,
        m200: f64,
        c200: f64,
        r_trunc: f64,
    },
    /// Singular isothermal sphere (`sigma_v` in km/s).
    Sis { x: f64, y: f64, sigma_v: f64 },
    /// Point mass (`mass` in Msun).
    Point { x: f64, y: f64, mass: f64 },
    /// Circular Gaussian (`mass` in Msun, `sigma` in arcsec).
    Gaussian {
        x: f64,
        y: f64,
        mass: f64,
        sigma: f64,
    },
    /// Singular isothermal ellipsoid (`sigma_v` in km/s, axis ratio `q`, `pa` in degrees).
    Sie {
        x: f64,
        y: f64,
        sigma_v: f64,
        #[serde(default = "default_q")]
        q: f64,
        #[serde(default)]
        pa: f64,
    },
    /// External shear (sky-frame components at `D_ls/D_s = 1`).
    Shear { gamma1: f64, gamma2: f64 },
    /// Uniform mass sheet of convergence `kappa` at `D_ls/D_s = 1`.
    Sheet { kappa: f64 },
}

fn default_q() -> f64 {
    1.0
}

impl ComponentSpec {
    /// The `"type"` tag of this component.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Nfw { .. } => "nfw",
            Self::Tnfw { .. } => "tnfw",
            Self::Sis { .. } => "sis",
            Self::Point { .. } => "point",
            Self::Gaussian { .. } => "gaussian",
            Self::Sie { .. } => "sie",
            Self::Shear { .. } => "shear",
            Self::Sheet { .. } => "sheet",
        }
    }

    /// Builds the mass component on `plane`, validating every parameter.
    pub fn build(&self, plane: &LensPlane) -> Result<Box<dyn MassComponent>, ProfileError> {
        Ok(match *self {
            Self::Nfw {
                x,
                y,
                m200,
                c200,
                q,
                pa,
            } => {
                check_axis_ratio(q, pa)?;
                let center = DVec2::new(x, y);
                if q < 1.0 {
                    Box::new(NfwEllipse::new(center, m200, c200, q, pa, plane)?)
                } else {
                    Box::new(Nfw::new(center, m200, c200, plane)?)
                }
            }
            Self::Tnfw {
                x,
                y,
                m200,
                c200,
                r_trunc,
            } => {
                let center = DVec2::new(x, y);
                Box::new(TruncatedNfw::new(center, m200, c200, r_trunc, plane)?)
            }
            Self::Sis { x, y, sigma_v } => Box::new(Sis::new(DVec2::new(x, y), sigma_v)?),
            Self::Point { x, y, mass } => Box::new(PointMass::new(DVec2::new(x, y), mass, plane)?),
            Self::Gaussian { x, y, mass, sigma } => {
                Box::new(Gaussian::new(DVec2::new(x, y), mass, sigma, plane)?)
            }
            Self::Sie {
                x,
                y,
                sigma_v,
                q,
                pa,
            } => Box::new(Sie::new(DVec2::new(x, y), sigma_v, q, pa)?),
            Self::Shear { gamma1, gamma2 } => {
                Box::new(ExternalShear::from_components(DVec2::ZERO, gamma1, gamma2)?)
            }
            Self::Sheet { kappa } => Box::new(MassSheet::new(kappa)?),
        })
    }
}

/// `0 < q <= 1` and a finite `pa` (degrees) for the elliptical NFW.
fn check_axis_ratio(q: f64, pa_deg: f64) -> Result<(), ProfileError> {
    if !(q.is_finite() && q > 0.0 && q <= 1.0) {
        return Err(ProfileError::BadParameter {
            component: "nfw",
            field: "q",
            value: q,
            reason: "the axis ratio must be in (0, 1]",
        });
    }
    if !pa_deg.is_finite() {
        return Err(ProfileError::BadParameter {
            component: "nfw",
            field: "pa",
            value: pa_deg,
            reason: "the position angle in degrees must be finite",
        });
    }
    Ok(())
}

/// A parametric lens model. [`Self::from_json_str`] validates it; a model built or edited in
/// code is checked by [`Self::validate`] (or [`Self::build_lens`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Flat ΛCDM (default H0 = 70, Ωm = 0.3).
    #[serde(default)]
    pub cosmology: Cosmology,
    /// Lens redshift.
    pub z_lens: f64,
    /// Sky position of the frame origin, if known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<SkyReference>,
    /// The mass components, summed.
    pub components: Vec<ComponentSpec>,
    /// Name used in error messages (a file name); not part of the JSON.
    #[serde(skip)]
    pub source_name: String,
}

impl ModelFile {
    /// Parses and validates a model file. `source_name` (e.g. the file name) prefixes every
    /// error message; JSON errors carry line and column, component errors the component index.
    pub fn from_json_str(text: &str, source_name: &str) -> Result<Self, ModelError> {
        TooLarge::check_bytes(source_name, InputKind::Model, text.len() as u64)?;
        if let Some(line) = lenstool_par_line(text) {
            return Err(ModelError::Syntax {
                source_name: source_name.to_string(),
                line,
                column: 1,
                message: "this is a Lenstool parameter file (.par), not a JSON model: give it \
                          with --lenstool (the app reads a .par as the model file)"
                    .to_string(),
            });
        }
        if let Some((line, column, message)) = crate::limits::not_an_object(text) {
            return Err(ModelError::Syntax {
                source_name: source_name.to_string(),
                line,
                column,
                message,
            });
        }
        let mut model: Self =
            serde_json::from_str(text).map_err(|e| syntax_error(text, source_name, &e))?;
        model.source_name = source_name.to_string();
        model.validate()?;
        Ok(model)
    }

    /// The model as pretty-printed JSON, readable again by [`Self::from_json_str`].
    pub fn to_json_string(&self) -> String {
        // Plain structs of numbers with string keys: serde_json cannot fail on them.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The lens plane at `z_lens` in the model's cosmology.
    pub fn lens_plane(&self) -> Result<LensPlane, ModelError> {
        LensPlane::new(self.cosmology, self.z_lens).map_err(|source| ModelError::Cosmology {
            source_name: self.name().to_string(),
            source,
        })
    }

    /// The lens: every component built on [`Self::lens_plane`], with full validation.
    pub fn build_lens(&self) -> Result<Lens, ModelError> {
        let plane = self.lens_plane()?;
        if self.components.is_empty() {
            return Err(ModelError::NoComponents {
                source_name: self.name().to_string(),
            });
        }
        let components = self
            .components
            .iter()
            .enumerate()
            .map(|(index, spec)| {
                spec.build(&plane).map_err(|e| match e {
                    ProfileError::BadParameter {
                        field,
                        value,
                        reason,
                        ..
                    } => ModelError::BadComponent {
                        source_name: self.name().to_string(),
                        index,
                        kind: spec.kind(),
                        field,
                        value,
                        reason,
                    },
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Lens::new(components))
    }

    /// Checks the cosmology, `z_lens`, the reference and every component.
    pub fn validate(&self) -> Result<(), ModelError> {
        if let Some(r) = self.reference {
            self.check_reference(
                "ra",
                r.ra_deg,
                (0.0..360.0).contains(&r.ra_deg),
                "0 <= ra < 360",
            )?;
            let dec_ok = (-90.0..=90.0).contains(&r.dec_deg);
            self.check_reference("dec", r.dec_deg, dec_ok, "-90 <= dec <= 90")?;
        }
        self.build_lens().map(|_| ())
    }

    fn check_reference(
        &self,
        field: &'static str,
        value: f64,
        ok: bool,
        reason: &'static str,
    ) -> Result<(), ModelError> {
        if ok {
            Ok(())
        } else {
            Err(ModelError::BadReference {
                source_name: self.name().to_string(),
                field,
                value,
                reason,
            })
        }
    }

    fn name(&self) -> &str {
        if self.source_name.is_empty() {
            "model"
        } else {
            &self.source_name
        }
    }
}

/// Turns a serde_json error into a [`ModelError`] with line and column. If the text is valid
/// JSON and a component fails to parse on its own, the error also names that component.
fn syntax_error(text: &str, source_name: &str, e: &serde_json::Error) -> ModelError {
    let (line, column, message) = json_error_parts(text, e);
    // Attribute the error to a component only if that component fails on its own with the
    // same message (so a bad top-level field before it is not blamed on it).
    match failing_component(text) {
        Some((index, kind, inner))
            if message.ends_with(&crate::limits::json_words(&inner.to_string())) =>
        {
            ModelError::ComponentSyntax {
                source_name: source_name.to_string(),
                line,
                column,
                index,
                kind,
                message,
            }
        }
        _ => ModelError::Syntax {
            source_name: source_name.to_string(),
            line,
            column,
            message,
        },
    }
}

/// The first component of `text` (if it is JSON with a `components` array) that does not parse:
/// its index, its `"type"` (or `"?"`) and the error.
fn failing_component(text: &str) -> Option<(usize, String, serde_json::Error)> {
    let value: serde_json::Value = serde_json::from_str(text).ok()?;
    let list = value.get("components")?.as_array()?;
    list.iter().enumerate().find_map(|(index, c)| {
        let err = ComponentSpec::deserialize(c).err()?;
        let kind = c.get("type").and_then(|t| t.as_str()).unwrap_or("?");
        Some((index, kind.to_string(), err))
    })
}

/// The line (1-based) of a text's first word when that word opens a Lenstool `.par` block
/// (`runmode`, `potentiel`, ...), so that a `.par` given as a JSON model is named as one.
fn lenstool_par_line(text: &str) -> Option<usize> {
    const BLOCKS: [&str; 8] = [
        "runmode",
        "cosmologie",
        "potentiel",
        "potfile",
        "image",
        "grille",
        "champ",
        "limit",
    ];
    let (k, line) = text
        .lines()
        .enumerate()
        .find(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))?;
    let word = line.split_whitespace().next()?;
    BLOCKS.iter().any(|b| word.starts_with(b)).then_some(k + 1)
}

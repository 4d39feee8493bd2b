//! Errors of the mass-component constructors.

use thiserror::Error;

/// A mass component was given a parameter it cannot use.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ProfileError {
    /// `component` (e.g. `"nfw"`) got `field = value`, which is not allowed for `reason`.
    #[error("{component}: {field} = {} is not allowed ({reason})", crate::error::number(*.value))]
    BadParameter {
        component: &'static str,
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
}

impl ProfileError {
    /// The offending field name (e.g. `"m200"`), for error messages that add context.
    pub fn field(&self) -> &'static str {
        match self {
            Self::BadParameter { field, .. } => field,
        }
    }
}

/// Largest velocity dispersion a profile takes (km/s): the richest clusters have about 1500;
/// far above, `sigma^2` overflows on the way to the maps (1e200 gave NaN pixels).
pub(crate) const MAX_SIGMA_V_KM_S: f64 = 1e4;

/// `value` when it is a velocity dispersion in `(0, MAX_SIGMA_V_KM_S]` km/s.
pub(crate) fn require_sigma_v(component: &'static str, value: f64) -> Result<f64, ProfileError> {
    if value.is_finite() && value > 0.0 && value <= MAX_SIGMA_V_KM_S {
        Ok(value)
    } else {
        Err(ProfileError::BadParameter {
            component,
            field: "sigma_v",
            value,
            reason: "a velocity dispersion must be above 0 and at most 1e4 km/s; the richest \
                     clusters have about 1500",
        })
    }
}

/// `Ok(value)` if `value` is finite and strictly positive, else a [`ProfileError::BadParameter`]
/// with reason "must be positive and finite".
pub(crate) fn require_positive(
    component: &'static str,
    field: &'static str,
    value: f64,
) -> Result<f64, ProfileError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ProfileError::BadParameter {
            component,
            field,
            value,
            reason: "must be positive and finite",
        })
    }
}

/// `Ok(center)` if both coordinates are finite, else a [`ProfileError::BadParameter`] naming
/// the coordinate (`"x"` or `"y"`, arcsec).
pub(crate) fn require_finite_center(
    component: &'static str,
    center: glam::DVec2,
) -> Result<glam::DVec2, ProfileError> {
    for (field, value) in [("x", center.x), ("y", center.y)] {
        if !value.is_finite() {
            return Err(ProfileError::BadParameter {
                component,
                field,
                value,
                reason: "a position in arcsec must be finite",
            });
        }
    }
    Ok(center)
}

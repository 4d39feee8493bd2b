//! The error every settings check shares: a field whose value is outside what a run can use.

use thiserror::Error;

/// A setting or option outside the range a run can use: the field as a settings file names it
/// (its block first, e.g. `grid.cells`, `products.pixels`, `cosmology.omega_m`), the value
/// given, and the reason, which states the range.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{field} = {value} is not allowed ({reason})")]
pub struct BadFieldValue {
    pub field: String,
    pub value: f64,
    pub reason: &'static str,
}

impl BadFieldValue {
    pub fn new(field: impl Into<String>, value: f64, reason: &'static str) -> Self {
        Self {
            field: field.into(),
            value,
            reason,
        }
    }
}

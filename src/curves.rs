//! Critical curves and caustics (METHOD.md section 6).

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// A polyline in arcsec; closed curves repeat no point (the last joins the first).
pub type Polyline = Vec<DVec2>;

/// Critical curves and caustics for one source redshift, in arcsec.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CriticalCurves {
    pub z_source: f64,
    /// `sqrt(area inside the tangential curves / pi)`, 0 when there is none.
    pub einstein_radius_arcsec: f64,
    pub tangential: Vec<Polyline>,
    pub radial: Vec<Polyline>,
    pub caustics: Caustics,
}

/// The critical curves mapped to the source plane.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Caustics {
    pub tangential: Vec<Polyline>,
    pub radial: Vec<Polyline>,
}

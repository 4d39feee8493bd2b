//! The settings of a reconstruction (`CONFIG.json` of `wslap reconstruct`): one struct per
//! stage, every field with a documented default.

use serde::{Deserialize, Serialize};

use crate::error::BadFieldValue;
use crate::inversion::{
    ConstraintConfig, GridConfig, MemberConfig, ObjectiveConfig, Regulariser, ShearConfig,
    SystemConfig,
};
use crate::limits::{json_error_message, InputKind, TooLarge};
use crate::solver::SolverSettings;

use super::ReconstructError;

/// Every setting of a reconstruction. Missing blocks and fields take their defaults; unknown
/// fields are errors.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReconstructConfig {
    /// The cell grid (default 32 x 32 over the images' extent with a margin).
    pub grid: GridConfig,
    /// Member galaxies: masses from magnitudes and the layers (default one layer, the paper).
    pub members: MemberConfig,
    /// Constraints from the images (default: the pixels inside each catalogue ellipse).
    pub constraints: ConstraintConfig,
    /// The linear system (mass unit, frame shift, block size).
    pub system: SystemConfig,
    /// What is minimised: the regulariser, its strength, the image-plane weighting.
    pub objective: ObjectiveConfig,
    /// The solver.
    pub solver: SolverConfig,
    /// The maps and curves of the result.
    pub products: ProductConfig,
    /// Weak lensing: the shape noise of the arclets and the ring of coarser cells (used only
    /// with an arclet catalogue).
    pub shear: ShearConfig,
}

/// Which solver minimises the objective.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolverMethod {
    /// The exact minimiser of the regularised objective ([`crate::solver::minimise_exact`],
    /// default): the answer depends on the objective alone, not on the start or an
    /// iteration count. Needs a regulariser with a positive strength.
    #[default]
    Exact,
    /// QADP, the paper's multiplicative update, stopped after `iterations`: the early stop is
    /// the regulariser.
    Qadp,
    /// The accelerated projected gradient of [`crate::solver::accelerated_gradient`]: it goes
    /// much further per iteration, towards the minimiser of the objective itself, which on
    /// extended arcs is the over-fitting "point-source solution" (too much mass, sources
    /// shrunk). For comparisons: how far the early-stopped answer is from the data's best fit.
    AcceleratedGradient,
}

/// The solver settings and its start (the paper's "reasonable" start: small masses and small C).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverConfig {
    /// "exact" (default), "qadp" (the paper) or "accelerated_gradient" (see [`SolverMethod`]).
    pub method: SolverMethod,
    /// Iterations: for QADP the regulariser (default 8000, the paper's best; 50000 over-fits);
    /// for "exact" the most exchanges of its free set.
    pub iterations: usize,
    /// Report objective, grid mass and C every this many iterations (default 100).
    pub report_every: usize,
    /// Start mass of every cell in Msun (default 1e10: small against a cluster's ~1e12 per
    /// cell, as the paper's "reasonable" start).
    pub start_cell_mass_msun: f64,
    /// Start value of every layer factor C_l (default 0.1).
    pub start_c: f64,
    /// Iterates of the last solve kept in the result ([`crate::Reconstruction::iterates`]; see
    /// [`SolverSettings::keep_iterates`]), default 0. Not a setting: the app asks for them,
    /// to step through the iterations.
    #[serde(skip)]
    pub keep_iterates: usize,
}

impl Default for SolverConfig {
    fn default() -> Self {
        let run = SolverSettings::default();
        Self {
            method: SolverMethod::Exact,
            iterations: run.iterations,
            report_every: run.report_every,
            start_cell_mass_msun: 1e10,
            start_c: 0.1,
            keep_iterates: 0,
        }
    }
}

/// Which maps and curves are made of the result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ProductConfig {
    /// Source redshift of the magnification map and critical curves (default 2).
    pub z_source: f64,
    /// Map side in pixels (default 512).
    pub pixels: usize,
    /// Map width in arcsec (default: the grid's field).
    pub size_arcsec: Option<f64>,
    /// Maps only, no curves (see [`crate::products::ProductOptions::maps_only`]). Not a
    /// setting: the trials of an "auto" strength set it.
    #[serde(skip)]
    pub maps_only: bool,
}

impl Default for ProductConfig {
    fn default() -> Self {
        Self {
            z_source: 2.0,
            pixels: 512,
            size_arcsec: None,
            maps_only: false,
        }
    }
}

impl ReconstructConfig {
    /// Parses a configuration file; errors name the file, line and column (once), and a text
    /// over [`crate::limits::MAX_JSON_BYTES`] is refused before parsing.
    pub fn from_json_str(text: &str, source_name: &str) -> Result<Self, ReconstructError> {
        TooLarge::check_bytes(source_name, InputKind::Config, text.len() as u64)?;
        if let Some(message) = crate::limits::not_an_object_message(text) {
            let source_name = source_name.to_string();
            return Err(ReconstructError::Config {
                source_name,
                message,
            });
        }
        let config: Self = serde_json::from_str(text).map_err(|e| ReconstructError::Config {
            source_name: source_name.to_string(),
            message: json_error_message(text, &e),
        })?;
        config.validate().map_err(|e| ReconstructError::Config {
            source_name: source_name.to_string(),
            message: e.to_string(),
        })?;
        Ok(config)
    }

    /// The prior width of the external shear this run fits: `grid.external_shear_sigma`, but
    /// none with the least-mass regulariser ([`Regulariser::Density`]). That one charges the
    /// grid for every unit of mass and the shear for nothing beyond its prior, so together
    /// they trade the map's mass for a shear (MACS J1149: a shear of 0.79 and an Einstein
    /// radius 12% too large, BENCHMARKS.md); the smoothness regularisers do not charge for
    /// mass itself. An "auto" strength tries it without a shear beside the others with one
    /// ([`super::strength_candidates`]).
    pub fn external_shear_fitted(&self) -> Option<f64> {
        match self.objective.regulariser {
            Regulariser::Density => None,
            _ => self.grid.external_shear_sigma,
        }
    }

    /// The paper's method: QADP stopped after `solver.iterations` on the source-plane chi^2,
    /// with no regulariser and every member factor free (what `wslap paper` reproduces).
    pub fn paper() -> Self {
        let mut c = Self::default();
        c.solver.method = SolverMethod::Qadp;
        c.objective = ObjectiveConfig::paper();
        c.members.c_prior_sigma_unmeasured = None;
        c.grid.external_shear_sigma = None;
        c
    }

    /// Checks every block.
    pub fn validate(&self) -> Result<(), ReconstructError> {
        self.grid.validate()?;
        self.members.validate()?;
        self.constraints.validate()?;
        self.system.validate()?;
        self.objective.validate()?;
        self.shear.validate()?;
        self.solver_settings().validate()?;
        if self.solver.method == SolverMethod::Exact {
            let o = &self.objective;
            let auto = o.strength.value().is_none();
            let zero = o.strength.value() == Some(0.0) || (auto && o.candidates.contains(&0.0));
            let none = match auto {
                true => o.auto_regularisers.contains(&Regulariser::None),
                false => o.regulariser == Regulariser::None,
            };
            if none || zero {
                return Err(ReconstructError::from(BadFieldValue::new(
                    "objective.strength",
                    0.0,
                    "the exact solver needs a regulariser with a positive strength: \
                             without one the data leave the map undetermined (use solver.method \
                             \"qadp\" for the paper's early stop)",
                )));
            }
        }
        let s = &self.solver;
        if !(s.start_cell_mass_msun.is_finite()
            && s.start_cell_mass_msun > 0.0
            && s.start_cell_mass_msun <= 1e18)
        {
            return Err(ReconstructError::from(BadFieldValue::new(
                "solver.start_cell_mass_msun",
                s.start_cell_mass_msun,
                "the start mass must be positive, at most 1e18 Msun: a cell that starts at 0 \
                 stays at 0",
            )));
        }
        if !(s.start_c.is_finite() && s.start_c > 0.0 && s.start_c <= 1e3) {
            return Err(ReconstructError::from(BadFieldValue::new(
                "solver.start_c",
                s.start_c,
                "the start C must be positive, at most 1000: a factor that starts at 0 stays \
                 at 0",
            )));
        }
        let p = &self.products;
        if !(p.z_source.is_finite() && p.z_source > 0.0 && p.z_source < 20.0) {
            return Err(ReconstructError::from(BadFieldValue::new(
                "products.z_source",
                p.z_source,
                "a source redshift must be in (0, 20)",
            )));
        }
        if !(16..=crate::products::MAX_PIXELS).contains(&p.pixels) {
            return Err(ReconstructError::from(BadFieldValue::new(
                "products.pixels",
                p.pixels as f64,
                "the map side must be 16 to 8192 pixels",
            )));
        }
        if let Some(w) = p.size_arcsec {
            if !(w.is_finite() && w > 0.0 && w <= 36_000.0) {
                return Err(ReconstructError::from(BadFieldValue::new(
                    "products.size_arcsec",
                    w,
                    "the map width must be in (0, 36000] arcsec",
                )));
            }
        }
        Ok(())
    }

    /// Checks that the redshifts these settings give sources, `products.z_source` (the
    /// curves') and `constraints.default_z`, lie behind a lens at `z_lens`: known before any
    /// data is read, so a run refuses them at once.
    pub fn check_behind_lens(&self, z_lens: f64) -> Result<(), BadFieldValue> {
        let fields = [
            ("products.z_source", Some(self.products.z_source)),
            ("constraints.default_z", self.constraints.default_z),
            (
                "constraints.free_z_prior[1]",
                self.constraints.free_z_prior.map(|p| p[1]),
            ),
        ];
        for (field, z) in fields {
            if let Some(z) = z.filter(|&z| z.is_nan() || z <= z_lens) {
                return Err(BadFieldValue::new(
                    field,
                    z,
                    format!("a source must be behind the lens: z_s > z_lens = {z_lens}"),
                ));
            }
        }
        Ok(())
    }

    /// The solver run settings of this configuration.
    pub fn solver_settings(&self) -> SolverSettings {
        SolverSettings {
            iterations: self.solver.iterations,
            report_every: self.solver.report_every,
            // One thread count for the whole run (`system.threads`).
            threads: self.system.threads,
            keep_iterates: self.solver.keep_iterates,
        }
    }
}

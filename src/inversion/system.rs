//! The linear system `Theta = Gamma X` of WSLAP+ ([method §3], paper eqs. 4-7) and
//! its normal equations `A = Gamma^T W Gamma`, `b = -Gamma^T W Theta` (section 5).
//!
//! Unknowns `X = (m_1..m_Nc, C_1..C_L, beta_x,1..beta_x,Ns, beta_y,1..beta_y,Ns)`. Pixel `i`
//! of system `s` gives two rows, `2i` (x) and `2i + 1` (y):
//!
//! ```text
//! theta_x,i + S = f(z_s) [ sum_j Ux_ij m_j + sum_l C_l ax_l(theta_i) ] + beta'_x,s
//! theta_y,i + S = f(z_s) [ sum_j Uy_ij m_j + sum_l C_l ay_l(theta_i) ] + beta'_y,s
//! ```
//!
//! - `U_ij` = deflection (arcsec) at pixel `i` of cell `j` holding one mass unit:
//!   `K mu / D_l` times the unit Gaussian deflection, with the mass unit `mu` (default
//!   1e12 Msun: a 1e15 Msun cluster on a 32 x 32 grid has cells of ~1e12) so that the cell
//!   unknowns are O(1); the mass of cell `j` is `X_j mu`.
//! - `a_l` = fiducial deflection of galaxy layer `l` (arcsec, `D_ls/D_s = 1`).
//! - `S` = frame shift (arcsec) added to every row so that every `beta' = beta + S` is
//!   positive for the non-negative solver; the source position is `beta = X_beta - S`.
//!   Default `S = max_i max(|theta_x,i|, |theta_y,i|) + field width`, rounded up to an arcsec:
//!   `|beta| <= |theta| + |alpha|` and no deflection in the field exceeds its width.
//! - `S` does not change the minimiser, but it changes the path of QADP, whose multiplicative
//!   update is not invariant under a shift of the unknowns, and so the early-stopped answer.
//!   Measured on `wslap paper` (8000 iterations; median deflection error in the arc region of
//!   case (ii)): S = 120" gives 2.09", the default (~240") 0.98", S = 500" 1.97". Eliminating
//!   the betas (each at its best value for the current masses, [method §5]'s other
//!   option) lets QADP reach the over-fitted "point-source solution" within the 8000
//!   iterations (8.8", grid mass +33% in case (iii)), so the betas stay unknowns here.
//!
//! `Gamma` is never held whole: rows are made in blocks of at most `block_mbytes` and fed to
//! the normal-equation accumulator; cell columns are filled by all threads natively.
//!
//! [method §3]: crate::method#3-the-linear-system
//! [method §5]: crate::method#5-the-solver-qadp

use std::ops::Range;
use std::sync::Arc;

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::cells::{CellGrid, GridError, GridMass};
use super::constraints::ConstraintSet;
use super::members::{member_layers_with, Layer};
use super::regularise::{cell_penalty, Regulariser};
use super::shear::{kappa_gamma, ShearSet};
use crate::cosmology::{CosmologyError, LensPlane};
use crate::profiles::{cell_unit_deflection, gaussian_unit_hessian};
use crate::profiles::{Lens, MassComponent};
use crate::solver::{NormalEquations, SolverError};
use crate::units::point_mass_deflection_arcsec2;

/// [`LinearSystem::measurability_warnings`] warns of a member layer whose independent share
/// is below this: its factor's uncertainty is then over 30 times (`1 / sqrt(share)`) what it
/// would be if the grid could not mimic the layer. Measured on the paper's simulated cluster
/// (2885 arc pixels, 32 x 32 cells): 1.2e-5 for its true galaxies, 6.6e-5 to 1.2e-4 for the
/// members of its `members.cat` (the app's example and `wslap reconstruct`).
pub const LAYER_SHARE_WARN: f64 = 1e-3;

/// Whether a layer's independent share ([`LinearSystem::layer_independence`]) says the data
/// hardly measure its factor: below [`LAYER_SHARE_WARN`].
fn hardly_measured(share: f64) -> bool {
    share < LAYER_SHARE_WARN
}

/// How many prior widths from 1 a layer's fitted factor `C` may end before the run says so
/// ([`LinearSystem::prior_pull_warnings`]).
pub const PRIOR_PULL_SIGMA: f64 = 3.0;

/// What can go wrong building or using the linear system.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SystemError {
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error("system {system}: {source}")]
    Redshift {
        system: String,
        #[source]
        source: CosmologyError,
    },
    #[error("layer \"{layer}\": its deflection at ({x}, {y}) arcsec is not finite")]
    LayerNotFinite { layer: String, x: f64, y: f64 },
    #[error("{what} has {got} values, expected {expected}")]
    Length {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("normal equations: {0}")]
    Accumulate(#[from] SolverError),
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// Settings of the linear system (the `system` block of an inversion configuration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SystemConfig {
    /// Mass unit of the cell unknowns in Msun (default 1e12). Allowed [1e3, 1e18].
    pub mass_unit_msun: f64,
    /// Frame shift `S` in arcsec (default: automatic, see the module documentation, which
    /// also says how `S` changes QADP's early-stopped answer). Allowed [0, 1e6].
    pub theta_shift_arcsec: Option<f64>,
    /// Largest block of `Gamma` rows held at once, in MB (default 64). Allowed [0.001, 1e5].
    pub block_mbytes: f64,
    /// Threads for the whole reconstruction (rows, normal equations, QADP passes, maps, image
    /// search); 0 (default) = all available (always 1 on wasm32). Allowed 0..=1024.
    pub threads: usize,
}

impl Default for SystemConfig {
    fn default() -> Self {
        Self {
            mass_unit_msun: 1.0e12,
            theta_shift_arcsec: None,
            block_mbytes: 64.0,
            threads: 0,
        }
    }
}

impl SystemConfig {
    /// Checks every field against the range in its documentation.
    pub fn validate(&self) -> Result<(), SystemError> {
        let bad = |field: &str, value, reason| {
            SystemError::from(crate::error::BadFieldValue::new(
                format!("system.{field}"),
                value,
                reason,
            ))
        };
        let m = self.mass_unit_msun;
        if !(m.is_finite() && (1e3..=1e18).contains(&m)) {
            return Err(bad("mass_unit_msun", m, "must be in [1e3, 1e18] Msun"));
        }
        if let Some(s) = self.theta_shift_arcsec {
            if !(s.is_finite() && (0.0..=1e6).contains(&s)) {
                return Err(bad("theta_shift_arcsec", s, "must be in [0, 1e6] arcsec"));
            }
        }
        let mb = self.block_mbytes;
        if !(mb.is_finite() && (1e-3..=1e5).contains(&mb)) {
            return Err(bad("block_mbytes", mb, "must be in [0.001, 1e5] MB"));
        }
        if self.threads > 1024 {
            return Err(bad(
                "threads",
                self.threads as f64,
                "must be 0 (all cores) to 1024",
            ));
        }
        Ok(())
    }
}

/// What one column of `Gamma` (one unknown) is. In JSON tagged by `"kind"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ColumnInfo {
    /// Mass of grid cell `index`, in units of `mass_unit_msun`.
    Cell {
        index: usize,
        center: DVec2,
        size_arcsec: f64,
        sigma_arcsec: f64,
    },
    /// Scale `C_l` of galaxy layer `index` (dimensionless).
    Layer { index: usize, name: String },
    /// `beta'_x` (arcsec, shifted) of system `system`.
    BetaX { system: usize, id: String },
    /// `beta'_y` (arcsec, shifted) of system `system`.
    BetaY { system: usize, id: String },
}

/// Rows of `Gamma` for a range of pixels (or the prior rows): `gamma` row-major (`rows x n_columns`),
/// `theta` the shifted positions and `weights` the row weights (1/arcsec^2).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowBlock {
    pub gamma: Vec<f64>,
    pub theta: Vec<f64>,
    pub weights: Vec<f64>,
}

/// The terms of the objective beyond the paper's source-plane chi^2 (see the `regularise`
/// module): per-pixel image-plane transforms of the rows and a regulariser on the cells.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjectiveTerms {
    /// Per constraint pixel, the 2 x 2 matrix `[m00, m01, m10, m11]` applied to its two rows
    /// of `Gamma` and `Theta` (the capped inverse Jacobian); empty: none.
    pub pixel_transforms: Vec<[f64; 4]>,
    /// The regulariser on the cells.
    pub regulariser: Regulariser,
    /// Its relative strength (used when `penalty_weight` is `None`).
    pub strength: f64,
    /// The absolute weight `lambda` of the regulariser, to keep one objective while the
    /// transforms change; `None`: `strength * tr(A_cells) / tr(R)` of this system.
    pub penalty_weight: Option<f64>,
    /// Least mass only: the member layers' mass in the cells
    /// ([`LinearSystem::member_mass_in_cells`]), resolved by the first build and carried, like
    /// `penalty_weight`, to the systems built again on the same grid and layers (the
    /// image-plane passes); `None`, or a length that does not fit: computed by the build.
    pub member_mass_in_cells: Option<std::sync::Arc<[f64]>>,
}

/// The assembled system: column layout, normal equations and what is needed to make rows and
/// the reconstructed lens again.
#[derive(Debug, Clone)]
pub struct LinearSystem {
    pub columns: Vec<ColumnInfo>,
    /// Rows of `Gamma`: `2 x` number of pixels, `2 x` number of weak-lensing galaxies, then
    /// one per layer with a prior on `C_l`.
    pub n_rows: usize,
    /// Frame shift `S` in arcsec.
    pub theta_shift_arcsec: f64,
    /// Mass unit of the cell unknowns in Msun.
    pub mass_unit_msun: f64,
    /// `A = Gamma^T W Gamma`, row-major `n x n` (`n = columns.len()`).
    pub a: Vec<f64>,
    /// `b = -Gamma^T W Theta`.
    pub b: Vec<f64>,
    /// `Theta^T W Theta`: `chi^2(X) = 2 phi(X) + Theta^T W Theta`.
    pub theta_w_theta: f64,
    pub grid: CellGrid,
    pub layers: Vec<Layer>,
    pub constraints: ConstraintSet,
    /// The weak-lensing galaxies (empty without an arclet catalogue; the `shear` module).
    pub shear: ShearSet,
    /// `f(z_s) = D_ls / D_s` per system.
    pub distance_ratios: Vec<f64>,
    /// `D_l` in Mpc.
    pub d_l_mpc: f64,
    /// The objective's terms beyond the source-plane chi^2, with `penalty_weight` resolved.
    pub terms: ObjectiveTerms,
    /// [`Self::layer_independence`], computed at its first use.
    layer_independence: std::sync::OnceLock<Vec<Option<f64>>>,
    /// `a_l(theta_i)` for pixel `i`, layer `l` at `[i * L + l]`.
    layer_deflections: Vec<DVec2>,
    /// Hessian of layer `l` at galaxy `g` at `[g * L + l]` (`D_ls/D_s = 1`).
    shear_layer_hessians: Vec<[f64; 3]>,
    threads: usize,
    rows_per_block: usize,
}

/// Points per side of a cell's square on which [`LinearSystem::member_mass_in_cells`]
/// integrates a member layer's convergence.
const MEMBER_MASS_SAMPLES: usize = 6;

/// Calls `fill(first_item, chunk)` on consecutive chunks of `out` (`stride` values per item),
/// split over `threads` threads (in this thread when 1).
fn parallel_fill<F>(out: &mut [f64], stride: usize, threads: usize, fill: F)
where
    F: Fn(usize, &mut [f64]) + Sync,
{
    let items = out.len() / stride.max(1);
    if threads <= 1 || items < 2 {
        fill(0, out);
        return;
    }
    let per = items.div_ceil(threads);
    let chunks: Vec<(usize, &mut [f64])> = out.chunks_mut(per * stride).enumerate().collect();
    crate::threads::for_each(chunks, threads, |(k, chunk)| fill(k * per, chunk));
}

impl LinearSystem {
    /// Builds the system of [method §3] for `grid`, `layers` and `constraints` on
    /// `plane` and accumulates its normal equations block by block.
    ///
    /// [method §3]: crate::method#3-the-linear-system
    pub fn build(
        grid: &CellGrid,
        layers: &[Layer],
        constraints: &ConstraintSet,
        plane: &LensPlane,
        config: &SystemConfig,
    ) -> Result<Self, SystemError> {
        Self::build_with(
            grid,
            layers,
            constraints,
            plane,
            config,
            ObjectiveTerms::default(),
        )
    }

    /// As [`Self::build`], with the image-plane transforms and the regulariser of `terms`.
    pub fn build_with(
        grid: &CellGrid,
        layers: &[Layer],
        constraints: &ConstraintSet,
        plane: &LensPlane,
        config: &SystemConfig,
        terms: ObjectiveTerms,
    ) -> Result<Self, SystemError> {
        let no_shear = ShearSet::default();
        Self::build_with_shear(grid, layers, constraints, &no_shear, plane, config, terms)
    }

    /// As [`Self::build_with`], with the weak-lensing rows of `shear` after the pixels' rows
    /// (the `shear` module).
    pub fn build_with_shear(
        grid: &CellGrid,
        layers: &[Layer],
        constraints: &ConstraintSet,
        shear: &ShearSet,
        plane: &LensPlane,
        config: &SystemConfig,
        terms: ObjectiveTerms,
    ) -> Result<Self, SystemError> {
        config.validate()?;
        if !terms.pixel_transforms.is_empty()
            && terms.pixel_transforms.len() != constraints.pixels.len()
        {
            return Err(SystemError::Length {
                what: "pixel transforms",
                expected: constraints.pixels.len(),
                got: terms.pixel_transforms.len(),
            });
        }
        let distance_ratios = constraints
            .systems
            .iter()
            .map(|s| {
                plane
                    .distance_ratio(s.z)
                    .map_err(|source| SystemError::Redshift {
                        system: s.id.clone(),
                        source,
                    })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        let columns = column_layout(grid, layers, constraints);
        let n_cols = columns.len();
        let theta_shift_arcsec = config.theta_shift_arcsec.unwrap_or_else(|| {
            let reach = constraints
                .pixels
                .iter()
                .map(|p| p.position.abs().max_element())
                .fold(0.0, f64::max);
            (reach + grid.width_arcsec).ceil()
        });
        let threads = crate::threads::count(config.threads, constraints.pixels.len(), 1);
        let layer_deflections = layer_deflections(layers, constraints, threads)?;
        let shear_layer_hessians = layer_hessians(layers, shear)?;
        let bytes_per_pixel = 2.0 * n_cols as f64 * 8.0;
        let rows_per_block =
            ((config.block_mbytes * 1e6 / bytes_per_pixel).floor() as usize).max(1);
        let mut system = Self {
            columns,
            n_rows: 2 * constraints.pixels.len()
                + 2 * shear.len()
                + layers.iter().filter(|l| l.prior_sigma.is_some()).count(),
            theta_shift_arcsec,
            mass_unit_msun: config.mass_unit_msun,
            a: Vec::new(),
            b: Vec::new(),
            theta_w_theta: 0.0,
            grid: grid.clone(),
            layers: layers.to_vec(),
            constraints: constraints.clone(),
            shear: shear.clone(),
            distance_ratios,
            d_l_mpc: plane.d_l_mpc,
            terms,
            layer_independence: std::sync::OnceLock::new(),
            layer_deflections,
            shear_layer_hessians,
            threads,
            rows_per_block,
        };
        system.accumulate_normal()?;
        Ok(system)
    }

    /// Per layer, the share of its deflection at the constraints (weighted, as in `A`) that no
    /// combination of the other unknowns reproduces ([`crate::solver::column_independence`]):
    /// near 0, the data do not measure `C_l`. `None` above
    /// [`crate::solver::INDEPENDENCE_MAX_UNKNOWNS`] unknowns. Factorises `A` at the first call
    /// (not in [`Self::build`]: the systems of a refined grid's earlier levels never need it).
    /// The share is that of the data: the regulariser, which would let no cell mimic a
    /// layer for free, and the priors on `C` are taken out of `A` first.
    pub fn layer_independence(&self) -> &[Option<f64>] {
        self.layer_independence.get_or_init(|| {
            let layer_cols: Vec<usize> = self.layer_columns().collect();
            let n = self.n_columns();
            let lambda = self.terms.penalty_weight.unwrap_or(0.0);
            let priors = self.layers.iter().any(|l| l.prior_sigma.is_some());
            if (lambda == 0.0 && !priors) || layer_cols.is_empty() {
                return crate::solver::column_independence(&self.a, n, &layer_cols);
            }
            let mut data = self.a.clone();
            for (col, layer) in self.layer_columns().zip(&self.layers) {
                if let Some(sigma) = layer.prior_sigma {
                    data[col * n + col] -= 1.0 / (sigma * sigma);
                }
            }
            let r = cell_penalty(&self.grid, self.terms.regulariser);
            self.add_scaled_penalty(&mut data, &r, -lambda);
            crate::solver::column_independence(&data, n, &layer_cols)
        })
    }

    /// Adds the prior `C_l = 1 +- sigma` to layer `l` that has none (as the row of
    /// [`Self::prior_rows`], straight into `A`, `b` and `Theta^T W Theta`); the layer keeps it
    /// in `layers` for the systems built from them later.
    pub fn add_layer_prior(&mut self, l: usize, sigma: f64) {
        if self.layers[l].prior_sigma.is_some() {
            return;
        }
        let n = self.n_columns();
        let col = self.layer_columns().start + l;
        let w = 1.0 / (sigma * sigma);
        self.a[col * n + col] += w;
        self.b[col] -= w;
        self.theta_w_theta += w;
        self.n_rows += 1;
        self.layers[l].prior_sigma = Some(sigma);
    }

    /// True when these constraints hardly measure the member factors `C`: when there are
    /// layers and [`Self::measurability_warnings`] has something to say.
    pub fn members_unmeasured(&self) -> bool {
        self.layers.iter().any(|l| l.kind.is_galaxies())
            && !self.measurability_warnings().is_empty()
    }

    /// One sentence per member layer (not an external shear's) with a prior whose factor `C`
    /// in the solution `x` ends
    /// more than [`PRIOR_PULL_SIGMA`] of the prior's width from 1: "fitted with a prior" (the
    /// warning of [`Self::measurability_warnings`], said before the solve) is then not "at 1"
    /// (the HFF catalogues end at C = 0.6 - 0.7 with the prior 1 +- 0.1).
    ///
    /// Where the data hardly measure the layer's factor (as [`Self::measurability_warnings`]
    /// said before the solve), the sentence says that the regulariser, weighed against the
    /// prior, set it: the images would fit as well at 1 with the grid standing in, so
    /// "the images make the members lighter" would contradict the warning before it.
    pub fn prior_pull_warnings(&self, x: &[f64]) -> Vec<String> {
        let Some(factors) = x.get(self.layer_columns()) else {
            return Vec::new();
        };
        // As `measurability_warnings` judged them (its cached shares; none with fewer rows).
        let measured: Vec<bool> = match self.n_rows < self.n_columns() {
            true => vec![false; self.layers.len()],
            false => self
                .layer_independence()
                .iter()
                .map(|share| !share.is_some_and(hardly_measured))
                .collect(),
        };
        member_layers_with(&self.layers, factors.iter().zip(measured))
            .filter_map(|(layer, (&c, measured))| {
                let sigma = layer.prior_sigma?;
                let pull = (c - 1.0) / sigma;
                (pull.abs() > PRIOR_PULL_SIGMA).then(|| {
                    let (side, mass) = match pull < 0.0 {
                        true => ("below", "lighter"),
                        false => ("above", "heavier"),
                    };
                    let why = match measured {
                        true => format!("the images and the regulariser make the members {mass}"),
                        false => format!(
                            "the images hardly measure C (the grid can stand in for the \
                             members), so the regulariser, weighed against the prior, sets it \
                             and makes the members {mass}"
                        ),
                    };
                    format!(
                        "member layer \"{}\": C ends at {c:.2}, {:.1} sigma {side} its prior C = \
                         1 +- {sigma}: {why} than the luminosity law as set \
                         (members.mass_to_light), and the map keeps the fitted C",
                        layer.name,
                        pull.abs()
                    )
                })
            })
            .collect()
    }

    /// What these constraints cannot measure, in words: fewer rows than unknowns (many maps
    /// then fit the data exactly, and the start and the iteration count choose among them;
    /// point images on the default 32 x 32 grid are always in this case), or else a member
    /// layer whose deflection the other unknowns reproduce all but [`LAYER_SHARE_WARN`] of.
    pub fn measurability_warnings(&self) -> Vec<String> {
        let (rows, unknowns) = (self.n_rows, self.n_columns());
        let regularised = self.terms.penalty_weight.unwrap_or(0.0) > 0.0;
        let held = |layer: &Layer| match layer.prior_sigma {
            // Said before the solve: the prior is given, where C ends is the run's to say
            // (the data and the regulariser can still pull it several sigma away, said then).
            Some(sigma) => format!(
                "it is fitted with a prior C = 1 +- {sigma}, which the regulariser can outweigh"
            ),
            None if regularised => "nothing holds it (members.c_prior_sigma would)".to_string(),
            None => "the start and the iteration count set it".to_string(),
        };
        if rows < unknowns {
            let members = match self.layers.iter().find(|l| l.kind.is_galaxies()) {
                None => String::new(),
                Some(layer) => format!(
                    ", and the member factors C are not measured: {}",
                    held(layer)
                ),
            };
            let chooser = if regularised {
                "the regulariser (the objective block) chooses the smoothest of the maps that fit them"
            } else {
                "the start and the iteration count choose among the maps that fit them"
            };
            let shear = match self.layers.iter().any(|l| !l.kind.is_galaxies()) {
                true => ", external shear",
                false => "",
            };
            // The rows as `new` and `add_layer_prior` count them: the images' (or arc
            // pixels'), the arclets' and one per layer prior (C's, the external shear's).
            let images = 2 * self.constraints.pixels.len();
            let priors = self
                .layers
                .iter()
                .filter(|l| l.prior_sigma.is_some())
                .count();
            let arclets = rows.saturating_sub(images + priors);
            let mut counted = vec![format!("{images} from the images or arc pixels, two each")];
            if arclets > 0 {
                counted.push(format!("{arclets} from the arclets"));
            }
            if priors > 0 {
                counted.push(format!(
                    "{priors} from the priors on the member factors and the external shear"
                ));
            }
            let counted = counted.join(", ");
            return vec![format!(
                "{rows} constraint rows ({counted}) for {unknowns} unknowns \
                 (cell masses, member factors{shear}, source positions): the data cannot fix the mass \
                 map on their own; {chooser}{members}. Arc pixels or ellipses, or a coarser \
                 grid, give the data more say"
            )];
        }
        member_layers_with(&self.layers, self.layer_independence())
            .filter_map(|(layer, share)| {
                let share = share.filter(|&s| hardly_measured(s))?;
                Some(format!(
                    "member layer \"{}\": the grid cells and source positions reproduce all but \
                     {share:.1e} of its deflection at the constraints, so the data hardly \
                     measure its factor C: {}",
                    layer.name,
                    held(layer)
                ))
            })
            .collect()
    }

    /// Number of unknowns.
    pub fn n_columns(&self) -> usize {
        self.columns.len()
    }

    /// Columns of the cell masses.
    pub fn cell_columns(&self) -> Range<usize> {
        0..self.grid.len()
    }

    /// The order in which the solver stores the columns: the cells along a Hilbert curve
    /// through their centres, then the other columns (see
    /// [`crate::solver::QadpProblem::with_order`]; only the speed depends on it).
    pub fn solver_order(&self) -> Vec<usize> {
        let centres: Vec<[f64; 2]> = self
            .grid
            .cells
            .iter()
            .map(|c| [c.center.x, c.center.y])
            .collect();
        let mut order = crate::solver::locality_order(&centres);
        order.extend(self.grid.len()..self.n_columns());
        order
    }

    /// Columns of the layer scales `C_l`.
    pub fn layer_columns(&self) -> Range<usize> {
        let start = self.grid.len();
        start..start + self.layers.len()
    }

    /// Columns of `beta'_x` (then `beta'_y` follow in [`Self::beta_y_columns`]).
    pub fn beta_x_columns(&self) -> Range<usize> {
        let start = self.grid.len() + self.layers.len();
        start..start + self.constraints.systems.len()
    }

    /// Columns of `beta'_y`.
    pub fn beta_y_columns(&self) -> Range<usize> {
        let start = self.beta_x_columns().end;
        start..start + self.constraints.systems.len()
    }

    /// Pixels per block of rows (each pixel is two rows).
    pub fn pixels_per_block(&self) -> usize {
        self.rows_per_block
    }

    /// `K mu f / D_l`: the deflection (arcsec) per unit Gaussian deflection and per cell
    /// unknown, for a source with distance ratio `f`.
    fn cell_scale(&self, f: f64) -> f64 {
        point_mass_deflection_arcsec2() * self.mass_unit_msun / self.d_l_mpc * f
    }

    /// Rows `2 p0 .. 2 p1` of `Gamma`, `Theta` and `W` for pixels `p0..p1` into `out`
    /// (resized; see [`RowBlock`]).
    pub fn rows(&self, pixels: Range<usize>, out: &mut RowBlock) -> Result<(), SystemError> {
        let n_pix = self.constraints.pixels.len();
        if pixels.start > pixels.end || pixels.end > n_pix {
            return Err(SystemError::Length {
                what: "pixel range end",
                expected: n_pix,
                got: pixels.end,
            });
        }
        let n_cols = self.n_columns();
        let count = pixels.len();
        out.gamma.clear();
        out.gamma.resize(2 * count * n_cols, 0.0);
        out.theta.clear();
        out.weights.clear();
        let centers_x: Vec<f64> = self.grid.cells.iter().map(|c| c.center.x).collect();
        let centers_y: Vec<f64> = self.grid.cells.iter().map(|c| c.center.y).collect();
        let inv_2s2: Vec<f64> = self
            .grid
            .cells
            .iter()
            .map(|c| 0.5 / (c.sigma_arcsec * c.sigma_arcsec))
            .collect();
        let (n_cells, n_layers) = (self.grid.len(), self.layers.len());
        let (bx, by) = (self.beta_x_columns().start, self.beta_y_columns().start);
        let first = pixels.start;
        parallel_fill(&mut out.gamma, 2 * n_cols, self.threads, |k0, chunk| {
            for (k, two_rows) in chunk.chunks_exact_mut(2 * n_cols).enumerate() {
                let i = first + k0 + k;
                let pixel = &self.constraints.pixels[i];
                let f = self.distance_ratios[pixel.system];
                let scale = self.cell_scale(f);
                let (row_x, row_y) = two_rows.split_at_mut(n_cols);
                let p = pixel.position;
                for j in 0..n_cells {
                    let (gx, gy) =
                        cell_unit_deflection(p.x - centers_x[j], p.y - centers_y[j], inv_2s2[j]);
                    row_x[j] = scale * gx;
                    row_y[j] = scale * gy;
                }
                for l in 0..n_layers {
                    let a = self.layer_deflections[i * n_layers + l];
                    row_x[n_cells + l] = f * a.x;
                    row_y[n_cells + l] = f * a.y;
                }
                row_x[bx + pixel.system] = 1.0;
                row_y[by + pixel.system] = 1.0;
            }
        });
        for pixel in &self.constraints.pixels[pixels.clone()] {
            out.theta.push(pixel.position.x + self.theta_shift_arcsec);
            out.theta.push(pixel.position.y + self.theta_shift_arcsec);
            out.weights.push(pixel.weight);
            out.weights.push(pixel.weight);
        }
        if let Some(transforms) = self.terms.pixel_transforms.get(pixels) {
            for (k, m) in transforms.iter().enumerate() {
                let (row_x, row_y) =
                    out.gamma[2 * k * n_cols..(2 * k + 2) * n_cols].split_at_mut(n_cols);
                for (u, v) in row_x.iter_mut().zip(row_y.iter_mut()) {
                    (*u, *v) = (m[0] * *u + m[1] * *v, m[2] * *u + m[3] * *v);
                }
                let (tx, ty) = (out.theta[2 * k], out.theta[2 * k + 1]);
                out.theta[2 * k] = m[0] * tx + m[1] * ty;
                out.theta[2 * k + 1] = m[2] * tx + m[3] * ty;
            }
        }
        Ok(())
    }

    /// Rows `2 g0 .. 2 g1` of the weak-lensing block for galaxies `g0..g1` into `out` (resized;
    /// see [`RowBlock`]): `gamma_i = e_i (1 - kappa_0)`, the cells' and layers' shear at the
    /// galaxy times its `D_ls/D_s`, zeros in the beta columns, weight
    /// `1 / (sigma_e (1 - kappa_0))^2` (the `shear` module; [`ShearPoint::row_target`]).
    ///
    /// [`ShearPoint::row_target`]: super::ShearPoint::row_target
    pub fn shear_rows(
        &self,
        galaxies: Range<usize>,
        out: &mut RowBlock,
    ) -> Result<(), SystemError> {
        let n_gal = self.shear.len();
        if galaxies.start > galaxies.end || galaxies.end > n_gal {
            return Err(SystemError::Length {
                what: "galaxy range end",
                expected: n_gal,
                got: galaxies.end,
            });
        }
        let n_cols = self.n_columns();
        out.gamma.clear();
        out.gamma.resize(2 * galaxies.len() * n_cols, 0.0);
        out.theta.clear();
        out.weights.clear();
        let cells = &self.grid.cells;
        let (n_cells, n_layers) = (self.grid.len(), self.layers.len());
        let first = galaxies.start;
        parallel_fill(&mut out.gamma, 2 * n_cols, self.threads, |k0, chunk| {
            for (k, two_rows) in chunk.chunks_exact_mut(2 * n_cols).enumerate() {
                let g = first + k0 + k;
                let point = &self.shear.points[g];
                let f = point.distance_ratio;
                let scale = self.cell_scale(f);
                let (row_1, row_2) = two_rows.split_at_mut(n_cols);
                let p = point.position;
                for (j, cell) in cells.iter().enumerate() {
                    let d = p - cell.center;
                    let h = gaussian_unit_hessian(d.x, d.y, cell.sigma_arcsec);
                    let [_, g1, g2] = kappa_gamma(h);
                    row_1[j] = scale * g1;
                    row_2[j] = scale * g2;
                }
                for l in 0..n_layers {
                    let [_, g1, g2] = kappa_gamma(self.shear_layer_hessians[g * n_layers + l]);
                    row_1[n_cells + l] = f * g1;
                    row_2[n_cells + l] = f * g2;
                }
            }
        });
        for point in &self.shear.points[galaxies] {
            let (target, weight) = point.row_target();
            out.theta.extend([target.x, target.y]);
            out.weights.extend([weight, weight]);
        }
        Ok(())
    }

    /// The rows after the pixels' rows: `C_l = 1` with weight `1 / sigma_l^2` for each layer
    /// `l` that has a prior (`Layer::prior_sigma`), in layer order.
    pub fn prior_rows(&self) -> RowBlock {
        let n_cols = self.n_columns();
        let mut out = RowBlock::default();
        for (column, layer) in self.layer_columns().zip(&self.layers) {
            if let Some(sigma) = layer.prior_sigma {
                let mut row = vec![0.0; n_cols];
                row[column] = 1.0;
                out.gamma.extend(row);
                out.theta.push(1.0);
                out.weights.push(1.0 / (sigma * sigma));
            }
        }
        out
    }

    /// Fills `a`, `b` and `theta_w_theta` from blocks of rows.
    fn accumulate_normal(&mut self) -> Result<(), SystemError> {
        let n = self.n_columns();
        let mut acc = NormalEquations::new(n)?;
        let mut theta_w_theta = 0.0;
        let mut block = RowBlock::default();
        // Adds a block of rows to the normal equations; returns its `theta^T W theta`.
        let mut add = |block: &RowBlock| -> Result<f64, SystemError> {
            acc.add_rows(&block.gamma, &block.weights, &block.theta)?;
            Ok(block
                .theta
                .iter()
                .zip(&block.weights)
                .map(|(t, w)| w * t * t)
                .sum::<f64>())
        };
        let per = self.rows_per_block;
        let blocks = |len: usize| (0..len).step_by(per).map(move |s| s..(s + per).min(len));
        for range in blocks(self.constraints.pixels.len()) {
            self.rows(range, &mut block)?;
            theta_w_theta += add(&block)?;
        }
        for range in blocks(self.shear.len()) {
            self.shear_rows(range, &mut block)?;
            theta_w_theta += add(&block)?;
        }
        let prior = self.prior_rows();
        acc.add_rows(&prior.gamma, &prior.weights, &prior.theta)?;
        theta_w_theta += prior.weights.iter().sum::<f64>();
        let (mut a, b) = acc.finish();
        self.add_penalty(&mut a);
        self.a = a;
        self.b = b;
        self.theta_w_theta = theta_w_theta;
        Ok(())
    }

    /// Adds `lambda R` to `a` and records `lambda` in `terms.penalty_weight` (see the
    /// `regularise` module).
    fn add_penalty(&mut self, a: &mut [f64]) {
        if self.terms.regulariser == Regulariser::None {
            self.terms.penalty_weight = Some(0.0);
            self.terms.member_mass_in_cells = None;
            return;
        }
        // The member masses are kept exactly when the regulariser charges them, so that
        // `add_scaled_penalty` (here and in `layer_independence`) reads them from the terms.
        let fits = |p: &[f64]| p.len() == self.grid.len() * self.layers.len();
        self.terms.member_mass_in_cells = match self.charges_members() {
            false => None,
            true => match self.terms.member_mass_in_cells.take() {
                Some(p) if fits(&p) => Some(p),
                _ => Some(self.member_mass_in_cells().into()),
            },
        };
        let n_cells = self.grid.len();
        let r = cell_penalty(&self.grid, self.terms.regulariser);
        let n = self.columns.len();
        let terms = &mut self.terms;
        let lambda = *terms.penalty_weight.get_or_insert_with(|| {
            let trace_a: f64 = (0..n_cells).map(|j| a[j * n + j]).sum();
            let trace_r: f64 = (0..n_cells).map(|j| r[j * n_cells + j]).sum();
            if trace_r > 0.0 {
                terms.strength * trace_a / trace_r
            } else {
                0.0
            }
        });
        self.add_scaled_penalty(a, &r, lambda);
    }

    /// Whether the regulariser charges the member layers too (least mass with galaxies).
    fn charges_members(&self) -> bool {
        self.terms.regulariser == Regulariser::Density
            && self.layers.iter().any(|l| l.kind.is_galaxies())
    }

    /// Adds `scale R` to `a`, `R` the regulariser's matrix over the unknowns: `r` (from
    /// [`cell_penalty`]) on the cells' block and, for least mass, the member layers' blocks
    /// too. Least mass charges the galaxies' mass as the cells': the member layer `l` at
    /// `C_l` counts as the cell masses `C_l P_jl` (its mass inside each cell's square,
    /// [`Self::member_mass_in_cells`]), so the regulariser is
    /// `(m + P C)^T R_cells (m + P C)`, the least total surface density at the cells'
    /// resolution. Without it the least mass moves the cells' mass into the members, which
    /// cost nothing (MACS J1149: `C` = 2.04 and an Einstein radius 25% too large).
    fn add_scaled_penalty(&self, a: &mut [f64], r: &[f64], scale: f64) {
        let (n, n_cells) = (self.columns.len(), self.grid.len());
        for j in 0..n_cells {
            for k in 0..n_cells {
                a[j * n + k] += scale * r[j * n_cells + k];
            }
        }
        // Set by `add_penalty` when (and only when) the regulariser charges the members.
        let Some(p) = self.terms.member_mass_in_cells.as_deref() else {
            return;
        };
        let cols = self.layer_columns();
        let layers = cols.len();
        // (R P)_jl at [j * layers + l].
        let mut rp = vec![0.0; n_cells * layers];
        for j in 0..n_cells {
            for k in 0..n_cells {
                let rjk = r[j * n_cells + k];
                for l in 0..layers {
                    rp[j * layers + l] += rjk * p[k * layers + l];
                }
            }
        }
        for j in 0..n_cells {
            for (l, c) in cols.clone().enumerate() {
                a[j * n + c] += scale * rp[j * layers + l];
                a[c * n + j] += scale * rp[j * layers + l];
            }
        }
        for (l, cl) in cols.clone().enumerate() {
            for (m, cm) in cols.clone().enumerate() {
                let ptrp: f64 = (0..n_cells)
                    .map(|j| p[j * layers + l] * rp[j * layers + m])
                    .sum();
                a[cl * n + cm] += scale * ptrp;
            }
        }
    }

    /// Per cell `j` and layer `l` at `[j * L + l]`: the mass of galaxy layer `l` at `C_l = 1`
    /// inside cell `j`'s square, in mass units (0 for an external shear's layers), by the
    /// midpoint rule on 6 x 6 points of the square (`MEMBER_MASS_SAMPLES`). Coarse (a galaxy's
    /// core falls between points), which a regulariser's weight on it tolerates.
    pub fn member_mass_in_cells(&self) -> Vec<f64> {
        let layers = self.layers.len();
        let mut p = vec![0.0; self.grid.len() * layers];
        if layers == 0 {
            return p;
        }
        // Sigma_cr at D_ls/D_s = 1 in mass units per arcsec^2: kappa 1 over the arcsec^2.
        let arcsec2_per_sr = crate::units::ARCSEC_PER_RAD * crate::units::ARCSEC_PER_RAD;
        let sigma_cr = crate::units::c2_over_4pi_g_msun_per_mpc() * self.d_l_mpc
            / arcsec2_per_sr
            / self.mass_unit_msun;
        let k = MEMBER_MASS_SAMPLES;
        parallel_fill(&mut p, layers, self.threads, |j0, chunk| {
            for (cell, row) in self.grid.cells[j0..].iter().zip(chunk.chunks_mut(layers)) {
                let h = cell.size_arcsec / k as f64;
                let corner = cell.center - DVec2::splat(cell.size_arcsec / 2.0);
                for (out, layer) in row.iter_mut().zip(&self.layers) {
                    if !layer.kind.is_galaxies() {
                        continue;
                    }
                    let kappa: f64 = (0..k * k)
                        .map(|i| {
                            let q = DVec2::new((i % k) as f64 + 0.5, (i / k) as f64 + 0.5);
                            layer.lens.kappa(corner + q * h)
                        })
                        .sum();
                    *out = kappa * h * h * sigma_cr;
                }
            }
        });
        p
    }

    /// Checks that `x` has one value per column.
    fn check_x(&self, x: &[f64]) -> Result<(), SystemError> {
        if x.len() != self.n_columns() {
            return Err(SystemError::Length {
                what: "solution X",
                expected: self.n_columns(),
                got: x.len(),
            });
        }
        Ok(())
    }

    /// Cell masses in Msun: `X_j mu`.
    pub fn cell_masses_msun(&self, x: &[f64]) -> Result<Vec<f64>, SystemError> {
        self.check_x(x)?;
        Ok(x[self.cell_columns()]
            .iter()
            .map(|m| m * self.mass_unit_msun)
            .collect())
    }

    /// Source positions `beta = X_beta' - S` in arcsec, per system.
    pub fn betas_arcsec(&self, x: &[f64]) -> Result<Vec<DVec2>, SystemError> {
        self.check_x(x)?;
        let (bx, by) = (self.beta_x_columns(), self.beta_y_columns());
        Ok(x[bx]
            .iter()
            .zip(&x[by])
            .map(|(&u, &v)| DVec2::new(u, v) - DVec2::splat(self.theta_shift_arcsec))
            .collect())
    }

    /// The grid part of the reconstructed lens for unknowns `x` (the cells' masses alone).
    pub fn grid_mass(&self, x: &[f64]) -> Result<GridMass, SystemError> {
        self.check_x(x)?;
        let k = point_mass_deflection_arcsec2() * self.mass_unit_msun / self.d_l_mpc;
        let b2 = x[self.cell_columns()].iter().map(|m| k * m).collect();
        Ok(GridMass::new(&self.grid, b2)?)
    }

    /// The mass model of solution `x` at `D_ls/D_s = 1`: the cells as Gaussians of mass
    /// `X_j mu` and each layer scaled by `C_l` (layers with `C_l = 0` left out).
    pub fn reconstructed_lens(&self, x: &[f64]) -> Result<Lens, SystemError> {
        let grid = self.grid_mass(x)?;
        let mut components: Vec<Box<dyn MassComponent>> = vec![Box::new(grid)];
        for (layer, &c) in self.layers.iter().zip(&x[self.layer_columns()]) {
            if c != 0.0 {
                components.push(Box::new(ScaledLens {
                    factor: c,
                    lens: Arc::clone(&layer.lens),
                }));
            }
        }
        Ok(Lens::new(components))
    }
}

/// A shared lens scaled by a constant (a galaxy layer times its `C_l`).
#[derive(Debug, Clone)]
pub struct ScaledLens {
    pub factor: f64,
    pub lens: Arc<Lens>,
}

impl MassComponent for ScaledLens {
    fn kappa(&self, p: DVec2) -> f64 {
        self.factor * self.lens.kappa(p)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        self.factor * self.lens.deflection(p)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        self.lens.hessian(p).map(|h| self.factor * h)
    }
    fn deflection_hessian(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        let (a, h) = self.lens.deflection_hessian(p);
        (self.factor * a, h.map(|v| self.factor * v))
    }
}

/// Column layout: cells, layers, `beta'_x` per system, `beta'_y` per system.
fn column_layout(
    grid: &CellGrid,
    layers: &[Layer],
    constraints: &ConstraintSet,
) -> Vec<ColumnInfo> {
    let mut columns: Vec<ColumnInfo> = grid
        .cells
        .iter()
        .enumerate()
        .map(|(index, c)| ColumnInfo::Cell {
            index,
            center: c.center,
            size_arcsec: c.size_arcsec,
            sigma_arcsec: c.sigma_arcsec,
        })
        .collect();
    columns.extend(
        layers
            .iter()
            .enumerate()
            .map(|(index, l)| ColumnInfo::Layer {
                index,
                name: l.name.clone(),
            }),
    );
    let systems = constraints.systems.iter().enumerate();
    columns.extend(systems.clone().map(|(system, s)| ColumnInfo::BetaX {
        system,
        id: s.id.clone(),
    }));
    columns.extend(systems.map(|(system, s)| ColumnInfo::BetaY {
        system,
        id: s.id.clone(),
    }));
    columns
}

/// The Hessian of every layer at every weak-lensing galaxy (`[g * L + l]`), checked finite.
fn layer_hessians(layers: &[Layer], shear: &ShearSet) -> Result<Vec<[f64; 3]>, SystemError> {
    let mut out = Vec::with_capacity(layers.len() * shear.len());
    for point in &shear.points {
        for layer in layers {
            let h = layer.lens.hessian(point.position);
            if !h.iter().all(|v| v.is_finite()) {
                return Err(SystemError::LayerNotFinite {
                    layer: layer.name.clone(),
                    x: point.position.x,
                    y: point.position.y,
                });
            }
            out.push(h);
        }
    }
    Ok(out)
}

/// `a_l(theta_i)` for every pixel and layer (`[i * L + l]`), checked finite.
fn layer_deflections(
    layers: &[Layer],
    constraints: &ConstraintSet,
    threads: usize,
) -> Result<Vec<DVec2>, SystemError> {
    let n_layers = layers.len();
    let n_pix = constraints.pixels.len();
    let mut flat = vec![0.0; 2 * n_layers * n_pix];
    if n_layers > 0 {
        parallel_fill(&mut flat, 2 * n_layers, threads, |i0, chunk| {
            for (k, out) in chunk.chunks_exact_mut(2 * n_layers).enumerate() {
                let p = constraints.pixels[i0 + k].position;
                for (l, layer) in layers.iter().enumerate() {
                    let a = layer.deflection(p);
                    out[2 * l] = a.x;
                    out[2 * l + 1] = a.y;
                }
            }
        });
    }
    let out: Vec<DVec2> = flat
        .chunks_exact(2)
        .map(|v| DVec2::new(v[0], v[1]))
        .collect();
    if let Some(k) = out.iter().position(|a| !a.is_finite()) {
        let p = constraints.pixels[k / n_layers].position;
        return Err(SystemError::LayerNotFinite {
            layer: layers[k % n_layers].name.clone(),
            x: p.x,
            y: p.y,
        });
    }
    Ok(out)
}

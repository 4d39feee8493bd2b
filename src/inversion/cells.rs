//! The cell grid: the free-form basis of WSLAP ([method §2] and [§3]).
//!
//! `N x N` square cells cover a square field; cell `j` carries a circular Gaussian of mass
//! `m_j` centred on the cell with width `s = cell_sigma_factor * cell_size`. Cells are numbered
//! row by row from the bottom-left corner, `j = row * N + column` (column along +x, row along
//! +y), as the maps of `crate::map` are.
//!
//! Default width: `s = 0.75` cell. Equal masses on a square lattice of spacing `h` give a
//! peak-to-peak ripple of about `8 exp(-2 pi^2 s^2 / h^2)` in the convergence: measured 5.9%
//! at `s = 0.5 h` ([method §2]: ~6%), 1.2e-4 at `s = 0.75 h` and 2e-8 at `s = h`
//! (tests/inversion/ checks that the default is smooth and 0.5 is not). 0.75 is the
//! narrowest width that is smooth, so it keeps the most resolution.
//!
//! The best width depends on the data. On the paper's simulated cluster (`wslap paper`, the
//! sweep in its report.md; 32 x 32 cells over 198") wider cells fit better: case (ii)'s median
//! deflection error is 2.70" at 0.5, 2.42" at 0.75, 1.73" at 1.0, 0.98" at 1.25, 1.13" at 1.5
//! and 2.27" at 2.0 cells, so `wslap paper` and the app's example of that cluster use 1.25. On
//! the synthetic lens of tests/inversion/reconstruct.rs (16 x 16 cells) 1.25 doubles the image-plane rms
//! (1.26" to 2.40"), so the general default stays at the smooth minimum.
//!
//! [method §2]: crate::method#2-mass-components
//! [§3]: crate::method#3-the-linear-system

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::cells_fft::{self, MapPlan};
use crate::map::LensMaps;
use crate::map::MapGeometry;
use crate::profiles::cell_unit_deflection;

/// What can be wrong with a grid setting or a refinement request.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GridError {
    /// `grid.<field> = value` is outside its allowed range.
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    /// The field must be sized from positions but none were given.
    #[error("grid: no image positions to size the field from (give grid.width_arcsec and grid.center_arcsec)")]
    NoPositions,
    /// `refine` got a mass list of the wrong length.
    #[error("grid refinement: {got} masses given for {expected} cells")]
    MassCount { got: usize, expected: usize },
}

/// Grid settings (the `grid` block of an inversion configuration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GridConfig {
    /// Cells per side, `N` (default 32: the paper's 32 x 32 grid). Allowed 1..=256.
    pub cells: usize,
    /// Field centre in arcsec (default: the centre of the bounding box of the constraint
    /// positions).
    pub center_arcsec: Option<DVec2>,
    /// Field width in arcsec (default: `margin_factor` x the larger side of the bounding box of
    /// the constraint positions, at least `min_width_arcsec`).
    pub width_arcsec: Option<f64>,
    /// Field width over the larger extent of the constraint positions (default 1.3: the mass
    /// just outside the outermost arcs still shapes them). Allowed 1..=10.
    pub margin_factor: f64,
    /// Smallest automatic field width in arcsec (default 60: a compact set of images still
    /// gets a field larger than a typical Einstein radius of 20-40 arcsec).
    pub min_width_arcsec: f64,
    /// Gaussian width over the cell size (default 0.75, see the module documentation).
    /// Allowed 0.1..=3.
    pub cell_sigma_factor: f64,
    /// Refinement passes after a first solution (default 0: the paper found the regular grid
    /// better than a multi-resolution one). Allowed 0..=4.
    pub refinements: usize,
    /// Fraction of the cells (those of highest mass density) split in each pass (default 0.25:
    /// the cells above the 75th percentile). Allowed (0, 1].
    pub refine_fraction: f64,
    /// The tidal field of mass beyond the grid: an external shear, two more unknowns
    /// `gamma1`, `gamma2` with the Gaussian prior `0 +- external_shear_sigma` each (see
    /// [`super::external_shear_layers`]). Default 0.1 (the tidal shears of published cluster
    /// models are 0.05 - 0.2); `null`: none, as in the paper. Never with the least-mass
    /// regulariser, whose "auto" candidates fit none
    /// ([`crate::ReconstructConfig::external_shear_fitted`]). Allowed (0, 1].
    pub external_shear_sigma: Option<f64>,
}

impl Default for GridConfig {
    fn default() -> Self {
        Self {
            cells: 32,
            center_arcsec: None,
            width_arcsec: None,
            margin_factor: 1.3,
            min_width_arcsec: 60.0,
            cell_sigma_factor: 0.75,
            refinements: 0,
            refine_fraction: 0.25,
            external_shear_sigma: Some(0.1),
        }
    }
}

fn bad(field: &'static str, value: f64, reason: &'static str) -> GridError {
    crate::error::BadFieldValue::new(format!("grid.{field}"), value, reason).into()
}

fn check_range(
    field: &'static str,
    v: f64,
    lo: f64,
    hi: f64,
    why: &'static str,
) -> Result<(), GridError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(bad(field, v, why))
    }
}

impl GridConfig {
    /// Checks every field against the range in its documentation.
    pub fn validate(&self) -> Result<(), GridError> {
        if !(1..=256).contains(&self.cells) {
            return Err(bad("cells", self.cells as f64, "must be in 1..=256"));
        }
        if let Some(c) = self.center_arcsec {
            check_range("center_arcsec.x", c.x, -1e6, 1e6, "must be finite arcsec")?;
            check_range("center_arcsec.y", c.y, -1e6, 1e6, "must be finite arcsec")?;
        }
        if let Some(w) = self.width_arcsec {
            check_range(
                "width_arcsec",
                w,
                1e-3,
                1e6,
                "must be in [1e-3, 1e6] arcsec",
            )?;
        }
        check_range(
            "margin_factor",
            self.margin_factor,
            1.0,
            10.0,
            "must be in [1, 10]",
        )?;
        check_range(
            "min_width_arcsec",
            self.min_width_arcsec,
            0.0,
            1e6,
            "must be in [0, 1e6] arcsec",
        )?;
        check_range(
            "cell_sigma_factor",
            self.cell_sigma_factor,
            0.1,
            3.0,
            "must be in [0.1, 3]",
        )?;
        if self.refinements > 4 {
            return Err(bad(
                "refinements",
                self.refinements as f64,
                "must be in 0..=4",
            ));
        }
        if let Some(sigma) = self.external_shear_sigma {
            if !(sigma > 0.0 && sigma <= 1.0) {
                return Err(bad("external_shear_sigma", sigma, "must be in (0, 1]"));
            }
        }
        if !(self.refine_fraction > 0.0 && self.refine_fraction <= 1.0) {
            return Err(bad(
                "refine_fraction",
                self.refine_fraction,
                "must be in (0, 1]",
            ));
        }
        Ok(())
    }
}

/// One grid cell: a square of side `size_arcsec` carrying a Gaussian of width `sigma_arcsec`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// Centre in arcsec.
    pub center: DVec2,
    /// Side in arcsec.
    pub size_arcsec: f64,
    /// Gaussian width (standard deviation) in arcsec.
    pub sigma_arcsec: f64,
    /// Refinement level (0 for the regular grid, +1 per split).
    pub level: u32,
    /// Index of the cell of the previous grid this one was made from (itself for a grid that
    /// was not refined), to carry a solution over as a starting point.
    pub parent: usize,
}

/// The cells of a (possibly refined) square grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellGrid {
    /// Field centre in arcsec.
    pub center: DVec2,
    /// Field side in arcsec.
    pub width_arcsec: f64,
    /// Cells per side of the regular level-0 grid.
    pub cells_per_side: usize,
    /// Gaussian width over cell size.
    pub cell_sigma_factor: f64,
    pub cells: Vec<Cell>,
}

impl CellGrid {
    /// A regular `n x n` grid over the square of side `width_arcsec` centred on `center`
    /// (arcsec); cell `j = row * n + column` has centre
    /// `center + ((column + 1/2 - n/2), (row + 1/2 - n/2)) * width / n` and
    /// `sigma = cell_sigma_factor * width / n`.
    pub fn regular(
        center: DVec2,
        width_arcsec: f64,
        n: usize,
        cell_sigma_factor: f64,
    ) -> Result<Self, GridError> {
        let config = GridConfig {
            cells: n,
            center_arcsec: Some(center),
            width_arcsec: Some(width_arcsec),
            cell_sigma_factor,
            ..GridConfig::default()
        };
        config.validate()?;
        let size = width_arcsec / n as f64;
        let half = n as f64 / 2.0;
        let mut cells = Vec::with_capacity(n * n);
        for row in 0..n {
            for col in 0..n {
                let offset = DVec2::new(col as f64 + 0.5 - half, row as f64 + 0.5 - half) * size;
                cells.push(Cell {
                    center: center + offset,
                    size_arcsec: size,
                    sigma_arcsec: cell_sigma_factor * size,
                    level: 0,
                    parent: cells.len(),
                });
            }
        }
        Ok(Self {
            center,
            width_arcsec,
            cells_per_side: n,
            cell_sigma_factor,
            cells,
        })
    }

    /// The regular grid of `config`, with the field sized from `positions` (arcsec) where the
    /// config leaves centre or width open: centre = bounding-box centre, width =
    /// `max(margin_factor * larger bounding-box side, min_width_arcsec)`.
    pub fn from_config(config: &GridConfig, positions: &[DVec2]) -> Result<Self, GridError> {
        config.validate()?;
        let bbox = positions
            .iter()
            .fold(None, |acc: Option<(DVec2, DVec2)>, &p| match acc {
                None => Some((p, p)),
                Some((lo, hi)) => Some((lo.min(p), hi.max(p))),
            });
        let center = match (config.center_arcsec, bbox) {
            (Some(c), _) => c,
            (None, Some((lo, hi))) => 0.5 * (lo + hi),
            (None, None) => return Err(GridError::NoPositions),
        };
        let width = match (config.width_arcsec, bbox) {
            (Some(w), _) => w,
            (None, Some((lo, hi))) => {
                // Extent about the chosen centre, so that an explicit centre still covers all.
                let half = (hi - center).max(center - lo);
                (config.margin_factor * 2.0 * half.max_element()).max(config.min_width_arcsec)
            }
            (None, None) => return Err(GridError::NoPositions),
        };
        Self::regular(center, width, config.cells, config.cell_sigma_factor)
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// True when the grid has no cells (never for a constructed grid).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Whether `p` (arcsec) lies inside the field square grown by `margin_arcsec` on each side.
    pub fn contains(&self, p: DVec2, margin_arcsec: f64) -> bool {
        let d = (p - self.center).abs();
        let half = 0.5 * self.width_arcsec + margin_arcsec;
        d.x <= half && d.y <= half
    }

    /// Side in arcsec of the square about the centre that holds every cell: the field's width,
    /// or wider when cells lie outside it (the weak-lensing ring, [`super::with_ring`]).
    pub fn extent_arcsec(&self) -> f64 {
        if self.cells.iter().all(|c| self.contains(c.center, 0.0)) {
            return self.width_arcsec;
        }
        let half = self
            .cells
            .iter()
            .map(|c| (c.center - self.center).abs().max_element() + 0.5 * c.size_arcsec)
            .fold(0.5 * self.width_arcsec, f64::max);
        2.0 * half
    }

    /// A multi-resolution grid: the `ceil(fraction * len)` cells of highest mass density
    /// `masses[j] / size_j^2` (masses in any unit, one per cell) are each split into 4
    /// sub-cells of half the size and half the width; the others are kept. Children replace
    /// their parent in place, in the order (-x,-y), (+x,-y), (-x,+y), (+x,+y); every new cell
    /// records its parent index. Ties are broken by the lower cell index.
    pub fn refine(&self, masses: &[f64], fraction: f64) -> Result<CellGrid, GridError> {
        if masses.len() != self.cells.len() {
            return Err(GridError::MassCount {
                got: masses.len(),
                expected: self.cells.len(),
            });
        }
        if !(fraction > 0.0 && fraction <= 1.0) {
            return Err(bad("refine_fraction", fraction, "must be in (0, 1]"));
        }
        if let Some(bad_mass) = masses.iter().find(|m| !m.is_finite()) {
            return Err(bad("masses", *bad_mass, "cell masses must be finite"));
        }
        let n_split = ((fraction * self.cells.len() as f64).ceil() as usize).min(self.cells.len());
        let density =
            |j: usize| masses[j] / (self.cells[j].size_arcsec * self.cells[j].size_arcsec);
        let mut order: Vec<usize> = (0..self.cells.len()).collect();
        order.sort_by(|&i, &j| density(j).total_cmp(&density(i)).then(i.cmp(&j)));
        let mut split = vec![false; self.cells.len()];
        for &j in &order[..n_split] {
            split[j] = true;
        }
        let mut cells = Vec::with_capacity(self.cells.len() + 3 * n_split);
        for (j, cell) in self.cells.iter().enumerate() {
            if !split[j] {
                cells.push(Cell { parent: j, ..*cell });
                continue;
            }
            let size = 0.5 * cell.size_arcsec;
            for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                cells.push(Cell {
                    center: cell.center + 0.5 * size * DVec2::new(sx, sy),
                    size_arcsec: size,
                    sigma_arcsec: 0.5 * cell.sigma_arcsec,
                    level: cell.level + 1,
                    parent: j,
                });
            }
        }
        Ok(CellGrid {
            center: self.center,
            width_arcsec: self.width_arcsec,
            cells_per_side: self.cells_per_side,
            cell_sigma_factor: self.cell_sigma_factor,
            cells,
        })
    }
}

/// The mass of a grid as one component: cell `j` a Gaussian with `K m_j / D_l = b2[j]`
/// arcsec^2 (any sign). Fields at `D_ls/D_s = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct GridMass {
    centers: Vec<DVec2>,
    sigmas_arcsec: Vec<f64>,
    inv_2s2: Vec<f64>,
    b2_arcsec2: Vec<f64>,
}

impl GridMass {
    /// The cells of `grid` with `K m_j / D_l = b2_arcsec2[j]` (arcsec^2, one per cell).
    pub fn new(grid: &CellGrid, b2_arcsec2: Vec<f64>) -> Result<Self, GridError> {
        if b2_arcsec2.len() != grid.len() {
            return Err(GridError::MassCount {
                got: b2_arcsec2.len(),
                expected: grid.len(),
            });
        }
        Ok(Self {
            centers: grid.cells.iter().map(|c| c.center).collect(),
            sigmas_arcsec: grid.cells.iter().map(|c| c.sigma_arcsec).collect(),
            inv_2s2: grid
                .cells
                .iter()
                .map(|c| 0.5 / (c.sigma_arcsec * c.sigma_arcsec))
                .collect(),
            b2_arcsec2,
        })
    }

    /// How [`crate::profiles::MassComponent::add_to_maps`] would make the maps of `geometry`:
    /// which cells go to the FFT convolution (groups of equal width on a sub-lattice of the
    /// pixel lattice, see `cells_fft`) and which to the direct per-pixel sum.
    pub fn map_plan(&self, geometry: &MapGeometry) -> MapPlan {
        let (groups, direct) = cells_fft::plan(
            &self.centers,
            &self.sigmas_arcsec,
            &self.b2_arcsec2,
            geometry,
        );
        cells_fft::summarize(&groups, &direct)
    }

    /// The cells `indices` alone.
    fn subset(&self, indices: &[usize]) -> GridMass {
        GridMass {
            centers: indices.iter().map(|&j| self.centers[j]).collect(),
            sigmas_arcsec: indices.iter().map(|&j| self.sigmas_arcsec[j]).collect(),
            inv_2s2: indices.iter().map(|&j| self.inv_2s2[j]).collect(),
            b2_arcsec2: indices.iter().map(|&j| self.b2_arcsec2[j]).collect(),
        }
    }
}

impl crate::profiles::MassComponent for GridMass {
    fn kappa(&self, p: DVec2) -> f64 {
        let mut k = 0.0;
        for j in 0..self.centers.len() {
            let d = p - self.centers[j];
            k += self.b2_arcsec2[j]
                * crate::profiles::gaussian_unit_kappa(d.x, d.y, self.sigmas_arcsec[j]);
        }
        k
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        let (mut ax, mut ay) = (0.0, 0.0);
        for j in 0..self.centers.len() {
            let d = p - self.centers[j];
            let (gx, gy) = cell_unit_deflection(d.x, d.y, self.inv_2s2[j]);
            ax += self.b2_arcsec2[j] * gx;
            ay += self.b2_arcsec2[j] * gy;
        }
        DVec2::new(ax, ay)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        let mut h = [0.0; 3];
        for j in 0..self.centers.len() {
            let d = p - self.centers[j];
            let hj = crate::profiles::gaussian_unit_hessian(d.x, d.y, self.sigmas_arcsec[j]);
            for k in 0..3 {
                h[k] += self.b2_arcsec2[j] * hj[k];
            }
        }
        h
    }
    /// Exact maps by FFT convolution for the cells on the pixel lattice (see
    /// [`GridMass::map_plan`]), the direct sum for the others; declines (returns false, adds
    /// nothing) when no cell group gains from the FFT.
    fn add_to_maps(&self, maps: &mut LensMaps) -> bool {
        let geometry = maps.geometry();
        let n2 = geometry.pixels * geometry.pixels;
        let fields = [
            &maps.kappa,
            &maps.gamma1,
            &maps.gamma2,
            &maps.alpha_x,
            &maps.alpha_y,
        ];
        if fields
            .iter()
            .any(|m| m.geometry != geometry || m.data.len() != n2)
        {
            return false;
        }
        let (groups, direct) = cells_fft::plan(
            &self.centers,
            &self.sigmas_arcsec,
            &self.b2_arcsec2,
            &geometry,
        );
        if groups.is_empty() {
            return false;
        }
        for group in &groups {
            cells_fft::add_group(group, maps);
        }
        if !direct.is_empty() {
            crate::profiles::add_pixelwise(&[&self.subset(&direct)], maps);
        }
        true
    }
}

//! Weak-lensing constraints: the reduced shear measured by background galaxies (an arclet
//! catalogue, [`crate::catalog::parse_arclet_catalog`]) as rows of the linear system, and the
//! ring of coarser cells that carries the mass they see outside the strong-lensing field.
//!
//! Diego et al. (2007; the WSLAP+ paper's "Extension to weak lensing analysis" points to it) add
//! the shear to the same linear system as the strong-lensing rows. The reduced shear
//! `g = gamma / (1 - kappa)` is linear in the mass once multiplied out, `gamma = g (1 - kappa)`,
//! and each galaxy at `theta` with distance ratio `f = D_ls / D_s` and measured ellipticity
//! `e` (the estimator of `g`) gives two rows, zeros in the source-position columns (a galaxy's
//! own position is not an unknown):
//!
//! ```text
//! gamma_1(theta) = e_1 (1 - kappa_0(theta))        weight 1 / (sigma_e (1 - kappa_0))^2
//! gamma_2(theta) = e_2 (1 - kappa_0(theta))
//! ```
//!
//! `gamma` is the sum over the cells and member layers of their shear at `theta`
//! (`gamma_1 = (psi_11 - psi_22)/2`, `gamma_2 = psi_12`, second derivatives of the potential),
//! each scaled by `f`; `sigma_e` is [`ShearConfig::shape_noise`], the scatter of one component
//! of the galaxies' intrinsic ellipticities. `kappa_0` is the convergence of the previous
//! solution at the galaxy (0 in the first solve): the system is solved
//! [`ShearConfig::iterations`] more times with it updated, so that at the fixed point each row
//! is `(g_model - e) / sigma_e` to first order, the reduced-shear residual itself.
//!
//! Why `kappa` is not a column, as the fully linear form `gamma + e kappa = e` would have it:
//! that form is solved exactly, whatever the data, by a critical sheet (`kappa = 1`,
//! `gamma = 0`), which non-negative cells can build. On the synthetic cluster of
//! tests/inversion/shear.rs it did: 1.2e16 Msun in the field, an Einstein radius of 269
//! arcsec and `chi^2` 0.02 per galaxy (2 is the noise). With `kappa_0` from the previous
//! solution on the right-hand side every row asks for shear, which no sheet gives.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::cells::{Cell, CellGrid, GridError};
use crate::catalog::ArcletCatalog;
use crate::cosmology::LensPlane;
use crate::error::BadFieldValue;

/// Settings of the weak-lensing rows (the `shear` block of an inversion configuration; used
/// only when an arclet catalogue is given).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShearConfig {
    /// Scatter (standard deviation) of each component of the intrinsic ellipticity, the
    /// weight of a row being `1 / shape_noise^2` (default 0.3). Allowed [0.01, 2].
    pub shape_noise: f64,
    /// Most cells in the ring of coarser cells around the grid (default 400). Its cells are
    /// `k` grid cells wide, `k` the smallest divisor of `grid.cells` that keeps the ring within
    /// this count (so the ring's lattice continues the grid's); the ring reaches the median
    /// galaxy (the outer half lie beyond the grid and weigh it: `reconstruct::grid_of`).
    /// Allowed 1..=10000.
    pub ring_cells_max: usize,
    /// Solves after the first with each row's `kappa_0` updated to the previous solution's
    /// convergence (default 3; 0: the rows stay `gamma = e`, the weak-shear approximation).
    /// Allowed 0..=20.
    pub iterations: usize,
}

impl Default for ShearConfig {
    fn default() -> Self {
        Self {
            shape_noise: 0.3,
            ring_cells_max: 400,
            iterations: 3,
        }
    }
}

impl ShearConfig {
    /// Checks every field against the range in its documentation.
    pub fn validate(&self) -> Result<(), BadFieldValue> {
        let s = self.shape_noise;
        if !(s.is_finite() && (0.01..=2.0).contains(&s)) {
            return Err(BadFieldValue::new(
                "shear.shape_noise",
                s,
                "must be in [0.01, 2]",
            ));
        }
        if !(1..=10_000).contains(&self.ring_cells_max) {
            return Err(BadFieldValue::new(
                "shear.ring_cells_max",
                self.ring_cells_max as f64,
                "must be in 1..=10000",
            ));
        }
        if self.iterations > 20 {
            return Err(BadFieldValue::new(
                "shear.iterations",
                self.iterations as f64,
                "must be in 0..=20",
            ));
        }
        Ok(())
    }
}

/// Smallest `1 - kappa_0` a row is divided by: a galaxy the previous solution put on a
/// critical density (`kappa_0 >= 0.9`) counts as at 0.9, so that no row outweighs the others
/// by more than a factor 100.
pub const MIN_ONE_MINUS_KAPPA: f64 = 0.1;

/// One galaxy's two rows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShearPoint {
    /// Position in arcsec.
    pub position: DVec2,
    /// Measured ellipticity `(e_1, e_2)`, the estimate of the reduced shear.
    pub g: DVec2,
    /// `D_ls / D_s` of the galaxy.
    pub distance_ratio: f64,
    /// Weight of each of its rows for `kappa_0 = 0`, `1 / sigma_e^2`.
    pub weight: f64,
    /// Convergence of the previous solution at the galaxy (at its `D_ls/D_s`; 0 at first).
    pub kappa_0: f64,
}

impl ShearPoint {
    /// The right-hand side `e (1 - kappa_0)` of its two rows and their weight
    /// `weight / (1 - kappa_0)^2` (`1 - kappa_0` at least [`MIN_ONE_MINUS_KAPPA`]).
    pub fn row_target(&self) -> (DVec2, f64) {
        let s = (1.0 - self.kappa_0).max(MIN_ONE_MINUS_KAPPA);
        (self.g * s, self.weight / (s * s))
    }
}

/// The weak-lensing data of a system: one [`ShearPoint`] per galaxy behind the lens.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ShearSet {
    /// The catalogue's file name (empty when there is none).
    pub source_name: String,
    pub points: Vec<ShearPoint>,
}

impl ShearSet {
    /// The galaxies of `catalog` behind the lens of `plane`, weighted by `config`. Galaxies at
    /// `z <= z_lens` carry no shear and are left out; the second value says how many, in a
    /// sentence naming the file and the first such line (`None` when all are used).
    pub fn from_catalog(
        catalog: &ArcletCatalog,
        config: &ShearConfig,
        plane: &LensPlane,
    ) -> (Self, Option<String>) {
        let weight = 1.0 / (config.shape_noise * config.shape_noise);
        let mut points = Vec::with_capacity(catalog.arclets.len());
        let mut skipped = Vec::new();
        for arclet in &catalog.arclets {
            match plane.distance_ratio(arclet.z) {
                Ok(f) if arclet.z > plane.z_lens && f > 0.0 => points.push(ShearPoint {
                    position: arclet.position,
                    g: arclet.ellipticity,
                    distance_ratio: f,
                    weight,
                    kappa_0: 0.0,
                }),
                _ => skipped.push(arclet),
            }
        }
        let warning = skipped.first().map(|first| {
            format!(
                "{}: line {}: {} arclet(s) at z <= z_lens = {} (the first at z = {}) carry no \
                 shear and are left out",
                catalog.source_name,
                first.line,
                skipped.len(),
                plane.z_lens,
                first.z
            )
        });
        let set = Self {
            source_name: catalog.source_name.clone(),
            points,
        };
        (set, warning)
    }

    /// Number of galaxies.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when there is no galaxy.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The set with each galaxy's `kappa_0` set to `f kappa(theta)`, `kappa` the convergence at
    /// `D_ls/D_s = 1` of the previous solution.
    pub fn with_kappa(&self, kappa: impl Fn(DVec2) -> f64) -> Self {
        let mut out = self.clone();
        for p in &mut out.points {
            p.kappa_0 = p.distance_ratio * kappa(p.position);
        }
        out
    }

    /// `chi^2 / N = sum |g - e|^2 / sigma_e^2 / N` of the reduced shear
    /// `g = gamma / (1 - kappa)` of the fields `(kappa, gamma_1, gamma_2)` at `D_ls/D_s = 1`
    /// that `fields` gives at a position (scaled here by each galaxy's ratio) against the
    /// ellipticities, `N` the number of galaxies: about 2 when the map fits them to their
    /// shape noise. `None` without galaxies.
    pub fn chi2_per_galaxy(&self, fields: impl Fn(DVec2) -> [f64; 3]) -> Option<f64> {
        if self.points.is_empty() {
            return None;
        }
        let chi2: f64 = self
            .points
            .iter()
            .map(|p| {
                let [k, g1, g2] = fields(p.position).map(|v| v * p.distance_ratio);
                let g = DVec2::new(g1, g2) / (1.0 - k).abs().max(MIN_ONE_MINUS_KAPPA);
                p.weight * (g - p.g).length_squared()
            })
            .sum();
        Some(chi2 / self.points.len() as f64)
    }
}

/// `(kappa, gamma_1, gamma_2)` of a Hessian `[psi_11, psi_12, psi_22]`.
pub fn kappa_gamma(h: [f64; 3]) -> [f64; 3] {
    [0.5 * (h[0] + h[2]), 0.5 * (h[0] - h[2]), h[1]]
}

/// `grid` with a ring of coarser cells around its field out to `reach_arcsec` (the larger of
/// `|x - x_c|`, `|y - y_c|` over the galaxies, arcsec from the grid's centre): cells `k` grid
/// cells wide on the lattice that continues the grid's (`k` the smallest divisor of the grid's
/// cells per side giving at most `max_cells` ring cells, else the grid's width), in rows of
/// the outer square from the bottom-left, after the grid's own cells. The grid itself when
/// `reach_arcsec` lies within its field.
pub fn with_ring(
    grid: &CellGrid,
    reach_arcsec: f64,
    max_cells: usize,
) -> Result<CellGrid, GridError> {
    let half = 0.5 * grid.width_arcsec;
    if !(reach_arcsec.is_finite() && reach_arcsec > half) {
        return Ok(grid.clone());
    }
    let n = grid.cells_per_side;
    let h = grid.width_arcsec / n as f64;
    let layout = |k: usize| {
        let size = k as f64 * h;
        let inner = n / k;
        let layers = ((reach_arcsec - half) / size).ceil() as usize;
        let side = inner + 2 * layers;
        (size, inner, layers, side, side * side - inner * inner)
    };
    let k = (1..=n)
        .filter(|k| n % k == 0)
        .find(|&k| layout(k).4 <= max_cells)
        .unwrap_or(n);
    let (size, inner, layers, side, _) = layout(k);
    let mut out = grid.clone();
    let origin = grid.center - DVec2::splat(half + layers as f64 * size);
    for row in 0..side {
        for col in 0..side {
            let inside = |i: usize| i >= layers && i < layers + inner;
            if inside(row) && inside(col) {
                continue;
            }
            let centre = origin + (DVec2::new(col as f64, row as f64) + 0.5) * size;
            out.cells.push(Cell {
                center: centre,
                size_arcsec: size,
                sigma_arcsec: grid.cell_sigma_factor * size,
                level: 0,
                parent: out.cells.len(),
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalog::parse_arclet_catalog;
    use crate::cosmology::Cosmology;

    #[test]
    fn galaxies_in_front_of_the_lens_are_left_out_with_one_warning() {
        let text = "#REFERENCE 3 150.0 2.0\n\
                    1 60 10 0.5 0.3 20 1.5\n\
                    2 70 -5 0.5 0.3 20 0.2\n\
                    3 -40 5 0.5 0.3 20 0.25\n";
        let (catalog, _) = parse_arclet_catalog(text, "wl.cat", None).unwrap();
        let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
        let config = ShearConfig {
            shape_noise: 0.25,
            ..ShearConfig::default()
        };
        let (set, warning) = ShearSet::from_catalog(&catalog, &config, &plane);
        assert_eq!(set.len(), 1);
        assert_eq!(set.points[0].weight, 16.0);
        assert_eq!(
            warning.unwrap(),
            "wl.cat: line 3: 2 arclet(s) at z <= z_lens = 0.3 (the first at z = 0.2) carry no \
             shear and are left out"
        );
    }

    #[test]
    fn the_ring_continues_the_grid_lattice() {
        let grid = CellGrid::regular(DVec2::new(1.0, -2.0), 80.0, 32, 0.75).unwrap();
        let ringed = with_ring(&grid, 250.0, 400).unwrap();
        let ring = &ringed.cells[grid.len()..];
        // k = 16: 40" cells, 6 layers around the 2 x 2 inner block: 14^2 - 4 cells.
        assert_eq!(ring.len(), 14 * 14 - 4);
        assert!(ring.iter().all(|c| c.size_arcsec == 40.0));
        let reach = ring
            .iter()
            .map(|c| (c.center - grid.center).abs().max_element() + 0.5 * c.size_arcsec)
            .fold(0.0, f64::max);
        assert!((reach - 280.0).abs() < 1e-9, "{reach}");
        // No ring cell overlaps the field; the nearest touch its edge.
        let nearest = ring
            .iter()
            .map(|c| (c.center - grid.center).abs().max_element() - 0.5 * c.size_arcsec)
            .fold(f64::INFINITY, f64::min);
        assert!((nearest - 40.0).abs() < 1e-9, "{nearest}");
        assert_eq!(with_ring(&grid, 30.0, 400).unwrap(), grid);
    }
}

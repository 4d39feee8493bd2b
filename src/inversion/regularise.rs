//! The stated objective of a reconstruction: the data term plus a regulariser on the cell
//! masses, and the image-plane weighting of the data term.
//!
//! ```text
//! Phi(X) = sum_i (M_i r_i)^T W_i (M_i r_i) + lambda R(m),    X >= 0,
//! r_i = Gamma_i X - Theta_i          (source-plane residual of constraint pixel i, arcsec)
//! R(m) = integral over the sky of |D^p Sigma_cells|^2,   Sigma_cells = sum_j m_j G_j
//! ```
//!
//! - `M_i` is the inverse lens Jacobian of the current model at pixel `i` (the magnification
//!   tensor): `M_i r_i` is, to first order, how far from pixel `i` its source's image lands.
//!   So the data term measures misfit in the image plane, where the images are observed, and
//!   not in the source plane, where more mass always helps (it shrinks the sources and with
//!   them the residuals: the over-focused "point-source solution"). The system stays linear
//!   because `M_i` is taken from the previous solution and the problem is solved again a few
//!   times (iteratively reweighted least squares, [`ObjectiveConfig::image_plane_iterations`]).
//!   The stretch `|M_i|` is capped at [`ObjectiveConfig::max_stretch`] along each axis: next
//!   to a critical curve the linear relation fails and one pixel must not outweigh the rest.
//! - `R` is a Tikhonov regulariser on the grid's surface density `Sigma_cells`, each cell a
//!   unit-mass Gaussian `G_j` of width `s_j` at `c_j`. For Gaussians the integrals are exact:
//!   with `s^2 = s_j^2 + s_k^2`, `t = |c_j - c_k|^2 / s^2` and `h = exp(-t/2) / (2 pi s^2)`,
//!
//!   ```text
//!   density   (p = 0, integral of Sigma^2):          R_jk = h
//!   gradient  (p = 1, integral of |grad Sigma|^2):   R_jk = h (2 - t) / s^2
//!   curvature (p = 2, integral of (lap Sigma)^2):    R_jk = h (t^2 - 8 t + 8) / s^4
//!   ```
//!
//!   (the Fourier transform of the product of two Gaussians is a Gaussian of variance `s^2`,
//!   and each derivative order multiplies it by `|k|^2`, i.e. applies `-laplacian` to `h`).
//!   `R` is a Gram matrix, so positive semi-definite, and it does not depend on how the cells
//!   are laid out: a refined grid is regularised as the same surface density.
//! - Density, the least mass, also charges the member galaxies' mass, coarse-grained to the
//!   cells: layer `l` at `C_l` counts as the cell masses `C_l P_jl` (its mass inside cell
//!   `j`'s square), so the term is `(m + P C)^T R (m + P C)`
//!   (`LinearSystem::member_mass_in_cells`). Otherwise the least mass would move the cells'
//!   mass into the members, which cost nothing. Gradient and curvature judge the smooth
//!   mass's shape and leave the members uncharged.
//! - `lambda = strength * tr(A_cells) / tr(R)`, with `A_cells` the cells' block of the data
//!   term's normal matrix (source-plane weights), so that `strength` means the same for any
//!   mass unit, field or number of images. It is fixed at the first solve and kept while the
//!   weights are updated, so the objective is one function.
//!
//! With a regulariser the objective is strictly convex in the cells, and
//! [`crate::solver::minimise_exact`] finds its minimiser: the answer no longer depends on the
//! start or on an iteration count.

use crate::error::BadFieldValue;
use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::cells::CellGrid;

/// Which derivative of the grid's surface density the regulariser penalises.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Regulariser {
    /// No regulariser (the paper's objective: QADP's early stop is then the regulariser).
    None,
    /// `integral Sigma^2`: the least-concentrated mass.
    Density,
    /// `integral |grad Sigma|^2`: the smoothest mass (a uniform sheet is free).
    #[default]
    Gradient,
    /// `integral (laplacian Sigma)^2`: the least curved mass (uniform gradients are free).
    Curvature,
}

impl Regulariser {
    /// Its name in the settings (`"gradient"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Regulariser::None => "none",
            Regulariser::Density => "density",
            Regulariser::Gradient => "gradient",
            Regulariser::Curvature => "curvature",
        }
    }
}

/// The strength of the regulariser: a number, or "auto" (chosen by cross-validation).
/// Read by hand, not by serde's untagged enum, whose error ("data did not match any variant")
/// would tell a person nothing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Strength {
    /// `strength` of the module documentation.
    Value(f64),
    /// Chosen among [`ObjectiveConfig::candidates`] by the held-out images of a K-fold
    /// cross-validation (`"auto"`).
    Auto(AutoWord),
}

/// The word `"auto"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AutoWord {
    Auto,
}

impl<'de> Deserialize<'de> for Strength {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct StrengthVisitor;

        impl serde::de::Visitor<'_> for StrengthVisitor {
            type Value = Strength;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number (0 to 1e6) or \"auto\"")
            }

            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Strength, E> {
                Ok(Strength::Value(v))
            }

            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Strength, E> {
                Ok(Strength::Value(v as f64))
            }

            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Strength, E> {
                Ok(Strength::Value(v as f64))
            }

            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Strength, E> {
                if v == "auto" {
                    Ok(Strength::Auto(AutoWord::Auto))
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
                }
            }
        }

        deserializer.deserialize_any(StrengthVisitor)
    }
}

impl Strength {
    /// The fixed value, `None` for "auto".
    pub fn value(self) -> Option<f64> {
        match self {
            Strength::Value(v) => Some(v),
            Strength::Auto(_) => None,
        }
    }
}

/// What the reconstruction minimises (the `objective` block of the configuration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObjectiveConfig {
    /// The regulariser on the cells (default "gradient").
    pub regulariser: Regulariser,
    /// Its strength: a number in [0, 1e6], or "auto" (default).
    pub strength: Strength,
    /// The strengths "auto" chooses from (default 0.01, 0.1 and 1: on the six synthetic
    /// clusters of tests/data/fidelity and AS1063, 0.001 and 10 were chosen once and never).
    pub candidates: Vec<f64>,
    /// The regularisers "auto" tries, each with every candidate strength (default gradient,
    /// curvature and density: gradient and curvature each predicted better on some of the
    /// synthetic clusters of tests/data/fidelity; neither costs a uniform sheet of mass, so
    /// where the images leave the mass-sheet-like direction open only density, the least
    /// mass, holds it, as on the simulated cluster of `wslap paper` (BENCHMARKS.md); density
    /// fits no external shear, [`crate::reconstruct::strength_candidates`]).
    /// With a number for the strength, `regulariser` alone is used.
    pub auto_regularisers: Vec<Regulariser>,
    /// The grids "auto" tries, each with every regulariser and strength, as fractions of
    /// `grid.cells` a side: a grid of `round(scale * grid.cells)` cells a side (at least 1)
    /// for each (default 0.5, 0.75 and 1: 16, 24 and 32 cells a side with the default grid;
    /// on the eight synthetic clusters of tests/data/fidelity each grid predicted best on
    /// some, BENCHMARKS.md). `[1]`: `grid.cells` alone. Allowed 1 to 4 scales, each in
    /// (0, 1]. With a number for the strength, `grid.cells` is used.
    pub auto_grid_scales: Vec<f64>,
    /// Folds of the cross-validation that chooses the strength (default 4). At least 2; fewer
    /// when there are fewer systems.
    pub folds: usize,
    /// Times the image-plane weights are updated and the problem solved again (default 2;
    /// 0 = source-plane residuals). Allowed 0..=10.
    pub image_plane_iterations: usize,
    /// Largest stretch of a residual by the magnification tensor, per axis (default 10).
    /// Allowed [1, 1000].
    pub max_stretch: f64,
}

impl Default for ObjectiveConfig {
    fn default() -> Self {
        Self {
            regulariser: Regulariser::Gradient,
            strength: Strength::Auto(AutoWord::Auto),
            candidates: vec![1e-2, 1e-1, 1.0],
            auto_regularisers: vec![
                Regulariser::Gradient,
                Regulariser::Curvature,
                Regulariser::Density,
            ],
            auto_grid_scales: vec![0.5, 0.75, 1.0],
            folds: 4,
            image_plane_iterations: 2,
            max_stretch: 10.0,
        }
    }
}

impl ObjectiveConfig {
    /// The paper's objective: the source-plane chi^2 alone (QADP's early stop regularises).
    pub fn paper() -> Self {
        Self {
            regulariser: Regulariser::None,
            strength: Strength::Value(0.0),
            image_plane_iterations: 0,
            ..Self::default()
        }
    }
}

impl ObjectiveConfig {
    /// Checks every field against the range in its documentation.
    pub fn validate(&self) -> Result<(), BadFieldValue> {
        let bad = |field, value, reason| Err(BadFieldValue::new(field, value, reason));
        let strength_ok = |v: f64| v.is_finite() && (0.0..=1e6).contains(&v);
        if let Some(v) = self.strength.value() {
            if !strength_ok(v) {
                return bad("objective.strength", v, "must be in [0, 1e6] or \"auto\"");
            }
        }
        if self.candidates.is_empty() || self.candidates.len() > 20 {
            return bad(
                "objective.candidates",
                self.candidates.len() as f64,
                "give 1 to 20 strengths",
            );
        }
        if let Some(&v) = self.candidates.iter().find(|&&v| !strength_ok(v)) {
            return bad("objective.candidates", v, "each must be in [0, 1e6]");
        }
        if self.auto_regularisers.is_empty() || self.auto_regularisers.len() > 4 {
            return bad(
                "objective.auto_regularisers",
                self.auto_regularisers.len() as f64,
                "give 1 to 4 regularisers",
            );
        }
        if self.auto_grid_scales.is_empty() || self.auto_grid_scales.len() > 4 {
            return bad(
                "objective.auto_grid_scales",
                self.auto_grid_scales.len() as f64,
                "give 1 to 4 scales",
            );
        }
        if let Some(&v) = self
            .auto_grid_scales
            .iter()
            .find(|&&v| !(v.is_finite() && v > 0.0 && v <= 1.0))
        {
            return bad(
                "objective.auto_grid_scales",
                v,
                "each must be in (0, 1]: a fraction of grid.cells",
            );
        }
        if !(2..=20).contains(&self.folds) {
            return bad("objective.folds", self.folds as f64, "must be 2 to 20");
        }
        if self.image_plane_iterations > 10 {
            return bad(
                "objective.image_plane_iterations",
                self.image_plane_iterations as f64,
                "must be 0 to 10",
            );
        }
        if !(self.max_stretch.is_finite() && (1.0..=1000.0).contains(&self.max_stretch)) {
            return bad(
                "objective.max_stretch",
                self.max_stretch,
                "must be in [1, 1000]",
            );
        }
        Ok(())
    }
}

/// Pairs farther apart than this (`t = d^2 / s^2`) contribute below `exp(-40)` and are left 0.
const T_MAX: f64 = 80.0;

/// `R` of the module documentation for the cells of `grid` (row-major, `n_cells^2`), in
/// units of (unit mass)^2 per arcsec^(2 + 2p); all zeros for [`Regulariser::None`].
pub fn cell_penalty(grid: &CellGrid, kind: Regulariser) -> Vec<f64> {
    let n = grid.len();
    let mut r = vec![0.0; n * n];
    if kind == Regulariser::None {
        return r;
    }
    let cells: Vec<(DVec2, f64)> = grid
        .cells
        .iter()
        .map(|c| (c.center, c.sigma_arcsec * c.sigma_arcsec))
        .collect();
    for (j, &(cj, sj)) in cells.iter().enumerate() {
        for (k, &(ck, sk)) in cells.iter().enumerate().skip(j) {
            let s2 = sj + sk;
            let t = (cj - ck).length_squared() / s2;
            if t > T_MAX {
                continue;
            }
            let h = (-0.5 * t).exp() / (2.0 * std::f64::consts::PI * s2);
            let v = match kind {
                Regulariser::None => 0.0,
                Regulariser::Density => h,
                Regulariser::Gradient => h * (2.0 - t) / s2,
                Regulariser::Curvature => h * (t * t - 8.0 * t + 8.0) / (s2 * s2),
            };
            r[j * n + k] = v;
            r[k * n + j] = v;
        }
    }
    r
}

/// The inverse of the lens Jacobian `[[1 - f h_xx, -f h_xy], [-f h_xy, 1 - f h_yy]]`
/// (`h = [psi_xx, psi_xy, psi_yy]` at `D_ls/D_s = 1`, `f = D_ls/D_s`) with each eigenvalue's
/// size capped at `max_stretch`, row-major `[m00, m01, m10, m11]`.
pub fn capped_inverse_jacobian(h: [f64; 3], f: f64, max_stretch: f64) -> [f64; 4] {
    let (a, b, d) = (1.0 - f * h[0], -f * h[1], 1.0 - f * h[2]);
    // Eigen-decomposition of the symmetric [[a, b], [b, d]].
    let mean = 0.5 * (a + d);
    let half = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (l1, l2) = (mean + half, mean - half);
    let angle = 0.5 * (2.0 * b).atan2(a - d);
    let (c, s) = (angle.cos(), angle.sin());
    let floor = 1.0 / max_stretch;
    let inv = |l: f64| {
        let size = l.abs().max(floor);
        if l < 0.0 {
            -1.0 / size
        } else {
            1.0 / size
        }
    };
    let (i1, i2) = (inv(l1), inv(l2));
    // R diag(i1, i2) R^T with R = [[c, -s], [s, c]].
    [
        c * c * i1 + s * s * i2,
        c * s * (i1 - i2),
        c * s * (i1 - i2),
        s * s * i1 + c * c * i2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regulariser's name is the one the settings use.
    #[test]
    fn names_are_the_settings_words() {
        for r in [
            Regulariser::None,
            Regulariser::Density,
            Regulariser::Gradient,
            Regulariser::Curvature,
        ] {
            assert_eq!(serde_json::to_value(r).unwrap(), r.name());
        }
    }

    /// A strength is a number or the word "auto", and reads back as it was written; anything
    /// else is refused with the value and what is expected, not with serde's "did not match
    /// any variant of untagged enum".
    #[test]
    fn strength_reads_a_number_or_auto() {
        for (text, strength) in [
            ("0.1", Strength::Value(0.1)),
            ("3", Strength::Value(3.0)),
            ("-2", Strength::Value(-2.0)),
            ("\"auto\"", Strength::Auto(AutoWord::Auto)),
        ] {
            let read: Strength = serde_json::from_str(text).unwrap();
            assert_eq!(read, strength, "{text}");
            let written = serde_json::to_string(&read).unwrap();
            assert_eq!(serde_json::from_str::<Strength>(&written).unwrap(), read);
        }
        for (text, shown) in [
            ("\"fast\"", "string \"fast\""),
            ("true", "boolean `true`"),
            ("[1]", "sequence"),
            ("null", "null"),
        ] {
            let message = serde_json::from_str::<Strength>(text)
                .unwrap_err()
                .to_string();
            assert!(
                message.contains(shown) && message.contains("a number (0 to 1e6) or \"auto\""),
                "{text}: {message}"
            );
        }
    }

    /// The grids "auto" tries are fractions of `grid.cells` in (0, 1], one to four of them;
    /// a bad one is refused with the field's name and the value.
    #[test]
    fn grid_scales_are_checked() {
        let mut o = ObjectiveConfig::default();
        assert_eq!(o.auto_grid_scales, vec![0.5, 0.75, 1.0]);
        assert!(o.validate().is_ok());
        for (scales, value) in [
            (vec![0.5, 0.0], "0"),
            (vec![1.5], "1.5"),
            (vec![f64::NAN], "NaN"),
            (vec![], "0"),
            (vec![0.2, 0.4, 0.6, 0.8, 1.0], "5"),
        ] {
            o.auto_grid_scales = scales.clone();
            let message = o.validate().unwrap_err().to_string();
            assert!(
                message.starts_with(&format!("objective.auto_grid_scales = {value}")),
                "{scales:?}: {message}"
            );
        }
    }

    /// The penalty of two unit Gaussians against a numerical integral on a fine grid.
    #[test]
    fn penalties_match_a_numerical_integral() {
        let (s1, s2) = (1.3f64, 0.8f64);
        let (c1, c2) = (DVec2::new(0.0, 0.0), DVec2::new(1.7, -0.6));
        let g = |p: DVec2, c: DVec2, s: f64| {
            let d = p - c;
            let e =
                (-d.length_squared() / (2.0 * s * s)).exp() / (2.0 * std::f64::consts::PI * s * s);
            // value, gradient, laplacian
            let grad = -d / (s * s) * e;
            let lap = e * (d.length_squared() / s.powi(4) - 2.0 / (s * s));
            (e, grad, lap)
        };
        let step = 0.02;
        let (mut dens, mut grad, mut curv) = (0.0, 0.0, 0.0);
        let mut y = -12.0;
        while y < 12.0 {
            let mut x = -12.0;
            while x < 12.0 {
                let p = DVec2::new(x, y);
                let (e1, g1, l1) = g(p, c1, s1);
                let (e2, g2, l2) = g(p, c2, s2);
                dens += e1 * e2;
                grad += g1.dot(g2);
                curv += l1 * l2;
                x += step;
            }
            y += step;
        }
        let area = step * step;
        let grid = CellGrid {
            cells: vec![
                super::super::cells::Cell {
                    center: c1,
                    size_arcsec: 1.0,
                    sigma_arcsec: s1,
                    level: 0,
                    parent: 0,
                },
                super::super::cells::Cell {
                    center: c2,
                    size_arcsec: 1.0,
                    sigma_arcsec: s2,
                    level: 0,
                    parent: 1,
                },
            ],
            ..CellGrid::regular(DVec2::ZERO, 10.0, 1, 0.75).unwrap()
        };
        for (kind, want) in [
            (Regulariser::Density, dens * area),
            (Regulariser::Gradient, grad * area),
            (Regulariser::Curvature, curv * area),
        ] {
            let r = cell_penalty(&grid, kind);
            assert!(
                (r[1] - want).abs() < 1e-6 * want.abs().max(1e-3),
                "{kind:?}: {} vs {want}",
                r[1]
            );
            assert_eq!(r[1], r[2]);
        }
    }

    #[test]
    fn the_inverse_jacobian_inverts_and_caps() {
        let h = [0.3, 0.1, 0.2];
        let m = capped_inverse_jacobian(h, 0.9, 1e6);
        let a = [1.0 - 0.9 * 0.3, -0.09, -0.09, 1.0 - 0.9 * 0.2];
        let prod = [
            m[0] * a[0] + m[1] * a[2],
            m[0] * a[1] + m[1] * a[3],
            m[2] * a[0] + m[3] * a[2],
            m[2] * a[1] + m[3] * a[3],
        ];
        for (p, want) in prod.iter().zip([1.0, 0.0, 0.0, 1.0]) {
            assert!((p - want).abs() < 1e-12, "{prod:?}");
        }
        // Near a tangential critical curve (kappa + gamma = 1) the stretch is capped.
        let m = capped_inverse_jacobian([1.0, 0.0, 0.0], 1.0, 10.0);
        assert!(
            (m[0] - 10.0).abs() < 1e-12 && (m[3] - 1.0).abs() < 1e-12,
            "{m:?}"
        );
        // Negative parity keeps its sign.
        let m = capped_inverse_jacobian([3.0, 0.0, 0.0], 1.0, 10.0);
        assert!((m[0] + 0.5).abs() < 1e-12, "{m:?}");
    }
}

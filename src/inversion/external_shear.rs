//! An external shear in the inversion: the tidal field of mass beyond the grid
//! ([method §4]).
//!
//! The grid's cells all lie inside the field, and positive mass there cannot make the nearly
//! uniform shear that a neighbouring group, a filament or the cluster's own mass beyond the
//! field put on it: the cells bend into a lopsided map to mimic one, and the Einstein radius
//! grows. Lenstool models of clusters fit one as a `potentiel` of profile 14 (the CATS model
//! of AS1063: `gamma` 0.10 along 51 degrees). Here it is two more unknowns, the sky-frame
//! components `gamma1`, `gamma2` at `D_ls/D_s = 1` about the field's centre `c`:
//!
//! ```text
//! alpha_shear(theta) = (gamma1 dx + gamma2 dy, gamma2 dx - gamma1 dy),   (dx, dy) = theta - c
//! ```
//!
//! scaled by each source's `f(z_s)` like every deflection (about another centre it differs
//! by a constant, which the sources' positions take). It has no convergence and no mass.
//!
//! The solver keeps every unknown non-negative, so each signed component is the difference of
//! two layers ([`super::Layer`] of kind [`LayerKind::ExternalShear`]): `+gamma1`, `-gamma1`,
//! `+gamma2`, `-gamma2`, each an [`ExternalShear`] of strength [`EXTERNAL_SHEAR_UNIT`] `u`
//! along 0, 90, 45 and 135 degrees, whose factors `C` give
//! `gamma1 = u (C_+1 - C_-1)` and `gamma2 = u (C_+2 - C_-2)`. Each layer has the prior
//! `C = 1 +- s` with `s = sigma / (u sqrt 2)`: the difference of a pair then has the Gaussian
//! prior `0 +- sigma` in `gamma` (`sigma` = [`super::GridConfig::external_shear_sigma`]), and
//! the pair's sum, which changes no deflection, is held at 2.
//!
//! [method §4]: crate::method#4-member-galaxies

use std::sync::Arc;

use glam::DVec2;
use serde::Serialize;

use super::members::{Layer, LayerKind};
use crate::profiles::{ExternalShear, Lens};

/// Strength of each external-shear layer at `C = 1` (a cluster's external shear is 0.01 -
/// 0.2, so the factors stay of order 1, as the members' do).
pub const EXTERNAL_SHEAR_UNIT: f64 = 0.1;

/// The four layers of an external shear about `center` (arcsec) with the prior `0 +- sigma`
/// on each of `gamma1`, `gamma2` (see the module documentation), in the order `+gamma1`,
/// `-gamma1`, `+gamma2`, `-gamma2`.
pub fn external_shear_layers(center: DVec2, sigma: f64) -> Vec<Layer> {
    let s = sigma / (EXTERNAL_SHEAR_UNIT * std::f64::consts::SQRT_2);
    [
        ("external shear +gamma1", 1u8, false, 0.0),
        ("external shear -gamma1", 1, true, 90.0),
        ("external shear +gamma2", 2, false, 45.0),
        ("external shear -gamma2", 2, true, 135.0),
    ]
    .into_iter()
    .map(|(name, component, negative, pa_deg)| {
        // A finite centre, a positive strength and a finite angle: cannot fail.
        let shear = ExternalShear::new(center, EXTERNAL_SHEAR_UNIT, pa_deg)
            .expect("a unit shear about a finite centre");
        Layer {
            name: name.to_string(),
            members: Vec::new(),
            lens: Arc::new(Lens::new(vec![Box::new(shear)])),
            prior_sigma: Some(s),
            kind: LayerKind::ExternalShear {
                component,
                negative,
            },
        }
    })
    .collect()
}

/// The external shear of a solution (`summary.json`'s `external_shear`), at
/// `D_ls/D_s = 1` as Lenstool's profile 14 gives it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ExternalShearFit {
    pub gamma1: f64,
    pub gamma2: f64,
    /// `sqrt(gamma1^2 + gamma2^2)`, Lenstool's `gamma`.
    pub gamma: f64,
    /// The stretching axis, degrees counter-clockwise from +x (West) in (-90, 90], Lenstool's
    /// `angle_pos`.
    pub angle_deg: f64,
    /// The prior's width on each component.
    pub prior_sigma: f64,
}

/// The external shear a solution's layer factors give, or `None` when no layer is an
/// external shear's.
pub fn external_shear_of(layers: &[Layer], factors: &[f64]) -> Option<ExternalShearFit> {
    let mut gamma = [0.0; 2];
    let mut prior_sigma = None;
    for (layer, &c) in layers.iter().zip(factors) {
        if let LayerKind::ExternalShear {
            component,
            negative,
        } = layer.kind
        {
            prior_sigma = layer
                .prior_sigma
                .map(|s| s * EXTERNAL_SHEAR_UNIT * std::f64::consts::SQRT_2);
            let sign = if negative { -1.0 } else { 1.0 };
            gamma[usize::from(component == 2)] += sign * EXTERNAL_SHEAR_UNIT * c;
        }
    }
    let prior_sigma = prior_sigma?;
    let [gamma1, gamma2] = gamma;
    let (strength, angle_deg) = shear_strength_angle(gamma1, gamma2);
    Some(ExternalShearFit {
        gamma1,
        gamma2,
        gamma: strength,
        angle_deg,
        prior_sigma,
    })
}

/// Strength `gamma` and the angle (degrees counter-clockwise from +x, in (-90, 90]) of the
/// shear's stretching axis, as Lenstool's `gamma` and `angle_pos` give them, from its
/// components.
pub fn shear_strength_angle(gamma1: f64, gamma2: f64) -> (f64, f64) {
    let gamma = gamma1.hypot(gamma2);
    let mut angle = 0.5 * gamma2.atan2(gamma1).to_degrees();
    if angle <= -90.0 {
        angle += 180.0;
    }
    (gamma, angle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profiles::MassComponent;

    #[test]
    fn layers_add_up_to_the_shear_they_report() {
        let center = DVec2::new(3.0, -2.0);
        let layers = external_shear_layers(center, 0.1);
        let factors = [1.3, 0.7, 0.4, 1.6];
        let fit = external_shear_of(&layers, &factors).unwrap();
        let (g1, g2) = (fit.gamma1, fit.gamma2);
        assert!(
            (g1 - 0.06).abs() < 1e-12 && (g2 + 0.12).abs() < 1e-12,
            "{g1} {g2}"
        );
        assert!((fit.prior_sigma - 0.1).abs() < 1e-12);
        // The summed deflection is that of one shear with those components.
        let one = ExternalShear::from_components(center, g1, g2).unwrap();
        for p in [DVec2::new(10.0, 5.0), DVec2::new(-20.0, 30.0)] {
            let sum: DVec2 = layers
                .iter()
                .zip(factors)
                .map(|(l, c)| c * l.deflection(p))
                .sum();
            assert!((sum - one.deflection(p)).length() < 1e-12, "{sum} at {p}");
        }
        assert_eq!(external_shear_of(&[], &[]), None);
    }

    #[test]
    fn strength_and_angle_follow_lenstool() {
        // Lenstool's gamma 0.1 along 50 degrees: gamma1 = g cos 100, gamma2 = g sin 100.
        let (g1, g2) = (
            0.1 * 100f64.to_radians().cos(),
            0.1 * 100f64.to_radians().sin(),
        );
        let (g, a) = shear_strength_angle(g1, g2);
        assert!(
            (g - 0.1).abs() < 1e-12 && (a - 50.0).abs() < 1e-9,
            "{g} {a}"
        );
        // Along y: 90 degrees, in (-90, 90]; along the other diagonal: -45.
        assert_eq!(shear_strength_angle(-0.05, 0.0), (0.05, 90.0));
        let (_, a) = shear_strength_angle(0.0, -0.05);
        assert!((a + 45.0).abs() < 1e-12, "{a}");
    }
}

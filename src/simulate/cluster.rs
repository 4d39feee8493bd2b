//! The simulated A1689-like cluster (paper section 4, [method §8]): 94 elliptical NFW
//! galaxy halos ("galaxy-true"), a smooth cluster halo ("soft") of three elliptical NFW
//! components, and the perturbed galaxies ("galaxy-model").
//!
//! Galaxies. The brightest cluster galaxy (BCG, `L = 12 L*`) sits at the origin; a second bright
//! galaxy (`4 L*`) 65 arcsec to the North-East (as in A1689) heads a clump of 14 more galaxies
//! (Gaussian scatter of 9 arcsec); the other 78 follow a cored projected density
//! `Sigma ∝ 1/(1 + r^2/r_c^2)`, `r_c = 30 arcsec`, flattened along the main halo (axis ratio
//! 0.8). Every galaxy lies inside the field (3 arcsec margin), no two within 3 arcsec, none
//! within 20 arcsec of the dark clump. Luminosities of all but the two bright ones follow a
//! Schechter function `dn/dL ∝ L^-1.2 exp(-L/L*)` in `[0.03, 3] L*`. Halo mass before
//! normalisation `M200 = 1.9e12 Msun (L/L*)`; concentration `c200 = 15 (M200/1e12 Msun)^-0.1`
//! (the Duffy et al. 2008 mass slope with about three times the field normalisation: halos in a
//! cluster core are stripped and concentrated), so the scale radius grows as
//! `r_s = r200/c200 ∝ M200^0.43` (13 kpc for 1e12 Msun at z = 0.185). Axis ratios are uniform
//! in [0.6, 0.95], position angles uniform (the BCG is aligned with the main halo).
//!
//! Soft halo: a main halo 3 arcsec from the BCG, a halo on the secondary clump (offset by
//! 5 arcsec from its bright galaxy) and a dark clump 77 arcsec South-West of the centre with
//! no galaxy within 20 arcsec ([`SOFT_HALOS`]).
//!
//! Normalisation: the projected masses inside the field square are measured by summing the
//! exact elliptical NFW convergence on a 1 arcsec grid; each set is then rescaled by one
//! factor applied to `rho_s` at fixed `r_s` (the convergence is linear in `rho_s`, so the
//! target is met exactly), giving galaxies = total/4 and soft = 3 total/4 with total
//! 2.58e14 Msun/h. The concentration law above holds for the drawn masses; the rescaling
//! moves `c200` by the normalisation factor (reported in the summary, close to 1).
//!
//! Galaxy-model: the same positions, `M200` and `r_s` each multiplied by `exp(sigma g)`
//! with independent standard normal `g` (`sigma = model_scatter`, default 0.2: ~20%).
//!
//! [method §8]: crate::method#8-the-papers-test

use glam::DVec2;

use super::rng::Rng;
use super::{SimulateError, SimulationConfig};
use crate::cosmology::LensPlane;
use crate::model::ComponentSpec;
use crate::profiles::{nfw_kappa, Nfw};

/// Number of galaxy halos (A1689's main halos in Coe et al. 2010, as in the paper).
pub const N_GALAXIES: usize = 94;
/// Total projected mass inside the field square: 2.58e14 Msun/h with h = 0.7, in Msun.
pub const TOTAL_FIELD_MASS_MSUN: f64 = 2.58e14 / 0.7;
/// Soft (cluster halo) to galaxy projected mass ratio inside the field.
pub const SOFT_TO_GALAXY: f64 = 3.0;

/// Luminosities (L/L*) of the BCG and of the bright galaxy of the secondary clump.
const BCG_L: f64 = 12.0;
const SECOND_L: f64 = 4.0;
/// Position of the secondary bright galaxy (arcsec; -x is East, +y North).
const SECOND_POS: [f64; 2] = [-48.0, 44.0];
/// Galaxies of the secondary clump besides its bright galaxy, and their Gaussian scatter.
const CLUMP_MEMBERS: usize = 14;
const CLUMP_SIGMA_ARCSEC: f64 = 9.0;
/// Core radius of the cored galaxy distribution and its axis ratio (along the main halo).
const CORE_RADIUS_ARCSEC: f64 = 30.0;
const GALAXY_DISTRIBUTION_Q: f64 = 0.8;
/// Position of the dark clump and the radius kept free of galaxies around it.
const DARK_POS: [f64; 2] = [58.0, -50.0];
const DARK_CLEAR_ARCSEC: f64 = 20.0;
/// Closest allowed galaxy pair and distance from the field edge.
const MIN_SEPARATION_ARCSEC: f64 = 3.0;
const EDGE_MARGIN_ARCSEC: f64 = 3.0;
/// Schechter slope and luminosity range (L/L*) of the ordinary galaxies.
const LF_ALPHA: f64 = -1.2;
const LF_RANGE: (f64, f64) = (0.03, 3.0);
/// M200 of an L* galaxy before normalisation, Msun.
const M200_LSTAR_MSUN: f64 = 1.9e12;
/// `c200 = C_GAL_1E12 (M200/1e12)^C_GAL_SLOPE`.
const C_GAL_1E12: f64 = 15.0;
const C_GAL_SLOPE: f64 = -0.1;
/// Axis-ratio range of the galaxy halos.
const GALAXY_Q_RANGE: (f64, f64) = (0.6, 0.95);
/// Major-axis position angle of the main halo (and the BCG), degrees.
const MAIN_PA_DEG: f64 = 35.0;
/// Grid step of the projected-mass measurement, arcsec.
const MASS_GRID_ARCSEC: f64 = 1.0;
/// Draws allowed when placing galaxies before giving up.
const MAX_POSITION_DRAWS: usize = 200_000;

/// The soft components: `(x, y, M200 before normalisation, c200, q, pa)` (arcsec, Msun,
/// degrees). A concentrated main halo (A1689 is famously over-concentrated), the clump halo
/// and the dark clump.
const SOFT_HALOS: [[f64; 6]; 3] = [
    [3.0, -1.5, 4.5e14, 24.0, 0.75, MAIN_PA_DEG],
    [-45.0, 40.0, 3.5e13, 6.0, 0.8, 110.0],
    [DARK_POS[0], DARK_POS[1], 2.0e13, 6.0, 0.85, 70.0],
];

/// One elliptical NFW halo (arcsec, Msun, degrees CCW from +x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Halo {
    pub(crate) center: DVec2,
    pub(crate) m200_msun: f64,
    pub(crate) c200: f64,
    pub(crate) q: f64,
    pub(crate) pa_deg: f64,
}

impl Halo {
    /// The model-file component (`nfw` with `q < 1` is the elliptical NFW).
    pub(crate) fn spec(&self) -> ComponentSpec {
        ComponentSpec::Nfw {
            x: self.center.x,
            y: self.center.y,
            m200: self.m200_msun,
            c200: self.c200,
            q: self.q,
            pa: self.pa_deg,
        }
    }
}

/// The cluster: soft halo, true and model galaxies, masses inside the field (Msun) and the
/// normalisation factors applied to `rho_s`.
#[derive(Debug, Clone)]
pub(crate) struct Cluster {
    pub(crate) soft: Vec<Halo>,
    pub(crate) galaxies_true: Vec<Halo>,
    pub(crate) galaxies_model: Vec<Halo>,
    pub(crate) soft_mass_msun: f64,
    pub(crate) galaxy_mass_msun: f64,
    pub(crate) galaxy_norm: f64,
    pub(crate) soft_norm: f64,
}

/// Builds the cluster of `config` on `plane` (module documentation).
pub(crate) fn build_cluster(
    config: &SimulationConfig,
    plane: &LensPlane,
) -> Result<Cluster, SimulateError> {
    let mut rng = Rng::stream(config.seed, 1);
    let half = 0.5 * config.field_arcsec;
    let positions = draw_positions(&mut rng, half)?;
    let mut galaxies = Vec::with_capacity(N_GALAXIES);
    for (k, &center) in positions.iter().enumerate() {
        let l = match k {
            0 => BCG_L,
            1 => SECOND_L,
            _ => draw_luminosity(&mut rng),
        };
        let m200_msun = M200_LSTAR_MSUN * l;
        let q = rng.range(GALAXY_Q_RANGE.0, GALAXY_Q_RANGE.1);
        let pa = rng.range(0.0, 180.0);
        galaxies.push(Halo {
            center,
            m200_msun,
            c200: C_GAL_1E12 * (m200_msun / 1e12).powf(C_GAL_SLOPE),
            q: if k == 0 { 0.75 } else { q },
            pa_deg: if k == 0 { MAIN_PA_DEG } else { pa },
        });
    }
    let soft: Vec<Halo> = SOFT_HALOS
        .iter()
        .map(|&[x, y, m, c, q, pa]| Halo {
            center: DVec2::new(x, y),
            m200_msun: m,
            c200: c,
            q,
            pa_deg: pa,
        })
        .collect();
    let galaxy_target = TOTAL_FIELD_MASS_MSUN / (1.0 + SOFT_TO_GALAXY);
    let soft_target = TOTAL_FIELD_MASS_MSUN - galaxy_target;
    let galaxy_raw = field_mass_msun(&galaxies, plane, config.field_arcsec)?;
    let soft_raw = field_mass_msun(&soft, plane, config.field_arcsec)?;
    let (galaxy_norm, soft_norm) = (galaxy_target / galaxy_raw, soft_target / soft_raw);
    let galaxies_true = rescale_all(&galaxies, galaxy_norm, plane)?;
    let soft = rescale_all(&soft, soft_norm, plane)?;
    let mut model_rng = Rng::stream(config.seed, 2);
    let galaxies_model = galaxies_true
        .iter()
        .map(|h| perturb(h, config.model_scatter, &mut model_rng, plane))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Cluster {
        // The convergence is linear in rho_s at fixed r_s: the rescaled masses are exact.
        soft_mass_msun: soft_norm * soft_raw,
        galaxy_mass_msun: galaxy_norm * galaxy_raw,
        soft,
        galaxies_true,
        galaxies_model,
        galaxy_norm,
        soft_norm,
    })
}

/// Galaxy positions: BCG, secondary bright galaxy, its clump, then the cored distribution.
fn draw_positions(rng: &mut Rng, half: f64) -> Result<Vec<DVec2>, SimulateError> {
    let second = DVec2::from(SECOND_POS);
    let dark = DVec2::from(DARK_POS);
    let mut out = vec![DVec2::ZERO, second];
    let limit = half - EDGE_MARGIN_ARCSEC;
    let axis = DVec2::from_angle(MAIN_PA_DEG.to_radians());
    // Inverse CDF of the cored profile in radius out to the field corner: p(r) ∝ r/(1 + r²/rc²).
    let rc2 = CORE_RADIUS_ARCSEC * CORE_RADIUS_ARCSEC;
    let log_max = (2.0 * half * half / rc2).ln_1p();
    for _ in 0..MAX_POSITION_DRAWS {
        if out.len() == N_GALAXIES {
            return Ok(out);
        }
        let p = if out.len() < 2 + CLUMP_MEMBERS {
            second + CLUMP_SIGMA_ARCSEC * DVec2::new(rng.normal(), rng.normal())
        } else {
            let r = CORE_RADIUS_ARCSEC * (rng.uniform() * log_max).exp_m1().sqrt();
            let phi = rng.range(0.0, std::f64::consts::TAU);
            // Flattened along the main halo: major axis stretched, minor squeezed (area kept).
            let s = GALAXY_DISTRIBUTION_Q.sqrt();
            let local = DVec2::new(r * phi.cos() / s, r * phi.sin() * s);
            axis.rotate(local)
        };
        let inside = p.x.abs() <= limit && p.y.abs() <= limit;
        let apart = out.iter().all(|o| o.distance(p) >= MIN_SEPARATION_ARCSEC);
        if inside && apart && p.distance(dark) >= DARK_CLEAR_ARCSEC {
            out.push(p);
        }
    }
    Err(SimulateError::Placement {
        what: "galaxy positions".into(),
        attempts: MAX_POSITION_DRAWS,
    })
}

/// One luminosity (L/L*) from `L^alpha exp(-L)` in [`LF_RANGE`], by rejection from a
/// log-uniform proposal (acceptance ∝ `L^(alpha+1) exp(-L)`, largest at the faint end).
fn draw_luminosity(rng: &mut Rng) -> f64 {
    let (lo, hi) = LF_RANGE;
    let weight = |l: f64| l.powf(LF_ALPHA + 1.0) * (-l).exp();
    let w_max = weight(lo);
    loop {
        let l = lo * (hi / lo).powf(rng.uniform());
        if rng.uniform() * w_max <= weight(l) {
            return l;
        }
    }
}

/// `mu(c) = ln(1 + c) - c/(1 + c)`.
fn nfw_mu(c: f64) -> f64 {
    c.ln_1p() - c / (1.0 + c)
}

/// `r200` in Mpc of a halo of `m200_msun` on `plane` (mean density 200 rho_crit(z_l)).
pub(crate) fn r200_mpc(m200_msun: f64, plane: &LensPlane) -> f64 {
    (3.0 * m200_msun / (800.0 * std::f64::consts::PI * plane.rho_crit_msun_per_mpc3)).cbrt()
}

/// `(rho_s [Msun/Mpc^3], r_s [Mpc])` of a halo.
fn rho_s_r_s(h: &Halo, plane: &LensPlane) -> (f64, f64) {
    let rho_c = plane.rho_crit_msun_per_mpc3;
    let rho_s = 200.0 / 3.0 * rho_c * h.c200.powi(3) / nfw_mu(h.c200);
    (rho_s, r200_mpc(h.m200_msun, plane) / h.c200)
}

/// The halo with the same `r_s` and `s` times its `rho_s`: `c200` solves
/// `(200/3) rho_crit c^3 / mu(c) = s rho_s` (bisection in log c), `M200 = (800 pi/3) rho_crit
/// (c r_s)^3`.
fn rescale(h: &Halo, s: f64, plane: &LensPlane) -> Result<Halo, SimulateError> {
    let (rho_s, r_s) = rho_s_r_s(h, plane);
    let c = c200_for_rho_s(s * rho_s, plane).ok_or(SimulateError::Normalisation {
        what: "halo concentration",
        value: s,
    })?;
    let m200 =
        800.0 / 3.0 * std::f64::consts::PI * plane.rho_crit_msun_per_mpc3 * (c * r_s).powi(3);
    Ok(Halo {
        m200_msun: m200,
        c200: c,
        ..*h
    })
}

fn rescale_all(halos: &[Halo], s: f64, plane: &LensPlane) -> Result<Vec<Halo>, SimulateError> {
    halos.iter().map(|h| rescale(h, s, plane)).collect()
}

/// `c` with `(200/3) rho_crit c^3 / mu(c) = rho_s` in [1e-2, 1e3], or `None`.
fn c200_for_rho_s(rho_s: f64, plane: &LensPlane) -> Option<f64> {
    let g = |c: f64| 200.0 / 3.0 * plane.rho_crit_msun_per_mpc3 * c.powi(3) / nfw_mu(c) - rho_s;
    let (mut lo, mut hi) = (1.0e-2_f64, 1.0e3_f64);
    if !(rho_s.is_finite() && g(lo) <= 0.0 && g(hi) >= 0.0) {
        return None;
    }
    for _ in 0..100 {
        let mid = (lo * hi).sqrt();
        if g(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some((lo * hi).sqrt())
}

/// The galaxy-model halo: `M200` and `r_s` each times `exp(sigma g)`.
fn perturb(h: &Halo, sigma: f64, rng: &mut Rng, plane: &LensPlane) -> Result<Halo, SimulateError> {
    let (_, r_s) = rho_s_r_s(h, plane);
    let m200 = h.m200_msun * (sigma * rng.normal()).exp();
    let r_s = r_s * (sigma * rng.normal()).exp();
    let c200 = r200_mpc(m200, plane) / r_s;
    if !(1.0e-2..=1.0e3).contains(&c200) {
        return Err(SimulateError::Normalisation {
            what: "galaxy-model concentration",
            value: c200,
        });
    }
    Ok(Halo {
        m200_msun: m200,
        c200,
        ..*h
    })
}

/// Projected mass in Msun of `halos` inside the square field of side `field_arcsec` centred on
/// the origin: the exact elliptical NFW convergence `kappa_NFW(R)`, `R^2 = q x'^2 + y'^2/q`,
/// summed at the centres of a [`MASS_GRID_ARCSEC`] grid, times `Sigma_cr_ref` and the cell area.
pub(crate) fn field_mass_msun(
    halos: &[Halo],
    plane: &LensPlane,
    field_arcsec: f64,
) -> Result<f64, SimulateError> {
    let n = (field_arcsec / MASS_GRID_ARCSEC).ceil().max(1.0) as usize;
    let step = field_arcsec / n as f64;
    let mut total = 0.0;
    for (index, h) in halos.iter().enumerate() {
        let nfw = Nfw::new(h.center, h.m200_msun, h.c200, plane)
            .map_err(|source| SimulateError::Halo { index, source })?;
        let (r_s, kappa_s) = (nfw.r_s_arcsec(), nfw.kappa_s());
        let axis = DVec2::from_angle(h.pa_deg.to_radians());
        let mut sum = 0.0;
        for j in 0..n {
            let y = -0.5 * field_arcsec + (j as f64 + 0.5) * step;
            for i in 0..n {
                let x = -0.5 * field_arcsec + (i as f64 + 0.5) * step;
                let d = DVec2::new(x, y) - h.center;
                let (xp, yp) = (d.dot(axis), axis.perp_dot(d));
                let r = (h.q * xp * xp + yp * yp / h.q).sqrt();
                sum += nfw_kappa(DVec2::new(r, 0.0), r_s, kappa_s);
            }
        }
        total += sum;
    }
    Ok(total * step * step * plane.sigma_cr_ref_msun_per_arcsec2)
}

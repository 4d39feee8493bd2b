//! Truncated NFW halo of Baltz, Marshall & Oguri (2009, JCAP 01, 015), the profile lenstronomy
//! calls `TNFW`: `rho(r) = rho_s / (x (1 + x)^2) * tau^2 / (tau^2 + x^2)`, `x = r / r_s`,
//! `tau = r_trunc / r_s`, with `rho_s` and `r_s` from M200 and c200 exactly as for
//! [`super::Nfw`] (the truncation is applied afterwards, so M200 is that of the parent NFW).
//!
//! With `T = tau^2`, `S = sqrt(T + x^2)`, `L = ln(x / (S + tau))` and the NFW `F`, `G`, `h`
//! ([`nfw_terms`]), the projected mass inside `x` is `4 pi rho_s r_s^3 m(x)` with
//! (BMO09 appendix A)
//! `m = T/(T+1)^2 [(T + 1 + 2(x^2 - 1)) F + pi tau + (T - 1) ln tau + S (-pi + (T-1) L / tau)]`,
//! evaluated here in the cancellation-free form
//! `m = T/(T+1)^2 [(T-1)(h - ln(1 + x^2/(2 tau (S+tau))) + x^2 L/(tau (S+tau))) + 2 x^2 F
//!  - pi x^2/(tau + S)]`,
//! and (from `kappa = 2 kappa_s m'(x)/x`)
//! `kappa = 2 kappa_s T/(T+1)^2 [(T+1) G + 2F - pi/S + (T-1) L/(tau S)]`,
//! `alpha = 4 kappa_s r_s m(x)/x`, mean convergence `4 kappa_s m/x^2`.
//! Total mass `4 pi rho_s r_s^3 T/(T+1)^2 [(T-1) ln tau + pi tau - (T+1)]`.
//!
//! Far field: for `x >= FAR_FIELD_FACTOR * max(1, tau)` the exact Laurent series
//! `m = m_tot + T sum_{k=2..K} c_k x^-k` (derived from the closed form; `c_2 = -1/3`,
//! `c_3 = pi/8`, ... see [`far_field_coefficients`]) replaces all transcendental functions
//! by one polynomial; truncated at `K = FAR_FIELD_TERMS` it matches the closed form to
//! about 1e-13 relative in `m` and 1e-11 in `kappa` (tests/physics/nfw.rs). A point mass of the total
//! mass would need `x > 500 tau` for 1e-6, since the mass outside `R` falls only as `T/(3 x^2)`.
//!
//! Near field: from `x = 2^-8` out to the far-field radius, `m/x^2` and `m'(x)/x` come from a
//! table of polynomials in `x^2` made from the closed form at the halo's first near-field
//! evaluation ([`super::tnfw_near`]: ~1e-13 relative, one polynomial in place of the closed
//! form's square root, logarithms and `atan`/`acosh`); closer to the centre, from the closed
//! form.

use std::sync::{Arc, Mutex};

use glam::DVec2;

use super::error::{require_finite_center, ProfileError};
use super::nfw_math::{axisymmetric_hessian, nfw_scales, nfw_terms, X_FLOOR};
use super::tnfw_near::{NearTable, Q_MIN};
use super::MassComponent;
use crate::cosmology::LensPlane;

use std::f64::consts::PI;

/// The far-field series is used beyond this many `max(1, tau)` scale radii.
pub const FAR_FIELD_FACTOR: f64 = 4.0;
/// Highest power of `1/x` kept in the far-field series (terms `k = 2..=FAR_FIELD_TERMS`).
pub const FAR_FIELD_TERMS: usize = 22;
/// Length of the far-field polynomials in `y = 1/x` (`FAR_FIELD_TERMS - 1` coefficients,
/// padded to a multiple of 4 for the four-way split evaluation).
const FAR_POLY_LEN: usize = (FAR_FIELD_TERMS - 1).div_ceil(4) * 4;
/// Accepted range of `tau = r_trunc / r_s`.
const TAU_RANGE: (f64, f64) = (1.0e-3, 1.0e4);

/// A truncated NFW halo (BMO09, lenstronomy `TNFW`).
#[derive(Debug, Clone, PartialEq)]
pub struct TruncatedNfw {
    center: DVec2,
    r_s_arcsec: f64,
    kappa_s: f64,
    m200_msun: f64,
    c200: f64,
    tau: f64,
    sigma_cr_ref_msun_per_arcsec2: f64,
    /// `m(infinity)`.
    m_tot: f64,
    /// `1 / r_s^2` in arcsec^-2.
    inv_r_s2: f64,
    /// `far_r2`: squared far-field radius in arcsec^2.
    far_r2_arcsec2: f64,
    /// `T c_(j+2)`, zero-padded: `m = m_tot + y^2 sum_j far_m_j y^j` with `y = 1/x`.
    far_m: [f64; FAR_POLY_LEN],
    /// `(j+2) T c_(j+2)`: `m'(x)/x = -y^4 sum_j far_dm_j y^j`.
    far_dm: [f64; FAR_POLY_LEN],
    /// The near field as polynomials ([`NearTable`]), made at the first near-field evaluation.
    near: NearCache,
}

/// A [`NearTable`] made on first use. It is a function of `tau` and its range alone, so it
/// takes no part in comparisons, and halos with the same two share one table
/// ([`shared_near_table`]): the members of a luminosity law all have `tau = r_t*/r_s*`, and
/// a table each (~11 kB) took 2.85 GB for 250,000 members.
#[derive(Debug, Clone, Default)]
struct NearCache(std::sync::OnceLock<Arc<NearTable>>);

/// Tables kept for sharing, the most recent last; older ones are dropped from the list (halos
/// that hold them keep them).
const SHARED_TABLES: usize = 32;

/// The near table of `(tau, q_end)`: one already made for the same two (bit for bit), or a new
/// one, kept for the next halo.
fn shared_near_table(tau: f64, q_end: f64) -> Arc<NearTable> {
    type Shared = Vec<((u64, u64), Arc<NearTable>)>;
    static TABLES: Mutex<Shared> = Mutex::new(Vec::new());
    let key = (tau.to_bits(), q_end.to_bits());
    // A poisoned lock (a panic while it was held) only loses the sharing.
    let found = TABLES.lock().ok().and_then(|tables| {
        tables
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, t)| Arc::clone(t))
    });
    if let Some(table) = found {
        return table;
    }
    // Made outside the lock: another thread may make the same table meanwhile (both are
    // correct; one is kept).
    let table = Arc::new(near_table(tau, q_end));
    if let Ok(mut tables) = TABLES.lock() {
        if !tables.iter().any(|(k, _)| *k == key) {
            if tables.len() == SHARED_TABLES {
                tables.remove(0);
            }
            tables.push((key, Arc::clone(&table)));
        }
    }
    table
}

impl PartialEq for NearCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Far-field coefficients `c_k(T)` (`k = 0..=FAR_FIELD_TERMS`, zero for `k < 2`) of
/// `m(x) = m_tot + T sum_k c_k x^-k`, from the large-`x` expansion of the BMO09 closed form
/// (checked against a symbolic expansion to k = 13 and mpmath to k = 25):
/// `c_2n = (-1)^n (2n-2)!!/(2n+1)!! sum_{j<n} (-1)^j (2j+1) T^(n-1-j)`,
/// `c_2n+1 = pi (-1)^(n+1) (2n-1)!!/(2n+2)!! sum_{j<n} (-1)^j (j+1) T^(n-1-j)`.
/// The series converges for `x > max(1, tau)`.
pub fn far_field_coefficients(tau: f64) -> [f64; FAR_FIELD_TERMS + 1] {
    let t2 = tau * tau;
    let dfact = |n: i64| -> f64 { (1..=n).rev().step_by(2).map(|k| k as f64).product() };
    let sign = |n: usize| if n % 2 == 0 { 1.0 } else { -1.0 };
    let mut c = [0.0; FAR_FIELD_TERMS + 1];
    for (k, ck) in c.iter_mut().enumerate().skip(2) {
        let n = k / 2;
        let poly =
            |w: fn(usize) -> f64| -> f64 { (0..n).fold(0.0, |acc, j| acc * t2 + sign(j) * w(j)) };
        *ck = if k % 2 == 0 {
            let ni = n as i64;
            sign(n) * dfact(2 * ni - 2) / dfact(2 * ni + 1) * poly(|j| (2 * j + 1) as f64)
        } else {
            let ni = n as i64;
            PI * sign(n + 1) * dfact(2 * ni - 1) / dfact(2 * ni + 2) * poly(|j| (j + 1) as f64)
        };
    }
    c
}

/// `m(infinity) = T/(T+1)^2 [(T-1) ln tau + pi tau - (T+1)]` (units of `4 pi rho_s r_s^3`).
pub fn tnfw_total_mass_unit(tau: f64) -> f64 {
    let t2 = tau * tau;
    t2 / ((t2 + 1.0) * (t2 + 1.0)) * ((t2 - 1.0) * tau.ln() + PI * tau - (t2 + 1.0))
}

/// Near-field closed forms `(m(x), m'(x)/x)` at `x = R / r_s` (dimensionless; see the module
/// documentation): `alpha = 4 kappa_s r_s m/x`, `kappa = 2 kappa_s m'(x)/x`.
pub fn tnfw_mass_and_kappa_unit(x: f64, tau: f64) -> (f64, f64) {
    let x = x.max(X_FLOOR);
    let t2 = tau * tau;
    let pref = t2 / ((t2 + 1.0) * (t2 + 1.0));
    let nfw = nfw_terms(x);
    let xx = x * x;
    let s = (t2 + xx).sqrt();
    let sp = s + tau;
    let l = (x / sp).ln();
    let m = pref
        * ((t2 - 1.0) * (nfw.h - (0.5 * xx / (tau * sp)).ln_1p() + xx * l / (tau * sp))
            + 2.0 * xx * nfw.f
            - PI * xx / sp);
    let dm_over_x = pref * ((t2 + 1.0) * nfw.g + 2.0 * nfw.f - PI / s + (t2 - 1.0) * l / (tau * s));
    (m, dm_over_x)
}

impl TruncatedNfw {
    /// A truncated NFW at `center` (arcsec) with parent-NFW `m200_msun` and `c200` (as
    /// [`super::Nfw::new`]) and truncation radius `r_trunc_arcsec` (arcsec). Errors name the
    /// field (`x`, `y`, `m200`, `c200`, `r_trunc`; `r_trunc / r_s` must be in [1e-3, 1e4]).
    pub fn new(
        center: DVec2,
        m200_msun: f64,
        c200: f64,
        r_trunc_arcsec: f64,
        plane: &LensPlane,
    ) -> Result<Self, ProfileError> {
        let center = require_finite_center("tnfw", center)?;
        let scales = nfw_scales("tnfw", m200_msun, c200, plane)?;
        let tau = r_trunc_arcsec / scales.r_s_arcsec;
        if !(r_trunc_arcsec.is_finite() && (TAU_RANGE.0..=TAU_RANGE.1).contains(&tau)) {
            return Err(ProfileError::BadParameter {
                component: "tnfw",
                field: "r_trunc",
                value: r_trunc_arcsec,
                reason: "r_trunc must be finite and r_trunc / r_s in [1e-3, 1e4]",
            });
        }
        let t2 = tau * tau;
        let c = far_field_coefficients(tau);
        let mut far_m = [0.0; FAR_POLY_LEN];
        let mut far_dm = [0.0; FAR_POLY_LEN];
        for k in 2..=FAR_FIELD_TERMS {
            far_m[k - 2] = t2 * c[k];
            far_dm[k - 2] = k as f64 * t2 * c[k];
        }
        let far_r = FAR_FIELD_FACTOR * tau.max(1.0) * scales.r_s_arcsec;
        Ok(Self {
            center,
            r_s_arcsec: scales.r_s_arcsec,
            kappa_s: scales.kappa_s,
            m200_msun,
            c200,
            tau,
            sigma_cr_ref_msun_per_arcsec2: plane.sigma_cr_ref_msun_per_arcsec2,
            m_tot: tnfw_total_mass_unit(tau),
            inv_r_s2: 1.0 / (scales.r_s_arcsec * scales.r_s_arcsec),
            far_r2_arcsec2: far_r * far_r,
            far_m,
            far_dm,
            near: NearCache::default(),
        })
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }
    /// Scale radius in arcsec.
    pub fn r_s_arcsec(&self) -> f64 {
        self.r_s_arcsec
    }
    /// `kappa_s = rho_s r_s / Sigma_cr_ref` of the parent NFW.
    pub fn kappa_s(&self) -> f64 {
        self.kappa_s
    }
    /// M200 of the parent (untruncated) NFW in Msun.
    pub fn m200_msun(&self) -> f64 {
        self.m200_msun
    }
    /// Concentration c200 of the parent NFW.
    pub fn c200(&self) -> f64 {
        self.c200
    }
    /// Truncation radius in arcsec.
    pub fn r_trunc_arcsec(&self) -> f64 {
        self.tau * self.r_s_arcsec
    }
    /// `tau = r_trunc / r_s`.
    pub fn tau(&self) -> f64 {
        self.tau
    }
    /// Total (3-D = projected) mass in Msun: `4 pi kappa_s Sigma_cr_ref r_s^2 m(infinity)`.
    pub fn total_mass_msun(&self) -> f64 {
        4.0 * PI
            * self.kappa_s
            * self.sigma_cr_ref_msun_per_arcsec2
            * self.r_s_arcsec
            * self.r_s_arcsec
            * self.m_tot
    }
    /// Projected mass inside radius `r_arcsec` (arcsec) in Msun: `pi R^2 Sigma_cr_ref mean_kappa`.
    pub fn mass_cylinder_msun(&self, r_arcsec: f64) -> f64 {
        let d = DVec2::new(r_arcsec.abs(), 0.0);
        PI * r_arcsec * r_arcsec * self.sigma_cr_ref_msun_per_arcsec2 * self.eval(d).1
    }

    /// Convergence, deflection (arcsec) and Hessian `[xx, xy, yy]` at `p` (arcsec) in one
    /// evaluation of the profile (cheaper than the three trait calls).
    pub fn fields(&self, p: DVec2) -> (f64, DVec2, [f64; 3]) {
        let d = p - self.center;
        let (kappa, mean_kappa) = self.eval(d);
        let hessian = axisymmetric_hessian(d, d.length(), kappa, mean_kappa);
        (kappa, d * mean_kappa, hessian)
    }

    /// `(kappa, mean kappa inside r)` at offset `d` (arcsec) from the centre.
    #[inline]
    fn eval(&self, d: DVec2) -> (f64, f64) {
        let r2 = d.length_squared();
        if r2 >= self.far_r2_arcsec2 {
            let y = self.r_s_arcsec / r2.sqrt();
            let (m, dm) = (poly4(&self.far_m, y), poly4(&self.far_dm, y));
            let y2 = y * y;
            let m = self.m_tot + m * y2;
            let dm_over_x = -dm * y2 * y2;
            return (2.0 * self.kappa_s * dm_over_x, 4.0 * self.kappa_s * m * y2);
        }
        let q = r2 * self.inv_r_s2;
        if q >= Q_MIN {
            let table = self
                .near
                .0
                .get_or_init(|| shared_near_table(self.tau, self.far_r2_arcsec2 * self.inv_r_s2));
            if let Some((mean_unit, dm_over_x)) = table.eval(q) {
                return (
                    2.0 * self.kappa_s * dm_over_x,
                    4.0 * self.kappa_s * mean_unit,
                );
            }
        }
        let x = (r2.sqrt() / self.r_s_arcsec).max(X_FLOOR);
        let (m, dm_over_x) = tnfw_mass_and_kappa_unit(x, self.tau);
        (
            2.0 * self.kappa_s * dm_over_x,
            4.0 * self.kappa_s * m / (x * x),
        )
    }
}

/// The [`NearTable`] of `(m/x^2, m'(x)/x)` from [`tnfw_mass_and_kappa_unit`] for `tau`,
/// covering `Q_MIN <= q < q_end`.
fn near_table(tau: f64, q_end: f64) -> NearTable {
    NearTable::new(q_end, |q| {
        let (m, dm_over_x) = tnfw_mass_and_kappa_unit(q.sqrt(), tau);
        [m / q, dm_over_x]
    })
}

/// `sum_j c_j y^j` by four interleaved Horner chains in `y^4` (shorter dependency chains than
/// one Horner pass; `c.len()` is a multiple of 4).
#[inline]
fn poly4(c: &[f64; FAR_POLY_LEN], y: f64) -> f64 {
    let y2 = y * y;
    let y4 = y2 * y2;
    let mut acc = [0.0; 4];
    for g in c.chunks_exact(4).rev() {
        for l in 0..4 {
            acc[l] = acc[l] * y4 + g[l];
        }
    }
    acc[0] + y * acc[1] + y2 * (acc[2] + y * acc[3])
}

impl MassComponent for TruncatedNfw {
    /// `2 kappa_s m'(x)/x`.
    fn kappa(&self, p: DVec2) -> f64 {
        self.eval(p - self.center).0
    }
    /// `alpha = mean_kappa * d`, i.e. `4 kappa_s r_s m(x)/x` along `d/|d|`.
    fn deflection(&self, p: DVec2) -> DVec2 {
        let d = p - self.center;
        d * self.eval(d).1
    }
    /// From `kappa` and `gamma_t = mean_kappa - kappa`.
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        let d = p - self.center;
        let (kappa, mean_kappa) = self.eval(d);
        axisymmetric_hessian(d, d.length(), kappa, mean_kappa)
    }
    fn deflection_hessian(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        let (_, alpha, hessian) = self.fields(p);
        (alpha, hessian)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_near_table_matches_the_closed_form() {
        assert_eq!(Q_MIN, 2f64.powi(-16));
        // The closed form itself loses digits where kappa is tiny against its terms (tau =
        // 1e-3, x >> tau: kappa ~ 1e-9 of its central value; the table is the smoother of the
        // two there), so that case is held to 1e-10. tests/physics/nfw.rs checks the fields against
        // 50-digit values.
        for (tau, rtol) in [
            (1e-3, 1e-10),
            (0.3, 1e-12),
            (1.0, 1e-12),
            (4.0, 1e-12),
            (37.0, 1e-12),
            (1e4, 1e-12),
        ] {
            let q_end = (4.0 * f64::max(tau, 1.0)).powi(2);
            let table = near_table(tau, q_end);
            let mut worst = [0.0f64; 2];
            let steps = 20000;
            for i in 0..steps {
                let q = Q_MIN * (q_end / Q_MIN).powf((i as f64 + 0.37) / steps as f64);
                let (a, b) = table.eval(q).expect("inside the table");
                let (m, dm) = tnfw_mass_and_kappa_unit(q.sqrt(), tau);
                worst[0] = worst[0].max((a - m / q).abs() / (m / q).abs());
                worst[1] = worst[1].max((b - dm).abs() / dm.abs());
            }
            assert!(worst[0] < rtol && worst[1] < rtol, "tau {tau}: {worst:?}");
            assert!(table.eval(Q_MIN * 0.999).is_none());
            assert!(table.eval(4.0 * q_end).is_none());
        }
    }

    /// Halos with the same `tau` (the members of a luminosity law) share one near table, and
    /// give the same fields as with a table of their own; another `tau` gets its own.
    #[test]
    fn halos_of_one_tau_share_their_near_table() {
        let plane = LensPlane::new(crate::cosmology::Cosmology::default(), 0.3).unwrap();
        let halo = |x: f64, r_t: f64| {
            TruncatedNfw::new(DVec2::new(x, 0.0), 1e12, 8.0, r_t, &plane).unwrap()
        };
        let (a, b, other) = (halo(0.0, 7.0), halo(50.0, 7.0), halo(0.0, 9.0));
        let p = DVec2::new(0.3, 0.2);
        let own = near_table(a.tau, a.far_r2_arcsec2 * a.inv_r_s2);
        let q = p.length_squared() * a.inv_r_s2;
        assert_eq!(a.kappa(p), {
            let (_, dm_over_x) = own.eval(q).unwrap();
            2.0 * a.kappa_s * dm_over_x
        });
        b.kappa(p + DVec2::new(50.0, 0.0));
        other.kappa(p);
        let table = |h: &TruncatedNfw| Arc::clone(h.near.0.get().expect("made"));
        assert!(Arc::ptr_eq(&table(&a), &table(&b)));
        assert!(!Arc::ptr_eq(&table(&a), &table(&other)));
    }
}

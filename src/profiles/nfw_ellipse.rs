//! Elliptical NFW halo with the ellipticity in the convergence ([method §2];
//! lenstronomy's `NFW_ELLIPSE_CSE`): `kappa(x', y') = kappa_NFW(R)`, `R^2 = q x'^2 + y'^2 / q`,
//! `x'` along the major axis at position angle `pa` (degrees counter-clockwise from +x), so the
//! area inside each iso-density ellipse, and hence the enclosed mass, is that of the sphere.
//!
//! Deflection and Hessian use the cored-steep-ellipsoid (CSE) decomposition of Oguri (2021,
//! PASP 133, 074504): `G(x)/2 ~= sum_i a_i / (2 (s_i^2 + x^2)^(3/2))` with the 44 pairs
//! `(a_i, s_i)` of his Table 1 ([`CSE_TERMS`]); each CSE has a closed-form deflection and
//! Hessian for any axis ratio (his section 3; Hessian eqs. 21-23), here for one major-axis CSE
//! of `kappa = a / (2 (s^2 + X^2 + Y^2/q^2)^(3/2))`):
//! `psi = sqrt(q^2 (s^2 + X^2) + Y^2)`, `Phi = (psi + s)^2 + (1 - q^2) X^2`,
//! `alpha_X = (a q/s) X (psi + q^2 s)/(psi Phi)`, `alpha_Y = (a q/s) Y (psi + s)/(psi Phi)`.
//! The product-averaged radius is reached by scaling the coordinates by `sqrt(q)`
//! (`X = sqrt(q) x' / r_s`): the Hessian is unchanged and the deflection gains `1/sqrt(q)`.
//!
//! Accuracy of the fit (measured at q = 1 against the exact NFW, see tests/physics/nfw.rs), for
//! `1e-4 < R / r_s < 1e3`: convergence 4e-5 relative, deflection 5e-6, Hessian 2e-5 (of its
//! largest element). Beyond `~1e3 r_s` the CSE
//! convergence falls as `R^-3` instead of `R^-2`. The convergence returned by
//! [`MassComponent::kappa`] is the CSE sum, so that it equals half the trace of the Hessian;
//! [`NfwEllipse::kappa_exact`] gives the exact elliptical NFW convergence.
//!
//! [method §2]: crate::method#2-mass-components

use glam::DVec2;

use super::error::{require_finite_center, ProfileError};
use super::nfw_math::{nfw_scales, nfw_terms};
use super::MassComponent;
use crate::cosmology::LensPlane;

/// Oguri (2021) Table 1: `(s_i, a_i)` of the 44-term CSE fit to the NFW convergence
/// (`s_i` in units of `r_s`).
pub const CSE_TERMS: [(f64, f64); 44] = [
    (1.082411e-06, 1.648988e-18),
    (8.786566e-06, 6.274458e-16),
    (3.292868e-06, 3.646620e-17),
    (1.860019e-05, 3.459206e-15),
    (3.274231e-05, 2.457389e-14),
    (6.232485e-05, 1.059319e-13),
    (9.256333e-05, 4.211597e-13),
    (1.546762e-04, 1.142832e-12),
    (2.097321e-04, 4.391215e-12),
    (3.391140e-04, 1.556500e-11),
    (5.178790e-04, 6.951271e-11),
    (8.636736e-04, 3.147466e-10),
    (1.405152e-03, 1.379109e-09),
    (2.193855e-03, 3.829778e-09),
    (3.179572e-03, 1.384858e-08),
    (4.970987e-03, 5.370951e-08),
    (7.631970e-03, 1.804384e-07),
    (1.119413e-02, 5.788608e-07),
    (1.827267e-02, 3.205256e-06),
    (2.945251e-02, 1.102422e-05),
    (4.562723e-02, 4.093971e-05),
    (6.782509e-02, 1.282206e-04),
    (1.596987e-01, 4.575541e-04),
    (1.127751e-01, 7.995270e-04),
    (2.169469e-01, 5.013701e-03),
    (3.423835e-01, 1.403508e-02),
    (5.194527e-01, 5.230727e-02),
    (8.623185e-01, 1.898907e-01),
    (1.382737e+00, 3.643448e-01),
    (2.034929e+00, 7.203734e-01),
    (3.402979e+00, 1.717667e+00),
    (5.594276e+00, 2.217566e+00),
    (8.052345e+00, 3.187447e+00),
    (1.349045e+01, 8.194898e+00),
    (2.603825e+01, 1.765210e+01),
    (4.736823e+01, 1.974319e+01),
    (6.559320e+01, 2.783688e+01),
    (1.087932e+02, 4.482311e+01),
    (1.477673e+02, 5.598897e+01),
    (2.495341e+02, 1.426485e+02),
    (4.305999e+02, 2.279833e+02),
    (7.760206e+02, 5.401335e+02),
    (2.143057e+03, 9.743682e+02),
    (1.935749e+03, 1.775124e+03),
];

/// Beyond this `R / r_s` the CSE set is replaced by a point of its total mass (relative error
/// below `max(s_i) / x ~ 2e-7`); it only keeps the arithmetic finite for absurd distances.
const X_POINT_LIMIT: f64 = 1.0e10;

/// Terms are evaluated in groups of `LANES` (structure of arrays), which lets the compiler
/// use SIMD square roots and divisions; 44 = 11 x 4.
const LANES: usize = 4;
/// Number of lane groups.
const CHUNKS: usize = CSE_TERMS.len() / LANES;

/// `q`-dependent constants of the CSE terms, in lane groups.
#[derive(Debug, Clone, PartialEq)]
struct CseLanes {
    s: [[f64; LANES]; CHUNKS],
    /// `q^2 s`.
    qqs: [[f64; LANES]; CHUNKS],
    /// `q^2 s^2`.
    qqss: [[f64; LANES]; CHUNKS],
    /// `s^2`.
    ss: [[f64; LANES]; CHUNKS],
    /// `a q / s`.
    k: [[f64; LANES]; CHUNKS],
    /// `a q^3 / 2`: `kappa_i = kappa_c / psi^3`.
    kappa_c: [[f64; LANES]; CHUNKS],
}

impl CseLanes {
    fn new(q: f64) -> Self {
        let field = |f: &dyn Fn(f64, f64) -> f64| {
            let mut out = [[0.0; LANES]; CHUNKS];
            for (i, (s, a)) in CSE_TERMS.iter().enumerate() {
                out[i / LANES][i % LANES] = f(*s, *a);
            }
            out
        };
        Self {
            s: field(&|s, _| s),
            qqs: field(&|s, _| q * q * s),
            qqss: field(&|s, _| q * q * s * s),
            ss: field(&|s, _| s * s),
            k: field(&|s, a| a * q / s),
            kappa_c: field(&|_, a| 0.5 * a * q * q * q),
        }
    }
}

/// An elliptical NFW halo (ellipticity in the convergence), evaluated by CSE decomposition.
#[derive(Debug, Clone, PartialEq)]
pub struct NfwEllipse {
    center: DVec2,
    r_s_arcsec: f64,
    kappa_s: f64,
    m200_msun: f64,
    c200: f64,
    q: f64,
    pa_deg: f64,
    /// `(cos pa, sin pa)`.
    axis: DVec2,
    terms: CseLanes,
    /// `sum_i a_i / s_i`: the CSE total mass is `4 pi kappa_s r_s^2` times this (arcsec^2).
    mass_sum: f64,
}

impl NfwEllipse {
    /// An elliptical NFW at `center` (arcsec) with `m200_msun`, `c200` as for
    /// [`super::Nfw::new`], axis ratio `0 < q <= 1` and major axis at `pa_deg` (degrees CCW from
    /// +x). Errors name the field (`x`, `y`, `m200`, `c200`, `q`, `pa`).
    pub fn new(
        center: DVec2,
        m200_msun: f64,
        c200: f64,
        q: f64,
        pa_deg: f64,
        plane: &LensPlane,
    ) -> Result<Self, ProfileError> {
        let center = require_finite_center("nfw_ellipse", center)?;
        let scales = nfw_scales("nfw_ellipse", m200_msun, c200, plane)?;
        // Below q = 0.01 the needle is no longer a sensible halo and Phi loses precision.
        if !(q.is_finite() && (0.01..=1.0).contains(&q)) {
            return Err(ProfileError::BadParameter {
                component: "nfw_ellipse",
                field: "q",
                value: q,
                reason: "the axis ratio must be in [0.01, 1]",
            });
        }
        if !pa_deg.is_finite() {
            return Err(ProfileError::BadParameter {
                component: "nfw_ellipse",
                field: "pa",
                value: pa_deg,
                reason: "the position angle in degrees must be finite",
            });
        }
        let pa = pa_deg.to_radians();
        let terms = CseLanes::new(q);
        Ok(Self {
            center,
            r_s_arcsec: scales.r_s_arcsec,
            kappa_s: scales.kappa_s,
            m200_msun,
            c200,
            q,
            pa_deg,
            axis: DVec2::new(pa.cos(), pa.sin()),
            terms,
            mass_sum: CSE_TERMS.iter().map(|(s, a)| a / s).sum(),
        })
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }
    /// Scale radius in arcsec (along the product-averaged radius `R`).
    pub fn r_s_arcsec(&self) -> f64 {
        self.r_s_arcsec
    }
    /// `kappa_s = rho_s r_s / Sigma_cr_ref`.
    pub fn kappa_s(&self) -> f64 {
        self.kappa_s
    }
    /// M200 in Msun.
    pub fn m200_msun(&self) -> f64 {
        self.m200_msun
    }
    /// Concentration c200.
    pub fn c200(&self) -> f64 {
        self.c200
    }
    /// Axis ratio `q = b/a`.
    pub fn q(&self) -> f64 {
        self.q
    }
    /// Major-axis position angle in degrees CCW from +x.
    pub fn pa_deg(&self) -> f64 {
        self.pa_deg
    }

    /// `(x', y') / r_s` of the offset `d` (arcsec) in the major-axis frame.
    #[inline]
    fn sky_to_axis(&self, d: DVec2) -> DVec2 {
        let (c, s) = (self.axis.x, self.axis.y);
        DVec2::new(c * d.x + s * d.y, -s * d.x + c * d.y) / self.r_s_arcsec
    }

    /// Exact elliptical NFW convergence `2 kappa_s G(R / r_s)`, `R^2 = q x'^2 + y'^2/q`, at `p`
    /// (arcsec); the CSE sum of [`MassComponent::kappa`] approximates it to 4e-5.
    pub fn kappa_exact(&self, p: DVec2) -> f64 {
        let u = self.sky_to_axis(p - self.center);
        let x = (self.q * u.x * u.x + u.y * u.y / self.q).sqrt();
        2.0 * self.kappa_s * nfw_terms(x).g
    }

    /// Offset `d` (arcsec) to CSE coordinates `sqrt(q) (x', y') / r_s`, or `None` beyond
    /// `X_POINT_LIMIT r_s` where the point-mass limit is used.
    #[inline]
    fn cse_coords(&self, p: DVec2) -> Option<DVec2> {
        let u = self.sky_to_axis(p - self.center) * self.q.sqrt();
        (u.length_squared() < self.q * X_POINT_LIMIT * X_POINT_LIMIT).then_some(u)
    }

    /// CSE convergence `4 kappa_s sum_i a_i q^3 / (2 psi_i^3)` at `p` (arcsec).
    fn kappa_cse(&self, p: DVec2) -> f64 {
        let Some(u) = self.cse_coords(p) else {
            return 0.0;
        };
        let w = self.q * self.q * u.x * u.x + u.y * u.y;
        let t = &self.terms;
        let mut acc = [0.0; LANES];
        for c in 0..CHUNKS {
            let psi2: [f64; LANES] = std::array::from_fn(|l| t.qqss[c][l] + w);
            let term: [f64; LANES] =
                std::array::from_fn(|l| t.kappa_c[c][l] / (psi2[l] * psi2[l].sqrt()));
            for l in 0..LANES {
                acc[l] += term[l];
            }
        }
        let sum: f64 = acc.iter().sum();
        4.0 * self.kappa_s * sum
    }

    /// CSE deflection in arcsec at `p` (arcsec): `4 kappa_s r_s / sqrt(q)` times the sum of the
    /// major-axis CSE deflections, rotated back to the sky frame.
    fn deflection_cse(&self, p: DVec2) -> DVec2 {
        let Some(u) = self.cse_coords(p) else {
            return self.point_limit(p).1;
        };
        let (xx, yy) = (u.x * u.x, u.y * u.y);
        let q2 = self.q * self.q;
        let (w, e) = (q2 * xx + yy, 1.0 - q2);
        let t = &self.terms;
        let (mut acc_x, mut acc_y) = ([0.0; LANES], [0.0; LANES]);
        for c in 0..CHUNKS {
            let psi2: [f64; LANES] = std::array::from_fn(|l| t.qqss[c][l] + w);
            let psi: [f64; LANES] = psi2.map(f64::sqrt);
            let b: [f64; LANES] = std::array::from_fn(|l| psi[l] + t.s[c][l]);
            let psi_phi: [f64; LANES] = std::array::from_fn(|l| psi[l] * (b[l] * b[l] + e * xx));
            // K/(psi Phi)
            let k_psiphi: [f64; LANES] = std::array::from_fn(|l| t.k[c][l] / psi_phi[l]);
            for l in 0..LANES {
                acc_x[l] += k_psiphi[l] * (psi[l] + t.qqs[c][l]);
                acc_y[l] += k_psiphi[l] * b[l];
            }
        }
        let (ax, ay): (f64, f64) = (acc_x.iter().sum(), acc_y.iter().sum());
        let scale = 4.0 * self.kappa_s * self.r_s_arcsec / self.q.sqrt();
        self.axis_to_sky_vec(DVec2::new(ax * u.x, ay * u.y) * scale)
    }

    /// Convergence, deflection (arcsec) and Hessian `[xx, xy, yy]` at `p` (arcsec), summed over
    /// the CSE terms in one pass (one square root and one division per term).
    pub fn fields(&self, p: DVec2) -> (f64, DVec2, [f64; 3]) {
        let Some(u) = self.cse_coords(p) else {
            return self.point_limit(p);
        };
        let (x, y) = (u.x, u.y);
        let (xx, yy) = (x * x, y * y);
        let q2 = self.q * self.q;
        let (w, e) = (q2 * xx + yy, 1.0 - q2);
        let t = &self.terms;
        // Accumulators per lane: kappa, alpha_x, alpha_y, H_xx, H_xy / (x y); H_yy follows
        // from the trace, H_yy = 2 kappa - H_xx. Lane-wise array maps vectorise well.
        let mut acc = [[0.0; LANES]; 5];
        for c in 0..CHUNKS {
            let (s, qqs, qqss, k) = (t.s[c], t.qqs[c], t.qqss[c], t.k[c]);
            let psi2: [f64; LANES] = std::array::from_fn(|l| qqss[l] + w);
            let psi: [f64; LANES] = psi2.map(f64::sqrt);
            let b: [f64; LANES] = std::array::from_fn(|l| psi[l] + s[l]);
            let phi: [f64; LANES] = std::array::from_fn(|l| b[l] * b[l] + e * xx);
            let inv: [f64; LANES] = std::array::from_fn(|l| 1.0 / (psi2[l] * psi[l] * phi[l]));
            for l in 0..LANES {
                let r_phi = psi2[l] * psi[l] * inv[l]; // 1/Phi
                let r_psi3 = phi[l] * inv[l]; // 1/psi^3
                let r_psi2phi = psi[l] * inv[l]; // 1/(psi^2 Phi)
                let a = psi[l] + qqs[l];
                let k_psiphi = k[l] * psi2[l] * inv[l]; // K/(psi Phi)
                let k_phi = k[l] * r_phi;
                acc[0][l] += t.kappa_c[c][l] * r_psi3;
                acc[1][l] += k_psiphi * a;
                acc[2][l] += k_psiphi * b[l];
                acc[3][l] +=
                    k_phi * (1.0 + qqs[l] * (qqss[l] + yy) * r_psi3 - 2.0 * xx * a * a * r_psi2phi);
                acc[4][l] -= k_phi * (qqs[l] * r_psi3 + 2.0 * a * b[l] * r_psi2phi);
            }
        }
        let [kap, ax, ay, hxx, hxy] = acc.map(|lanes| lanes.iter().sum::<f64>());
        let hyy = 2.0 * kap - hxx;
        let norm = 4.0 * self.kappa_s;
        let alpha_axis = DVec2::new(ax * x, ay * y) * (norm * self.r_s_arcsec / self.q.sqrt());
        let h_axis = [norm * hxx, norm * hxy * x * y, norm * hyy];
        (
            norm * kap,
            self.axis_to_sky_vec(alpha_axis),
            self.axis_to_sky_hessian(h_axis),
        )
    }

    /// Fields of a point holding the CSE total mass `4 pi kappa_s r_s^2 sum a_i/s_i`, used
    /// beyond `X_POINT_LIMIT r_s` only.
    fn point_limit(&self, p: DVec2) -> (f64, DVec2, [f64; 3]) {
        let d = p - self.center;
        let r2 = d.length_squared();
        let m_over_pi = 4.0 * self.kappa_s * self.r_s_arcsec * self.r_s_arcsec * self.mass_sum;
        let c = m_over_pi / (r2 * r2);
        let h = [
            c * (d.y * d.y - d.x * d.x),
            -2.0 * c * d.x * d.y,
            c * (d.x * d.x - d.y * d.y),
        ];
        (0.0, d * (m_over_pi / r2), h)
    }

    /// Rotates a vector from the major-axis frame back to the sky frame.
    #[inline]
    fn axis_to_sky_vec(&self, v: DVec2) -> DVec2 {
        let (c, s) = (self.axis.x, self.axis.y);
        DVec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
    }

    /// Rotates a Hessian `[xx, xy, yy]` from the major-axis frame back to the sky frame.
    #[inline]
    fn axis_to_sky_hessian(&self, h: [f64; 3]) -> [f64; 3] {
        let (c, s) = (self.axis.x, self.axis.y);
        let (cc, ss, cs) = (c * c, s * s, c * s);
        [
            cc * h[0] - 2.0 * cs * h[1] + ss * h[2],
            cs * (h[0] - h[2]) + (cc - ss) * h[1],
            ss * h[0] + 2.0 * cs * h[1] + cc * h[2],
        ]
    }
}

impl MassComponent for NfwEllipse {
    fn kappa(&self, p: DVec2) -> f64 {
        self.kappa_cse(p)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        self.deflection_cse(p)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        self.fields(p).2
    }
    fn deflection_hessian(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        let (_, alpha, hessian) = self.fields(p);
        (alpha, hessian)
    }
}

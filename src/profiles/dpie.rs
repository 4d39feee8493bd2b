//! Dual pseudo-isothermal elliptical mass distribution (dPIE): Lenstool's profile 81
//! (Elíasdóttir et al. 2007, arXiv:0710.5636, appendix A; Kassiola & Kovner 1993, ApJ 417, 450).
//!
//! With the core radius `a`, the cut radius `s > a`, the Kassiola-Kovner ellipticity `eps` and
//! `rho^2 = x'^2/(1+eps)^2 + y'^2/(1-eps)^2` (`x'` along the major axis at `pa`):
//! `kappa = (b0/2) s/(s-a) [1/sqrt(a^2+rho^2) - 1/sqrt(s^2+rho^2)]` and
//! `alpha' = b0 s/(s-a) [I(a) - I(s)]`, where `I(w)` is the complex deflection of a unit PIEMD
//! with core `w` (Kassiola & Kovner 1993, section 4.1, their `I*_{0.5}`):
//! `alpha_x' + i alpha_y' = -i (1-eps^2)/(2 sqrt(eps)) ln(N/D)`, `N = A + iB`, `D = C + iE`,
//! `A = x' (1-eps)/(1+eps) - i y' (1+eps)/(1-eps)`, `B = 2 sqrt(eps) sqrt(w^2 + rho^2)`,
//! `C = x' - i y'`, `E = 2 sqrt(eps) w`. The total mass is `pi b0 s (1 - eps^2) Sigma_cr`.
//!
//! Lenstool conventions (read in its source, `set_lens.c`, `e_grad.c`, `e_grad2.c` of
//! github.com/cerschae/Lenstool-HPC, ChiBenchmark/lenstoolchi/src):
//! - `v_disp` is the "dPIE" dispersion `sigma`: `b0 = 6 pi (sigma/c)^2` (not `4 pi`). For
//!   `a -> 0, s -> inf` the dPIE becomes an SIS of dispersion `sqrt(3/2) sigma`; Elíasdóttir
//!   2007 writes `sigma_0^2 = (3/2) sigma_dPIE^2`, and lenstronomy's `PJAFFE` takes the
//!   SIS-equivalent dispersion (`LensCosmo.vel_disp_dPIED_sigma0`).
//! - `ellipticite` of profile 81 is the mass ellipticity `e = (A^2 - B^2)/(A^2 + B^2)` of the
//!   isodensity contours (axes `A`, `B`); the formulas use `eps = (1 - sqrt(1 - e^2))/e`
//!   (= `(A - B)/(A + B)`; Lenstool calls it `epot`). The isodensity axis ratio is
//!   `(1-eps)/(1+eps)`.
//! - `angle_pos` is degrees counter-clockwise from +x, as in the frame of [method §1].
//!
//! `N/D` is 0/0 at `(x', y') = (0, 2 sqrt(eps) w)`; as `N conj'(N) = D conj'(D)` with
//! `conj'(N) = A - iB`, `conj'(D) = C - iE` (`A^2 + B^2 = C^2 + E^2` exactly), the ratio equals
//! `(C - iE)/(A - iB)`, which is regular there, and is evaluated in that form where `|D|` is
//! the smaller denominator. The Hessian is the analytic derivative of the same expressions.
//! Below [`CIRCULAR_EPSILON`] the circular formulas are used (Elíasdóttir 2007 eq. A23):
//! `alpha = b0 s/(s-a) R [1/(sqrt(R^2+a^2)+a) - 1/(sqrt(R^2+s^2)+s)]`; every field is finite
//! at the centre (`kappa(0) = b0/(2a)`).
//!
//! A singular core (`a = 0`, Lenstool's `core_radius 0`) is allowed: the formulas above stay
//! finite for `a -> 0` except at the centre itself (`kappa ~ b0/(2 rho)`, `|alpha| -> b0` for
//! a circular dPIE), so they are evaluated with the core [`DPIE_SINGULAR_CORE_ARCSEC`]
//! (lenstronomy's `PJAFFE` floors its core at the same 1e-8 arcsec): the fields differ from
//! the singular ones by about `1e-8 arcsec / r` relative, far below any pixel, and stay finite
//! at the centre, as the SIS's do inside the same radius.
//!
//! [method §1]: crate::method#1-frames-and-units

use glam::DVec2;

use super::error::{require_finite_center, require_positive, require_sigma_v, ProfileError};
use super::MassComponent;
use crate::cosmology::LensPlane;
use crate::units::{ARCSEC_PER_RAD, C_KM_S};

/// Kassiola-Kovner ellipticity below which the circular formulas are used. The elliptical
/// ones lose about `1e-16/eps` relative precision and differ from the circle by `~eps`, so the
/// switch is continuous to about 1e-8 (Lenstool switches at 2e-4).
pub const CIRCULAR_EPSILON: f64 = 1.0e-8;

/// Core radius in arcsec with which a singular dPIE (`r_core = 0`) is evaluated: far below any
/// pixel, large enough that `1/a^3` stays finite (the floor of lenstronomy's `PJAFFE` core).
pub const DPIE_SINGULAR_CORE_ARCSEC: f64 = 1.0e-8;

/// `b0 = 6 pi (sigma/c)^2` in arcsec (`D_ls/D_s = 1`): the Lenstool dPIE strength for the
/// "dPIE" velocity dispersion `sigma_v_km_s` [km/s] (Elíasdóttir 2007 `E_0`).
pub fn dpie_b0_arcsec(sigma_v_km_s: f64) -> f64 {
    let beta = sigma_v_km_s / C_KM_S;
    6.0 * std::f64::consts::PI * beta * beta * ARCSEC_PER_RAD
}

/// Kassiola-Kovner `eps = (1 - sqrt(1 - e^2))/e = e/(1 + sqrt(1 - e^2))` from Lenstool's mass
/// ellipticity `e = (A^2 - B^2)/(A^2 + B^2)`, `0 <= e < 1`.
pub fn kk_epsilon(ellipticity: f64) -> f64 {
    ellipticity / (1.0 + (1.0 - ellipticity * ellipticity).sqrt())
}

/// A dPIE (Lenstool profile 81) at `center` (arcsec).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dpie {
    center: DVec2,
    b0_arcsec: f64,
    r_core_arcsec: f64,
    r_cut_arcsec: f64,
    /// The core the formulas use: `r_core_arcsec`, or [`DPIE_SINGULAR_CORE_ARCSEC`] for 0.
    core_eval_arcsec: f64,
    ellipticity: f64,
    epsilon: f64,
    pa_deg: f64,
    /// `cos pa`, `sin pa`.
    rot: DVec2,
}

impl Dpie {
    /// A dPIE with Lenstool's parameters: `v_disp` = `sigma_v_km_s` [km/s] (`b0 = 6 pi
    /// (sigma/c)^2`), core and cut radii in arcsec (`0 <= r_core < r_cut`, finite; a singular
    /// core `r_core = 0` is evaluated as in the module documentation), mass
    /// ellipticity `e = (A^2-B^2)/(A^2+B^2)` in `[0, 1)`, position angle `pa_deg` [degrees
    /// counter-clockwise from +x].
    pub fn new(
        center: DVec2,
        sigma_v_km_s: f64,
        r_core_arcsec: f64,
        r_cut_arcsec: f64,
        ellipticity: f64,
        pa_deg: f64,
    ) -> Result<Self, ProfileError> {
        let sigma_v_km_s = require_sigma_v("dpie", sigma_v_km_s)?;
        let bad = |field, value, reason| ProfileError::BadParameter {
            component: "dpie",
            field,
            value,
            reason,
        };
        if !(r_core_arcsec.is_finite() && r_core_arcsec >= 0.0) {
            return Err(bad(
                "r_core",
                r_core_arcsec,
                "must be finite and >= 0 (0 is a singular core)",
            ));
        }
        let r_core = r_core_arcsec;
        let core_eval = if r_core > 0.0 {
            r_core
        } else {
            DPIE_SINGULAR_CORE_ARCSEC
        };
        let r_cut = require_positive("dpie", "r_cut", r_cut_arcsec)?;
        if r_cut <= core_eval {
            return Err(bad(
                "r_cut",
                r_cut,
                "the cut radius must exceed the core radius (and 1e-8 arcsec)",
            ));
        }
        if !(ellipticity.is_finite() && (0.0..1.0).contains(&ellipticity)) {
            return Err(bad("ellipticity", ellipticity, "must be in [0, 1)"));
        }
        if !pa_deg.is_finite() {
            return Err(bad("pa", pa_deg, "the position angle must be finite"));
        }
        let pa = pa_deg.to_radians();
        Ok(Self {
            center: require_finite_center("dpie", center)?,
            b0_arcsec: dpie_b0_arcsec(sigma_v_km_s),
            r_core_arcsec: r_core,
            r_cut_arcsec: r_cut,
            core_eval_arcsec: core_eval,
            ellipticity,
            epsilon: kk_epsilon(ellipticity),
            pa_deg,
            rot: DVec2::new(pa.cos(), pa.sin()),
        })
    }

    /// As [`Dpie::new`] with the radii in kpc (Lenstool `core_radius_kpc`, `cut_radius_kpc`),
    /// converted with the lens plane's `mpc_per_arcsec`.
    pub fn from_kpc(
        center: DVec2,
        sigma_v_km_s: f64,
        r_core_kpc: f64,
        r_cut_kpc: f64,
        ellipticity: f64,
        pa_deg: f64,
        plane: &LensPlane,
    ) -> Result<Self, ProfileError> {
        let kpc_per_arcsec = 1.0e3 * plane.mpc_per_arcsec;
        let (core, cut) = (r_core_kpc / kpc_per_arcsec, r_cut_kpc / kpc_per_arcsec);
        Self::new(center, sigma_v_km_s, core, cut, ellipticity, pa_deg)
    }

    /// Centre in arcsec.
    pub fn center(&self) -> DVec2 {
        self.center
    }
    /// `b0 = 6 pi (sigma/c)^2` in arcsec (`D_ls/D_s = 1`).
    pub fn b0_arcsec(&self) -> f64 {
        self.b0_arcsec
    }
    /// Core and cut radii in arcsec, as given (a singular core is 0).
    pub fn radii_arcsec(&self) -> (f64, f64) {
        (self.r_core_arcsec, self.r_cut_arcsec)
    }
    /// Lenstool mass ellipticity `e` and the Kassiola-Kovner `eps` derived from it.
    pub fn ellipticity(&self) -> (f64, f64) {
        (self.ellipticity, self.epsilon)
    }
    /// Position angle in degrees counter-clockwise from +x.
    pub fn pa_deg(&self) -> f64 {
        self.pa_deg
    }

    /// Total projected mass `pi b0 s (1 - eps^2) Sigma_cr_ref` in Msun (finite thanks to the
    /// cut radius `s`; `= (3/2) pi sigma^2 r_cut / G` for a circular dPIE).
    pub fn total_mass_msun(&self, plane: &LensPlane) -> f64 {
        let eps = self.epsilon;
        std::f64::consts::PI
            * self.b0_arcsec
            * self.r_cut_arcsec
            * (1.0 - eps * eps)
            * plane.sigma_cr_ref_msun_per_arcsec2
    }

    /// `b0 s/(s-a)`, the factor of the core-minus-cut difference.
    fn strength(&self) -> f64 {
        self.b0_arcsec * self.r_cut_arcsec / (self.r_cut_arcsec - self.core_eval_arcsec)
    }

    /// Offset from the centre rotated into the profile frame (`x'` along the major axis).
    fn frame_offset(&self, p: DVec2) -> DVec2 {
        let d = p - self.center;
        DVec2::new(
            d.x * self.rot.x + d.y * self.rot.y,
            -d.x * self.rot.y + d.y * self.rot.x,
        )
    }

    /// Deflection (arcsec) and Hessian in the sky frame.
    fn fields(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        let q = self.frame_offset(p);
        let (a, s, k) = (self.core_eval_arcsec, self.r_cut_arcsec, self.strength());
        let (g, h) = if self.epsilon < CIRCULAR_EPSILON {
            let (ga, gpa) = circular_unit(q, a);
            let (gs, gps) = circular_unit(q, s);
            let (g, gp) = (k * (ga - gs), k * (gpa - gps));
            let h = [g + gp * q.x * q.x, gp * q.x * q.y, g + gp * q.y * q.y];
            (q * g, h)
        } else {
            let ta = piemd_unit(q, self.epsilon, a);
            let ts = piemd_unit(q, self.epsilon, s);
            let alpha = DVec2::new(k * (ta.0.re - ts.0.re), k * (ta.0.im - ts.0.im));
            let (dx, dy) = (ta.1.sub(ts.1), ta.2.sub(ts.2));
            // d/dx (alpha_x + i alpha_y) = psi_xx + i psi_xy; d/dy = psi_xy + i psi_yy.
            let h = [k * dx.re, 0.5 * k * (dx.im + dy.re), k * dy.im];
            (alpha, h)
        };
        let (c, sn) = (self.rot.x, self.rot.y);
        let alpha = DVec2::new(g.x * c - g.y * sn, g.x * sn + g.y * c);
        // H = R H' R^T with R the rotation by pa.
        let [hxx, hxy, hyy] = h;
        let (c2, s2, cs) = (c * c, sn * sn, c * sn);
        let hessian = [
            hxx * c2 - 2.0 * hxy * cs + hyy * s2,
            (hxx - hyy) * cs + hxy * (c2 - s2),
            hxx * s2 + 2.0 * hxy * cs + hyy * c2,
        ];
        (alpha, hessian)
    }
}

/// Circular unit PIEMD of core `w`: `g = 1/(sqrt(R^2+w^2) + w)` (so `alpha = g q`) and
/// `g'(R)/R = -1/(sqrt(R^2+w^2) (sqrt(R^2+w^2) + w)^2)`; both finite at `R = 0`.
fn circular_unit(q: DVec2, w: f64) -> (f64, f64) {
    let u = (q.length_squared() + w * w).sqrt();
    let g = 1.0 / (u + w);
    (g, -g * g / u)
}

/// Unit PIEMD (`b0 = 1`) of core `w` at `q` (profile frame): `I = alpha_x + i alpha_y`,
/// `dI/dx`, `dI/dy` (Kassiola & Kovner 1993; see the module documentation).
fn piemd_unit(q: DVec2, eps: f64, w: f64) -> (Cx, Cx, Cx) {
    let se = eps.sqrt();
    let (ep, em) = (1.0 + eps, 1.0 - eps);
    let cx1 = em / ep;
    let root = (w * w + q.x * q.x / (ep * ep) + q.y * q.y / (em * em)).sqrt();
    let a = Cx::new(cx1 * q.x, -q.y / cx1);
    let b = 2.0 * se * root;
    let c = Cx::new(q.x, -q.y);
    let e = 2.0 * se * w;
    let (ax, ay) = (Cx::new(cx1, 0.0), Cx::new(0.0, -1.0 / cx1));
    let bx = 2.0 * se * q.x / (ep * ep * root);
    let by = 2.0 * se * q.y / (em * em * root);
    let (cx, cy) = (Cx::new(1.0, 0.0), Cx::new(0.0, -1.0));
    let n1 = a.add(Cx::new(0.0, b));
    let d1 = c.add(Cx::new(0.0, e));
    let n2 = c.sub(Cx::new(0.0, e));
    let d2 = a.sub(Cx::new(0.0, b));
    // ln(N/D) and its derivatives N'/N - D'/D, in the regular one of the two equal forms.
    let (log, lx, ly) = if d1.norm2() >= d2.norm2() {
        let lx = ax.add(Cx::new(0.0, bx)).div(n1).sub(cx.div(d1));
        let ly = ay.add(Cx::new(0.0, by)).div(n1).sub(cy.div(d1));
        (n1.div(d1).ln(), lx, ly)
    } else {
        let lx = cx.div(n2).sub(ax.sub(Cx::new(0.0, bx)).div(d2));
        let ly = cy.div(n2).sub(ay.sub(Cx::new(0.0, by)).div(d2));
        (n2.div(d2).ln(), lx, ly)
    };
    let zci = Cx::new(0.0, -0.5 * (1.0 - eps * eps) / se);
    (zci.mul(log), zci.mul(lx), zci.mul(ly))
}

/// The few complex operations the Kassiola-Kovner formula needs.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cx {
    re: f64,
    im: f64,
}

impl Cx {
    fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn norm2(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    /// Smith's algorithm: no overflow or needless cancellation for any finite operands.
    fn div(self, o: Self) -> Self {
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let d = o.re + o.im * r;
            Self::new((self.re + self.im * r) / d, (self.im - self.re * r) / d)
        } else {
            let r = o.re / o.im;
            let d = o.re * r + o.im;
            Self::new((self.re * r + self.im) / d, (self.im * r - self.re) / d)
        }
    }
    /// Principal logarithm.
    fn ln(self) -> Self {
        Self::new(self.re.hypot(self.im).ln(), self.im.atan2(self.re))
    }
}

impl MassComponent for Dpie {
    /// `(b0/2) s/(s-a) [1/sqrt(a^2+rho^2) - 1/sqrt(s^2+rho^2)]`, written as
    /// `(b0/2) s (s+a) / (u_a u_s (u_a + u_s))` with `u_w = sqrt(w^2 + rho^2)` (no cancellation).
    fn kappa(&self, p: DVec2) -> f64 {
        let q = self.frame_offset(p);
        let (ep, em) = (1.0 + self.epsilon, 1.0 - self.epsilon);
        let rho2 = q.x * q.x / (ep * ep) + q.y * q.y / (em * em);
        let (a, s) = (self.core_eval_arcsec, self.r_cut_arcsec);
        let (ua, us) = ((a * a + rho2).sqrt(), (s * s + rho2).sqrt());
        0.5 * self.b0_arcsec * s * (s + a) / (ua * us * (ua + us))
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        self.fields(p).0
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        self.fields(p).1
    }
    fn deflection_hessian(&self, p: DVec2) -> (DVec2, [f64; 3]) {
        self.fields(p)
    }
}

#!/usr/bin/env python3
"""Reference values for tests/physics/nfw.rs (NFW, elliptical NFW, truncated NFW).

Run from the repository root:  python3 tests/data/nfw_reference.py  > writes tests/data/nfw.json

* Cosmology: astropy FlatLambdaCDM(H0=70, Om0=0.3, Tcmb0=0) (the crate's default).
* Normalisation D_ls/D_s = 1: r_s [arcsec] and kappa_s = rho_s r_s / Sigma_cr_ref with
  Sigma_cr_ref = c^2/(4 pi G D_l), from M200 (200 rho_crit(z_l)) and c200, computed here with
  astropy's CODATA 2018 constants (the crate's constants). lenstronomy's own
  LensCosmo.nfw_physical2angle uses older G and M_sun; its alpha_Rs, rescaled by D_s/D_ls,
  is stored too ("alpha_rs_lenscosmo_arcsec") to show that the conventions agree (to ~4e-4).
* Fields: lenstronomy LensModel 'NFW', 'NFW_ELLIPSE_CSE' (high accuracy = Oguri 2021 Table 1)
  and 'TNFW' with Rs and alpha_Rs = 4 kappa_s r_s (1 + ln 1/2).
* Exact values: mpmath (50 digits) for the spherical NFW functions G, h and for the TNFW
  m(x) (BMO09 closed form) and kappa (direct numerical projection of the 3-D density).
"""

import json
import math
import os

import mpmath as mp
import numpy as np
from astropy import constants as const
from astropy import units as u
from astropy.cosmology import FlatLambdaCDM
from lenstronomy.Cosmo.lens_cosmo import LensCosmo
from lenstronomy.LensModel.lens_model import LensModel

mp.mp.dps = 50
COSMO = FlatLambdaCDM(H0=70.0, Om0=0.3, Tcmb0=0.0)
Z_LENS = 0.3
Z_SOURCE = 2.0
ARCSEC = math.pi / 180.0 / 3600.0


def scales(m200, c200):
    """r_s [arcsec], kappa_s (D_ls/D_s = 1), r200 [arcsec] with astropy constants."""
    d_l = COSMO.angular_diameter_distance(Z_LENS).to(u.Mpc).value
    rho_c = COSMO.critical_density(Z_LENS).to(u.Msun / u.Mpc**3).value
    r200 = (3.0 * m200 / (800.0 * math.pi * rho_c)) ** (1.0 / 3.0)
    r_s = r200 / c200
    rho_s = 200.0 / 3.0 * rho_c * c200**3 / (math.log1p(c200) - c200 / (1.0 + c200))
    sigma_cr = (const.c**2 / (4.0 * math.pi * const.G)).to(u.Msun / u.Mpc).value / d_l
    mpc_per_arcsec = d_l * ARCSEC
    return r_s / mpc_per_arcsec, rho_s * r_s / sigma_cr, r200 / mpc_per_arcsec


def lenscosmo_alpha_rs(m200, c200):
    """lenstronomy's own conversion, rescaled to D_ls/D_s = 1."""
    lc = LensCosmo(z_lens=Z_LENS, z_source=Z_SOURCE, cosmo=COSMO)
    rs, alpha_rs = lc.nfw_physical2angle(m200, c200)
    return float(rs), float(alpha_rs) * lc.ds / lc.dds


def fields(model, kwargs, xs, ys):
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    kappa = model.kappa(xs, ys, [kwargs])
    ax, ay = model.alpha(xs, ys, [kwargs])
    hxx, hxy, _, hyy = model.hessian(xs, ys, [kwargs])
    return [
        dict(x=float(x), y=float(y), kappa=float(k), ax=float(a), ay=float(b),
             hxx=float(h1), hxy=float(h2), hyy=float(h3))
        for x, y, k, a, b, h1, h2, h3 in zip(xs, ys, kappa, ax, ay, hxx, hxy, hyy)
    ]


def ring_points(center, r_s, xs_over_rs, angles_deg):
    pts = []
    for i, x in enumerate(xs_over_rs):
        ang = math.radians(angles_deg[i % len(angles_deg)])
        pts.append((center[0] + x * r_s * math.cos(ang), center[1] + x * r_s * math.sin(ang)))
    return [p[0] for p in pts], [p[1] for p in pts]


# Radii in units of r_s: small, around 1 (incl. exactly 1 +- tiny), large.
X_GRID = [1e-3, 3e-3, 0.01, 0.05, 0.1, 0.3, 0.5, 0.9, 0.99, 0.999, 1.0, 1.001, 1.01,
          1.1, 1.5, 2.0, 3.0, 5.0, 10.0, 30.0, 100.0, 300.0, 1000.0]
ANGLES = [0.0, 37.0, 90.0, 143.0, 211.0, 300.0]


def nfw_case(name, center, m200, c200):
    r_s, kappa_s, r200 = scales(m200, c200)
    alpha_rs = 4.0 * kappa_s * r_s * (1.0 + math.log(0.5))
    lc_rs, lc_alpha = lenscosmo_alpha_rs(m200, c200)
    xs, ys = ring_points(center, r_s, X_GRID, ANGLES)
    kw = dict(Rs=r_s, alpha_Rs=alpha_rs, center_x=center[0], center_y=center[1])
    return dict(name=name, center=center, m200_msun=m200, c200=c200, r_s_arcsec=r_s,
                kappa_s=kappa_s, r200_arcsec=r200, alpha_rs_arcsec=alpha_rs,
                r_s_lenscosmo_arcsec=lc_rs, alpha_rs_lenscosmo_arcsec=lc_alpha,
                points=fields(LensModel(["NFW"]), kw, xs, ys))


def ellipse_case(name, center, m200, c200, q, pa_deg):
    r_s, kappa_s, _ = scales(m200, c200)
    alpha_rs = 4.0 * kappa_s * r_s * (1.0 + math.log(0.5))
    e = (1.0 - q) / (1.0 + q)
    phi = math.radians(pa_deg)
    kw = dict(Rs=r_s, alpha_Rs=alpha_rs, e1=e * math.cos(2 * phi), e2=e * math.sin(2 * phi),
              center_x=center[0], center_y=center[1])
    xs, ys = ring_points(center, r_s, [v for v in X_GRID if v <= 300.0], ANGLES + [30.0, 120.0])
    return dict(name=name, center=center, m200_msun=m200, c200=c200, q=q, pa_deg=pa_deg,
                r_s_arcsec=r_s, kappa_s=kappa_s,
                points=fields(LensModel(["NFW_ELLIPSE_CSE"]), kw, xs, ys))


def mp_F(x):
    x = mp.mpf(x)
    if x < 1:
        return mp.acosh(1 / x) / mp.sqrt(1 - x * x)
    if x > 1:
        return mp.acos(1 / x) / mp.sqrt(x * x - 1)
    return mp.mpf(1)


def mp_G(x):
    x = mp.mpf(x)
    return mp.mpf(1) / 3 if x == 1 else (1 - mp_F(x)) / (x * x - 1)


def mp_tnfw_m(x, tau):
    x, t = mp.mpf(x), mp.mpf(tau)
    tt = t * t
    s = mp.sqrt(tt + x * x)
    lg = mp.log(x / (s + t))
    return tt / (tt + 1) ** 2 * ((tt + 1 + 2 * (x * x - 1)) * mp_F(x) + t * mp.pi
                                 + (tt - 1) * mp.log(t) + s * (-mp.pi + (tt - 1) / t * lg))


def mp_tnfw_kappa_unit(x, tau):
    """Sigma / (2 rho_s r_s) by projecting rho = 1/(r (1+r)^2) tau^2/(tau^2+r^2)."""
    x, t = mp.mpf(x), mp.mpf(tau)

    def rho(z):
        r = mp.sqrt(x * x + z * z)
        return 1 / (r * (1 + r) ** 2) * t * t / (t * t + r * r)

    return mp.quad(rho, [0, x, 1, 10 * t, mp.inf])


def tnfw_case(name, center, m200, c200, tau):
    r_s, kappa_s, _ = scales(m200, c200)
    alpha_rs = 4.0 * kappa_s * r_s * (1.0 + math.log(0.5))
    kw = dict(Rs=r_s, alpha_Rs=alpha_rs, r_trunc=tau * r_s, center_x=center[0],
              center_y=center[1])
    grid = [v for v in X_GRID if v != 1.0] + [0.5 * tau, tau, 2.0 * tau, 3.9 * tau, 4.1 * tau,
                                             10.0 * tau]
    xs, ys = ring_points(center, r_s, grid, ANGLES)
    exact_x = [1e-6, 1e-4, 0.01, 0.5, 1.0, 2.0, tau, 3.0 * tau, 4.0 * max(1.0, tau) * 1.0001,
               10.0 * max(1.0, tau), 100.0 * max(1.0, tau), 1e4]
    exact = [dict(x=x, m=float(mp_tnfw_m(x, tau)), kappa_unit=float(mp_tnfw_kappa_unit(x, tau)))
             for x in exact_x]
    tt = mp.mpf(tau) ** 2
    m_tot = tt / (tt + 1) ** 2 * ((tt - 1) * mp.log(tau) + mp.pi * tau - (tt + 1))
    return dict(name=name, center=center, m200_msun=m200, c200=c200, tau=tau,
                r_trunc_arcsec=tau * r_s, r_s_arcsec=r_s, kappa_s=kappa_s,
                m_tot_unit=float(m_tot), exact=exact,
                points=fields(LensModel(["TNFW"]), kw, xs, ys))


def main():
    nfw_exact_x = [1e-6, 1e-5, 1e-4, 1e-3, 0.01, 0.1, 0.5, 0.9, 0.95, 0.99, 0.995, 0.999999,
                   1.0, 1.000001, 1.005, 1.01, 1.05, 1.1, 2.0, 10.0, 1e3, 1e5]
    out = dict(
        generator="tests/data/nfw_reference.py",
        lenstronomy_version=__import__("lenstronomy").__version__,
        z_lens=Z_LENS, z_source=Z_SOURCE, h0=70.0, omega_m=0.3,
        nfw_exact=[dict(x=x, g=float(mp_G(x)), h=float(mp.log(mp.mpf(x) / 2) + mp_F(x)),
                        f=float(mp_F(x))) for x in nfw_exact_x],
        nfw=[nfw_case("cluster", [1.5, -2.0], 1.0e15, 5.0),
             nfw_case("galaxy", [-0.3, 0.7], 1.0e11, 12.0)],
        nfw_ellipse=[ellipse_case("q0.6", [-3.0, 2.0], 8.0e14, 4.5, 0.6, 30.0),
                     ellipse_case("q0.3", [0.0, 0.0], 2.0e14, 6.0, 0.3, -70.0),
                     ellipse_case("q1", [0.5, 0.5], 8.0e14, 4.5, 1.0, 0.0)],
        tnfw=[tnfw_case("tau5", [2.0, 1.0], 5.0e11, 8.0, 5.0),
              tnfw_case("tau0.7", [-1.0, -4.0], 2.0e12, 6.0, 0.7),
              tnfw_case("tau30", [0.0, 0.0], 1.0e11, 10.0, 30.0)],
    )
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "nfw.json")
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")
    print("wrote", path)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Reference values for tests/physics/dpie.rs (dPIE, Lenstool profile 81).

Run from the repository root:  python3 tests/data/dpie_reference.py  > writes tests/data/dpie.json

Lenstool's dPIE with v_disp = sigma, core a, cut s (arcsec) has b0 = 6 pi (sigma/c)^2 and
kappa = (b0/2) s/(s-a) [1/sqrt(a^2+rho^2) - 1/sqrt(s^2+rho^2)],
rho^2 = x'^2/(1+eps)^2 + y'^2/(1-eps)^2, eps = (1 - sqrt(1-e^2))/e.

* Circular case: lenstronomy LensModel 'PJAFFE' (PseudoJaffe) with Ra = a, Rs = s and
  sigma0 = b0/(2a): its kappa is sigma0 Ra Rs/(Rs-Ra) [1/sqrt(Ra^2+R^2) - 1/sqrt(Rs^2+R^2)].
* Elliptical case (independent of the Kassiola & Kovner closed form used by the crate): the
  kappa above is a function of xi^2 = x'^2 + y'^2/q^2 with q = (1-eps)/(1+eps)
  (rho = xi/(1+eps)), so deflection and Hessian follow from the 1-D integrals of Keeton
  (2001, astro-ph/0102341, eqs. 27-29, after Schramm 1990) for elliptical mass distributions:
  alpha_x' = q x' J0, alpha_y' = q y' J1, psi_x'x' = 2 q x'^2 K0 + q J0,
  psi_y'y' = 2 q y'^2 K2 + q J1, psi_x'y' = 2 q x' y' K1, with
  J_n = int_0^1 kappa(xi(u)^2) / (1-(1-q^2)u)^(n+1/2) du,
  K_n = int_0^1 u kappa'(xi(u)^2) / (1-(1-q^2)u)^(n+1/2) du,
  xi(u)^2 = u (x'^2 + y'^2/(1-(1-q^2)u)), computed with scipy.integrate.quad (epsrel 1e-12)
  and rotated to the sky frame by the position angle.
* Singular core (r_core = 0, Lenstool's `core_radius 0.000000`): the circular case against
  lenstronomy 'PJAFFE' with Ra = 0 (which lenstronomy floors at 1e-8 arcsec, as the crate
  does) and sigma0 Ra = b0/2; the elliptical case with the Keeton integrals above at a = 0
  exactly (kappa ~ 1/sqrt(u) near u = 0 is integrable; quad copes).
"""

import json
import math
import os

import numpy as np
from astropy import constants as const
from lenstronomy.LensModel.lens_model import LensModel
from scipy.integrate import quad

ARCSEC_PER_RAD = 180.0 / math.pi * 3600.0
C_KM_S = const.c.to("km/s").value


def b0_arcsec(sigma_km_s):
    return 6.0 * math.pi * (sigma_km_s / C_KM_S) ** 2 * ARCSEC_PER_RAD


def kk_eps(e):
    return e / (1.0 + math.sqrt(1.0 - e * e))


def circular_case(sigma=350.0, a=1.5, s=40.0, pts=None):
    b0 = b0_arcsec(sigma)
    lm = LensModel(["PJAFFE"])
    # lenstronomy replaces Ra < 1e-8 by 1e-8: sigma0 Ra = b0/2 with that Ra.
    kw = [{"sigma0": b0 / (2.0 * max(a, 1e-8)), "Ra": a, "Rs": s, "center_x": 0.3,
           "center_y": -0.2}]
    if pts is None:
        pts = [(0.3, -0.2), (0.31, -0.2), (1.0, 0.5), (-2.0, 3.0), (10.0, -7.0), (35.0, 20.0),
               (-80.0, 60.0), (200.0, 5.0)]
    rows = []
    for x, y in pts:
        k = float(lm.kappa(x, y, kw))
        ax, ay = (float(v) for v in lm.alpha(x, y, kw))
        fxx, fxy, fyx, fyy = (float(v) for v in lm.hessian(x, y, kw))
        rows.append({"x": x, "y": y, "kappa": k, "alpha": [ax, ay], "hessian": [fxx, fxy, fyy]})
    return {"sigma_km_s": sigma, "r_core_arcsec": a, "r_cut_arcsec": s, "center": [0.3, -0.2],
            "b0_arcsec": b0, "points": rows}


def elliptical_case(sigma, a, s, e, pa_deg, center, pts):
    b0 = b0_arcsec(sigma)
    eps = kk_eps(e)
    q = (1.0 - eps) / (1.0 + eps)
    k0 = 0.5 * b0 * s / (s - a)

    def kappa_xi2(xi2):
        rho2 = xi2 / (1.0 + eps) ** 2
        if a * a + rho2 == 0.0:
            return math.inf
        return k0 * (1.0 / math.sqrt(a * a + rho2) - 1.0 / math.sqrt(s * s + rho2))

    def dkappa_dxi2(xi2):
        rho2 = xi2 / (1.0 + eps) ** 2
        if a * a + rho2 == 0.0:
            return -math.inf
        d = -0.5 * ((a * a + rho2) ** -1.5 - (s * s + rho2) ** -1.5)
        return k0 * d / (1.0 + eps) ** 2

    def integrals(x, y):
        def xi2(u):
            return u * (x * x + y * y / (1.0 - (1.0 - q * q) * u))

        def den(u, n):
            return (1.0 - (1.0 - q * q) * u) ** (n + 0.5)

        opts = dict(epsabs=0.0, epsrel=1e-12, limit=500)
        j = [quad(lambda u: kappa_xi2(xi2(u)) / den(u, n), 0.0, 1.0, **opts)[0] for n in (0, 1)]
        kk = [quad(lambda u: u * dkappa_dxi2(xi2(u)) / den(u, n), 0.0, 1.0, **opts)[0]
              for n in (0, 1, 2)]
        return j, kk

    c, sn = math.cos(math.radians(pa_deg)), math.sin(math.radians(pa_deg))
    rot = np.array([[c, -sn], [sn, c]])
    rows = []
    for x, y in pts:
        dx, dy = x - center[0], y - center[1]
        xp, yp = dx * c + dy * sn, -dx * sn + dy * c
        (j0, j1), (k0_, k1_, k2_) = integrals(xp, yp)
        alpha_p = np.array([q * xp * j0, q * yp * j1])
        h_p = np.array([[2 * q * xp * xp * k0_ + q * j0, 2 * q * xp * yp * k1_],
                        [2 * q * xp * yp * k1_, 2 * q * yp * yp * k2_ + q * j1]])
        alpha = rot @ alpha_p
        h = rot @ h_p @ rot.T
        kap = kappa_xi2(xp * xp + yp * yp / (q * q))
        rows.append({"x": x, "y": y, "kappa": kap, "alpha": [float(alpha[0]), float(alpha[1])],
                     "hessian": [float(h[0, 0]), float(h[0, 1]), float(h[1, 1])]})
    return {"sigma_km_s": sigma, "r_core_arcsec": a, "r_cut_arcsec": s, "ellipticity": e,
            "pa_deg": pa_deg, "center": list(center), "b0_arcsec": b0, "epsilon": eps,
            "points": rows}


def main():
    # A cluster halo like AS1063's (e = 0.52) and a member galaxy (small core, e = 0.3).
    eps_h = kk_eps(0.517)
    sing = 2.0 * math.sqrt(eps_h) * 20.0  # where the closed form's ratio is 0/0
    halo_pts = [(0.0, 0.0), (3.0, -1.0), (-15.0, 25.0), (40.0, 10.0), (-60.0, -45.0),
                (150.0, 120.0), (0.0, sing), (0.0, -sing)]
    # The singular points are on the minor axis of the rotated frame: map them to the sky.
    pa = -36.0
    c, s_ = math.cos(math.radians(pa)), math.sin(math.radians(pa))
    halo_pts = [(x, y) if i < 6 else (-y * s_, y * c) for i, (x, y) in enumerate(halo_pts)]
    out = {
        "circular": circular_case(),
        "elliptical_halo": elliptical_case(1224.0, 20.0, 210.0, 0.517, pa, (0.0, 0.0), halo_pts),
        "elliptical_member": elliptical_case(
            180.0, 0.05, 8.0, 0.3, 50.0, (2.0, -1.0),
            [(2.0, -1.0), (2.02, -0.99), (2.5, -0.6), (0.0, 0.0), (-5.0, 6.0), (30.0, 20.0)]),
        # Singular cores (away from the centre, where the fields are infinite or undefined).
        "circular_singular": circular_case(
            1100.0, 0.0, 250.0,
            [(0.8, -0.2), (0.3, 1.0), (-2.0, 3.0), (10.0, -7.0), (35.0, 20.0), (-80.0, 60.0),
             (400.0, 5.0)]),
        "elliptical_singular": elliptical_case(
            1100.0, 0.0, 250.0, 0.35, 20.0, (1.0, -2.0),
            [(1.5, -2.0), (1.0, -1.0), (-3.0, 4.0), (25.0, -10.0), (-60.0, 45.0),
             (300.0, 200.0)]),
    }
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "dpie.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    print("wrote", path)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Independent-truth synthetic clusters for `benches/fidelity.py`, made with lenstronomy.

Nothing here uses this project's code: the lenses, the image positions and every truth number
come from lenstronomy (and astropy for the cosmology). Run from the repository root:

    /tmp/refenv/bin/python tests/data/fidelity/make_clusters.py [--only NAME] [--out DIR]
        [--seed-offset K]

Deterministic: every cluster has its own seed (numpy default_rng); the same lenstronomy,
numpy and astropy versions give the same files.

Conventions (those of wslap, see tests/data/fidelity/README.md):
- positions are arcsec in the frame of `#REFERENCE 3 ra0 dec0`: x = -(RA - RA0) cos(Dec0) 3600
  (+x West), y = (Dec - Dec0) 3600 (+y North). lenstronomy's (x, y) are these (x, y) as they
  are: the lens equation does not care which way is West, as long as lens and images share
  one frame, and they do.
- lens kwargs are written for D_ls/D_s = 1 (the HFF convention of wslap's maps): a source at
  z_s sees every deflection times f = D_ls/D_s(z_l, z_s); all profiles used here are linear in
  alpha_Rs, so `scaled_kwargs(kwargs, f)` multiplies alpha_Rs (and an external shear's gamma1, gamma2) by f.
- member galaxies follow wslap's member prior (src/inversion/members.rs): M = Upsilon L with
  Upsilon = 20, L* = 5e10 Lsun (M* = 1e12 Msun), truncated NFW (Baltz, Marshall & Oguri 2009,
  = lenstronomy 'TNFW') of TOTAL mass M with r_s = 10 kpc (M/1e12)^(1/3),
  r_t = 40 kpc (M/1e12)^(1/3); mag = mag* - 2.5 log10(M / M*), mag* = -21.5 + 5 log10(D_L/10pc),
  D_L = (1 + z_l)^2 D_l. The true mass is the catalogue mass times 10^(0.15 N(0,1)).
"""

import argparse
import json
import os
import sys
import time

import contourpy
import numpy as np
import astropy
from astropy import constants as const
from astropy import units as u
from astropy.cosmology import FlatLambdaCDM
from scipy import integrate
from scipy.spatial import ConvexHull

import lenstronomy
from lenstronomy.Cosmo.lens_cosmo import LensCosmo
from lenstronomy.LensModel.lens_model import LensModel
from lenstronomy.LensModel.Profiles.tnfw import TNFW
from lenstronomy.LensModel.Solver.lens_equation_solver import LensEquationSolver
from lenstronomy.Util import param_util

H0, OM0 = 70.0, 0.3
COSMO = FlatLambdaCDM(H0=H0, Om0=OM0)
ARCSEC_RAD = np.pi / 180.0 / 3600.0
# c^2 / (4 pi G) in Msun / Mpc.
C2_4PIG = (const.c**2 / (4 * np.pi * const.G)).to(u.Msun / u.Mpc).value

# wslap's member prior (src/inversion/members.rs defaults).
UPSILON, L_STAR, ABS_MAG_STAR = 20.0, 5.0e10, -21.5
M_STAR = UPSILON * L_STAR
RS_STAR_KPC, RT_STAR_KPC = 10.0, 40.0
MASS_SCATTER_DEX = 0.15
ASTROMETRIC_NOISE = 0.05  # arcsec, Gaussian per coordinate

FIELD_HALF = 100.0  # arcsec: truth grid half-width
FINE_PIX = 0.2  # arcsec: truth grid pitch (theta_E, mass, image search)
IMAGE_LIMIT = 90.0  # images beyond |x| or |y| of this are dropped
MU_MIN = 0.2  # images with |mu| below this are dropped (faint central images)
MIN_SEPARATION = 1.0  # arcsec: a system with two images closer than this is redrawn
DEFL_GRID_STEP = 2.0  # arcsec: truth deflection grid over the image region
KAPPA_MAP_BLOCK = 10  # fine pixels per stored kappa pixel (2 arcsec)


# ----------------------------------------------------------------------------------------------
# Cosmology and profile conversions


class Plane:
    """The lens plane: distances, critical densities at D_ls/D_s = 1."""

    def __init__(self, z_l):
        self.z_l = z_l
        self.d_l = COSMO.angular_diameter_distance(z_l).to(u.Mpc).value
        self.mpc_per_arcsec = self.d_l * ARCSEC_RAD
        self.sigma_cr_ref = C2_4PIG / self.d_l  # Msun / Mpc^2
        self.sigma_cr_ref_arcsec2 = self.sigma_cr_ref * self.mpc_per_arcsec**2
        self.rho_crit = COSMO.critical_density(z_l).to(u.Msun / u.Mpc**3).value
        d_lum = (1 + z_l) ** 2 * self.d_l
        self.mag_star = ABS_MAG_STAR + 5 * np.log10(d_lum) + 25

    def f(self, z_s):
        """D_ls / D_s."""
        d_s = COSMO.angular_diameter_distance(z_s).value
        d_ls = COSMO.angular_diameter_distance(self.z_l, z_s).value
        return d_ls / d_s


def nfw_mu(c):
    return np.log1p(c) - c / (1 + c)


def tnfw_total_unit(tau):
    """Total mass of the BMO09 (n = 1) truncated NFW in units of 4 pi rho_s r_s^3."""
    t2 = tau * tau
    return t2 / (t2 + 1) ** 2 * ((t2 - 1) * np.log(tau) + np.pi * tau - (t2 + 1))


def nfw_kwargs(plane, m200, c, x=0.0, y=0.0, q=1.0, phi_deg=0.0):
    """lenstronomy NFW (q = 1) or NFW_ELLIPSE_CSE kwargs at D_ls/D_s = 1; M200 w.r.t. rho_crit(z_l)."""
    r200 = (3 * m200 / (800 * np.pi * plane.rho_crit)) ** (1 / 3)
    rs = r200 / c
    rho_s = m200 / (4 * np.pi * rs**3 * nfw_mu(c))
    kappa_s = rho_s * rs / plane.sigma_cr_ref
    rs_as = rs / plane.mpc_per_arcsec
    kw = {"Rs": rs_as, "alpha_Rs": 4 * kappa_s * rs_as * (1 - np.log(2)),
          "center_x": x, "center_y": y}
    if q == 1.0:
        return "NFW", kw
    e1, e2 = param_util.phi_q2_ellipticity(np.deg2rad(phi_deg), q)
    kw.update(e1=e1, e2=e2)
    return "NFW_ELLIPSE_CSE", kw


def tnfw_kwargs(plane, mass, x, y):
    """lenstronomy TNFW kwargs at D_ls/D_s = 1 for wslap's member halo of TOTAL mass `mass`."""
    s = (mass / M_STAR) ** (1 / 3)
    rs = RS_STAR_KPC * 1e-3 * s
    rt = RT_STAR_KPC * 1e-3 * s
    rho_s = mass / (4 * np.pi * rs**3 * tnfw_total_unit(rt / rs))
    kappa_s = rho_s * rs / plane.sigma_cr_ref
    rs_as = rs / plane.mpc_per_arcsec
    return {"Rs": rs_as, "alpha_Rs": 4 * kappa_s * rs_as * (1 - np.log(2)),
            "r_trunc": rt / plane.mpc_per_arcsec, "center_x": x, "center_y": y}


def dpie_kwargs(plane, law, l, factor, x, y):
    """Total mass (Msun) and lenstronomy PJAFFE kwargs at D_ls/D_s = 1 of a circular Lenstool
    dPIE (profile 81) for a galaxy of L/L* = l under the Lenstool scaling `law` (v_disp in km/s
    and core, cut in kpc at L*; v_disp ~ L^(1/4), core and cut ~ L^(1/2)), its mass times
    `factor`. Lenstool's b0 = 6 pi (v_disp / c)^2 gives kappa = (b0 / 2) s / (s - a)
    [1/sqrt(a^2 + R^2) - 1/sqrt(s^2 + R^2)], PJAFFE's with sigma0 = b0 / (2 a) (as in
    tests/data/dpie_reference.py); its total mass is (3/2) pi v_disp^2 s / G."""
    sigma = law["v_disp"] * l**0.25 * np.sqrt(factor)
    a_kpc, s_kpc = law["core_kpc"] * l**0.5, law["cut_kpc"] * l**0.5
    c_km_s = const.c.to(u.km / u.s).value
    b0 = 6 * np.pi * (sigma / c_km_s) ** 2 / ARCSEC_RAD
    a, s = (r * 1e-3 / plane.mpc_per_arcsec for r in (a_kpc, s_kpc))
    g = const.G.to(u.kpc * u.km**2 / u.s**2 / u.Msun).value
    mass = 1.5 * np.pi * sigma**2 * s_kpc / g
    return mass, {"sigma0": b0 / (2 * a), "Ra": a, "Rs": s, "center_x": x, "center_y": y}


def scaled_kwargs(kwargs, f):
    """The kwargs for a source at D_ls/D_s = f (every profile here is linear in alpha_Rs, the
    dPIE in sigma0, the external shear in gamma1 and gamma2)."""
    out = []
    for kw in kwargs:
        kw = dict(kw)
        for key in ("alpha_Rs", "sigma0", "gamma1", "gamma2"):
            if key in kw:
                kw[key] *= f
        out.append(kw)
    return out


def check_conversions(plane, log):
    """Numerical checks of the conversions against lenstronomy's own functions."""
    # 1. TNFW: integrate lenstronomy's convergence to large radius, compare with M.
    tnfw = TNFW()
    worst = 0.0
    for mass in (1e10, 1e11, 1e12, 8e12):
        kw = tnfw_kwargs(plane, mass, 0.0, 0.0)
        rho0 = TNFW.alpha2rho0(kw["alpha_Rs"], kw["Rs"])
        kappa = lambda r: tnfw.density_2d(r, 0.0, kw["Rs"], rho0, kw["r_trunc"])
        rmax = 2000 * kw["r_trunc"]
        # log-spaced quadrature of 2 pi r kappa(r) dr in ln r
        lr = np.linspace(np.log(1e-6 * kw["Rs"]), np.log(rmax), 200001)
        r = np.exp(lr)
        m_int = integrate.simpson(2 * np.pi * r * r * kappa(r), x=lr)
        # the tail beyond rmax: kappa ~ A / r^3 -> 2 pi A / rmax
        a_tail = kappa(rmax) * rmax**3
        m_int += 2 * np.pi * a_tail / rmax
        m_int *= plane.sigma_cr_ref_arcsec2
        m2d = tnfw.mass_2d(1e4 * kw["r_trunc"], kw["Rs"], rho0, kw["r_trunc"])
        m2d *= plane.sigma_cr_ref_arcsec2  # mass_2d is the integral of kappa (arcsec^2)
        rel = m_int / mass - 1
        worst = max(worst, abs(rel))
        log(f"  TNFW M = {mass:.2e}: integral of lenstronomy kappa = {m_int:.5e} "
            f"(rel. err {rel:+.2e}); lenstronomy mass_2d(1e4 r_t) = {m2d:.5e}")
    assert worst < 1e-3, worst
    # 1b. dPIE (PJAFFE): lenstronomy's projected mass to 1e4 cut radii against (3/2) pi
    # v_disp^2 s / G (the mass beyond is (3/2) pi v^2 s / G times s / R, below 1e-4).
    pjaffe = LensModel(["PJAFFE"]).lens_model.func_list[0]
    law = dict(v_disp=100.0, core_kpc=0.15, cut_kpc=45.0)
    for l in (0.1, 1.0, 8.0):
        mass, kw = dpie_kwargs(plane, law, l, 1.0, 0.0, 0.0)
        rho0 = pjaffe.sigma2rho(kw["sigma0"], kw["Ra"], kw["Rs"])
        m2d = pjaffe.mass_2d(1e4 * kw["Rs"], rho0, kw["Ra"], kw["Rs"]) * plane.sigma_cr_ref_arcsec2
        rel = m2d / mass - 1
        log(f"  dPIE L = {l} L*: lenstronomy mass_2d(1e4 s) = {m2d:.5e} vs (3/2) pi v^2 s / G "
            f"= {mass:.5e} (rel. err {rel:+.2e})")
        assert abs(rel) < 1e-3, rel
    # 2. NFW: our alpha_Rs at D_ls/D_s = 1 times f equals lenstronomy's LensCosmo at z_s = 2.
    zs = 2.0
    lc = LensCosmo(z_lens=plane.z_l, z_source=zs, cosmo=COSMO)
    rs_lc, a_lc = lc.nfw_physical2angle(1e15, 5.0)
    _, kw = nfw_kwargs(plane, 1e15, 5.0)
    f = plane.f(zs)
    log(f"  NFW M200=1e15 c=5: Rs {kw['Rs']:.5f} vs LensCosmo {rs_lc:.5f}; "
        f"f*alpha_Rs {f * kw['alpha_Rs']:.5f} vs LensCosmo {a_lc:.5f}")
    # lenstronomy.Util.constants has G = 6.67384e-11 and Msun = 1.9891e30 where astropy (and
    # wslap) have 6.6743e-11 and 1.98841e30: Sigma_cr differs by 2.8e-4. We use astropy's.
    assert abs(kw["Rs"] / rs_lc - 1) < 1e-6 and abs(f * kw["alpha_Rs"] / a_lc - 1) < 5e-4
    # 3. Sigma_cr at D_ls/D_s = 1 against LensCosmo's sigma_crit times f.
    sc = lc.sigma_crit  # Msun / Mpc^2 for z_s = 2
    log(f"  Sigma_cr(z_s=2) * f = {sc * f:.6e} vs c^2/(4 pi G D_l) = {plane.sigma_cr_ref:.6e}")
    assert abs(sc * f / plane.sigma_cr_ref - 1) < 5e-4
    return worst


# ----------------------------------------------------------------------------------------------
# Cluster recipes


CLUSTERS = [
    # name, seed, z_l, ra0, dec0, n_systems, description, recipe
    dict(name="a_nfw_clump_members", seed=101, z_l=0.35, ra0=150.1172, dec0=2.2059, n_sys=30,
         halos=[dict(m200=1.3e15, c=6.0, x=0.0, y=0.0, q=0.7, phi=30.0, bcg_l=8.0)],
         clumps=[dict(m200=1.2e14, c=7.0, x=-38.0, y=27.0)],
         n_members=70, member_rc=30.0,
         what="(a) elliptical NFW halo (q = 0.7) with a BCG, a dark NFW clump (no galaxy) "
              "46 arcsec NE of the centre, 70 luminosity-scaled TNFW members"),
    dict(name="b_bimodal", seed=202, z_l=0.38, ra0=64.0392, dec0=-24.0710, n_sys=35,
         halos=[dict(m200=8.0e14, c=6.5, x=-24.0, y=-8.0, q=0.75, phi=15.0, bcg_l=6.0),
                dict(m200=6.0e14, c=7.0, x=24.0, y=10.0, q=0.8, phi=-20.0, bcg_l=5.0)],
         clumps=[], n_members=70, member_rc=25.0,
         what="(b) bimodal: two elliptical NFW halos 51 arcsec apart, each with a BCG, "
              "70 luminosity-scaled TNFW members around both"),
    dict(name="c_smooth", seed=303, z_l=0.32, ra0=342.1832, dec0=-44.5309, n_sys=25,
         halos=[dict(m200=1.4e15, c=7.0, x=0.0, y=0.0, q=0.72, phi=-40.0, bcg_l=None)],
         clumps=[], n_members=0, member_rc=0.0,
         what="(c) a single elliptical NFW halo (q = 0.72), no galaxies, no members.cat"),
    dict(name="d_few_systems", seed=404, z_l=0.30, ra0=177.3990, dec0=22.3985, n_sys=15,
         halos=[dict(m200=1.2e15, c=6.0, x=0.0, y=0.0, q=0.8, phi=70.0, bcg_l=7.0)],
         clumps=[], n_members=60, member_rc=30.0,
         what="(d) elliptical NFW halo with a BCG and 60 members, only 15 systems"),
    dict(name="e_rich", seed=505, z_l=0.40, ra0=109.3800, dec0=37.7550, n_sys=40,
         halos=[dict(m200=1.6e15, c=5.5, x=0.0, y=0.0, q=0.6, phi=-10.0, bcg_l=9.0)],
         clumps=[dict(m200=1.5e14, c=6.0, x=42.0, y=-20.0)],
         n_members=80, member_rc=35.0,
         what="(e) very elliptical NFW halo (q = 0.6) with a BCG, a dark clump 47 arcsec W, "
              "80 members, 40 systems"),
    dict(name="f_clump_offset", seed=606, z_l=0.33, ra0=3.5870, dec0=-30.3970, n_sys=20,
         halos=[dict(m200=9.0e14, c=6.5, x=0.0, y=0.0, q=0.78, phi=50.0, bcg_l=6.0)],
         clumps=[dict(m200=2.5e14, c=6.0, x=20.0, y=32.0)],
         n_members=65, member_rc=28.0,
         what="(f) elliptical NFW halo with a BCG, a massive dark clump 38 arcsec N "
              "(2.5e14 Msun), 65 members, 20 systems"),
    # Members lighter than the catalogue law says (member_scale: the true mass over the
    # law's, before the scatter). A Lenstool fit of a real cluster found its L* galaxy at a
    # velocity dispersion of 100 km/s (CATS, AS1063: a third of the law's mass), so the
    # reconstruction's member prior is then wrong by a factor 3, as it may be for any cluster.
    dict(name="g_light_members", seed=707, z_l=0.36, ra0=322.3590, dec0=-7.6910, n_sys=24,
         halos=[dict(m200=1.3e15, c=6.0, x=0.0, y=0.0, q=0.75, phi=20.0, bcg_l=7.0)],
         clumps=[dict(m200=1.0e14, c=7.0, x=30.0, y=-30.0)],
         n_members=70, member_rc=30.0, member_scale=1.0 / 3.0,
         what="(g) elliptical NFW halo with a BCG, a dark clump 42 arcsec SW, 70 members "
              "whose true masses are a third of the catalogue law's"),
    dict(name="h_light_bimodal", seed=808, z_l=0.42, ra0=39.9710, dec0=-1.5820, n_sys=30,
         halos=[dict(m200=7.5e14, c=6.5, x=-22.0, y=10.0, q=0.7, phi=-30.0, bcg_l=6.0),
                dict(m200=6.5e14, c=6.5, x=22.0, y=-8.0, q=0.8, phi=40.0, bcg_l=5.0)],
         clumps=[], n_members=75, member_rc=25.0, member_scale=1.0 / 3.0,
         what="(h) bimodal: two elliptical NFW halos 47 arcsec apart, each with a BCG, "
              "75 members whose true masses are a third of the catalogue law's"),
    # Lens redshifts outside the 0.30 - 0.42 of the clusters above (added after every default
    # was chosen, like g and h): a nearby lens (A1689, A383 are at z ~ 0.19), where the
    # sources' D_ls/D_s spans half as much and the mass-sheet degeneracy is looser, and a
    # distant one (MACS0717, MACS1149 are at z ~ 0.55), where members look smaller and fainter.
    dict(name="i_low_z", seed=909, z_l=0.19, ra0=197.8729, dec0=-1.3410, n_sys=30,
         halos=[dict(m200=1.1e15, c=7.0, x=0.0, y=0.0, q=0.75, phi=35.0, bcg_l=10.0)],
         clumps=[dict(m200=1.0e14, c=7.0, x=40.0, y=28.0)],
         n_members=70, member_rc=40.0,
         what="(i) a nearby lens (z_l = 0.19): elliptical NFW halo with a BCG, a dark clump "
              "49 arcsec NE, 70 members"),
    dict(name="j_high_z", seed=1010, z_l=0.55, ra0=177.3987, dec0=22.3953, n_sys=25,
         halos=[dict(m200=1.4e15, c=5.0, x=0.0, y=0.0, q=0.7, phi=-50.0, bcg_l=8.0)],
         clumps=[dict(m200=1.2e14, c=6.0, x=-30.0, y=-25.0)],
         n_members=70, member_rc=22.0,
         what="(j) a distant lens (z_l = 0.55): elliptical NFW halo with a BCG, a dark clump "
              "39 arcsec SW, 70 members"),
    # Members of another profile and law than the reconstruction assumes (added 2026-12-07,
    # after every default was chosen): Lenstool's dPIE with the scaling of a published fit, the
    # CATS model of AS1063 as its bestopt.par writes it (an L* galaxy of v_disp 100 km/s, core
    # 0.15 kpc, cut 45 kpc; v_disp ~ L^(1/4), core and cut ~ L^(1/2)): steeper than the
    # truncated NFW of the law inside a few kpc, a third of its mass inside 5 kpc, half in all.
    dict(name="l_dpie_members", seed=1212, z_l=0.35, ra0=330.4703, dec0=-59.9439, n_sys=26,
         halos=[dict(m200=1.3e15, c=6.0, x=0.0, y=0.0, q=0.72, phi=-25.0, bcg_l=8.0)],
         clumps=[dict(m200=1.1e14, c=7.0, x=-35.0, y=-28.0)],
         n_members=70, member_rc=30.0, member_dpie=dict(v_disp=100.0, core_kpc=0.15,
                                                         cut_kpc=45.0),
         what="(l) elliptical NFW halo with a BCG, a dark clump 45 arcsec SE, 70 members "
              "that are Lenstool dPIEs scaled as the CATS model of AS1063 scales its galaxies"),
    # The tidal field of mass beyond the field (added with wslap's external shear, 2026-12-06):
    # a Lenstool fit of AS1063 finds gamma 0.10, so a cluster's own field is not always alone.
    dict(name="k_external_shear", seed=1111, z_l=0.36, ra0=44.7370, dec0=-8.5560, n_sys=25,
         halos=[dict(m200=1.3e15, c=6.0, x=0.0, y=0.0, q=0.85, phi=10.0, bcg_l=8.0)],
         clumps=[], n_members=70, member_rc=30.0, shear=dict(gamma=0.08, angle_deg=60.0),
         what="(k) a rounder NFW halo (q = 0.85) with a BCG, 70 members, and an external "
              "shear of 0.08 along 60 degrees (lenstronomy SHEAR) from mass beyond the field"),
]


def draw_members(rng, spec):
    """Member positions and catalogue luminosities L/L* (BCGs first)."""
    members = []
    for h in spec["halos"]:
        if h["bcg_l"] is not None:
            members.append((h["x"], h["y"], h["bcg_l"]))
    n_rest = spec["n_members"] - len(members)
    centres = [(h["x"], h["y"]) for h in spec["halos"]]
    rc = spec["member_rc"]
    while n_rest > 0:
        cx, cy = centres[rng.integers(len(centres))]
        # projected beta-model (beta = 1): P(<r) = r^2 / (r^2 + rc^2)
        uu = rng.uniform()
        r = rc * np.sqrt(uu / (1 - uu))
        t = rng.uniform(0, 2 * np.pi)
        x, y = cx + r * np.cos(t), cy + r * np.sin(t)
        if max(abs(x), abs(y)) > 95 or min(np.hypot(x - a, y - b) for a, b, _ in members) < 2.0:
            continue
        # L/L* from dN/dL ~ L^-1.25 between 0.03 and 2.5
        lo, hi, s = 0.03, 2.5, -0.25
        l = (lo**s + rng.uniform() * (hi**s - lo**s)) ** (1 / s)
        members.append((x, y, l))
        n_rest -= 1
    return members


def build_lens(plane, spec, rng):
    """lens_model_list, kwargs (D_ls/D_s = 1) and the member table."""
    models, kwargs, roles = [], [], []
    for h in spec["halos"]:
        name, kw = nfw_kwargs(plane, h["m200"], h["c"], h["x"], h["y"], h["q"], h["phi"])
        models.append(name)
        kwargs.append(kw)
        roles.append("halo")
    for cl in spec["clumps"]:
        name, kw = nfw_kwargs(plane, cl["m200"], cl["c"], cl["x"], cl["y"])
        models.append(name)
        kwargs.append(kw)
        roles.append("dark clump")
    members = []
    for k, (x, y, l) in enumerate(draw_members(rng, spec) if spec["n_members"] else []):
        m_cat = M_STAR * l
        m_true = m_cat * spec.get("member_scale", 1.0) * 10 ** (MASS_SCATTER_DEX * rng.normal())
        q = rng.uniform(0.6, 1.0)
        theta = rng.uniform(-90, 90)
        a = 1.0 * (m_cat / 1e12) ** (1 / 3)
        mag = plane.mag_star - 2.5 * np.log10(m_cat / M_STAR)
        members.append(dict(id=k + 1, x=x, y=y, a=a, b=a * q, theta=theta, mag=mag, lum=l,
                            mass_catalogue_msun=m_cat, mass_true_msun=m_true))
        if "member_dpie" in spec:
            # The law's scatter, as a factor on the dPIE's mass (v_disp^2, radii as written).
            m_true, kw = dpie_kwargs(plane, spec["member_dpie"], l, m_true / m_cat, x, y)
            models.append("PJAFFE")
            kwargs.append(kw)
            members[-1]["mass_true_msun"] = m_true
        else:
            models.append("TNFW")
            kwargs.append(tnfw_kwargs(plane, m_true, x, y))
        roles.append("member")
    if "shear" in spec:
        two = np.deg2rad(2 * spec["shear"]["angle_deg"])
        g = spec["shear"]["gamma"]
        models.append("SHEAR")
        kwargs.append({"gamma1": g * np.cos(two), "gamma2": g * np.sin(two), "ra_0": 0.0,
                       "dec_0": 0.0})
        roles.append("external shear")
    return models, kwargs, roles, members


# ----------------------------------------------------------------------------------------------
# Grids and images


def eval_grid(lens, kwargs, xs, ys, chunk=200_000):
    """alpha_x, alpha_y, kappa, gamma1, gamma2 (D_ls/D_s of kwargs) at points xs, ys."""
    out = np.empty((5, xs.size))
    for s in range(0, xs.size, chunk):
        x, y = xs[s:s + chunk], ys[s:s + chunk]
        ax, ay = lens.alpha(x, y, kwargs)
        fxx, fxy, fyx, fyy = lens.hessian(x, y, kwargs)
        out[:, s:s + chunk] = [ax, ay, 0.5 * (fxx + fyy), 0.5 * (fxx - fyy), fxy]
    return out


def triangle_candidates(gx, gy, bx, by, beta):
    """Image-plane cells whose two triangles map around `beta` (ray shooting on the grid);
    returns the centres of those cells."""
    px, py = bx - beta[0], by - beta[1]
    out = []
    for tri in (((0, 0), (1, 0), (1, 1)), ((0, 0), (1, 1), (0, 1))):
        (i0, j0), (i1, j1), (i2, j2) = tri
        n0, n1 = px.shape
        s = lambda a, di, dj: a[di:n0 - 1 + di, dj:n1 - 1 + dj]
        ax, ay = s(px, i0, j0), s(py, i0, j0)
        bxx, byy = s(px, i1, j1), s(py, i1, j1)
        cx, cy = s(px, i2, j2), s(py, i2, j2)
        d1 = ax * byy - ay * bxx
        d2 = bxx * cy - byy * cx
        d3 = cx * ay - cy * ax
        inside = ((d1 >= 0) & (d2 >= 0) & (d3 >= 0)) | ((d1 <= 0) & (d2 <= 0) & (d3 <= 0))
        ii, jj = np.nonzero(inside)
        out += list(zip(gx[ii, jj] + 0.5 * FINE_PIX, gy[ii, jj] + 0.5 * FINE_PIX))
    return out


def solve_images(solver, lens, kw_f, beta, cands):
    """Images of `beta`: lenstronomy's LensEquationSolver started in a 2 arcsec window around
    each ray-shooting candidate; solutions merged within 1e-3 arcsec."""
    found = []
    for cx, cy in cands:
        xs, ys = solver.image_position_from_source(
            beta[0], beta[1], kw_f, solver="lenstronomy", min_distance=0.02, search_window=2.0,
            x_center=cx, y_center=cy, precision_limit=1e-10, num_iter_max=200,
            arrival_time_sort=False)
        for x, y in zip(xs, ys):
            if all(np.hypot(x - a, y - b) > 1e-3 for a, b in found):
                found.append((x, y))
    good = []
    for x, y in found:
        bx, by = lens.ray_shooting(x, y, kw_f)
        if np.hypot(bx - beta[0], by - beta[1]) < 1e-6:
            good.append((x, y))
    return good, len(found) - len(good)


def cluster_groups(cands, radius=1.0):
    """One representative per group of candidate cells within `radius` arcsec."""
    reps = []
    for c in cands:
        if all(np.hypot(c[0] - r[0], c[1] - r[1]) > radius for r in reps):
            reps.append(c)
    return reps


def in_hull(hull_eq, x, y, tol=1e-9):
    return np.all(hull_eq[:, 0:1] * x[None] + hull_eq[:, 1:2] * y[None] + hull_eq[:, 2:3] <= tol,
                  axis=0)


# ----------------------------------------------------------------------------------------------


def make_cluster(spec, out_root, log):
    t0 = time.time()
    rng = np.random.default_rng(spec["seed"])
    plane = Plane(spec["z_l"])
    log(f"{spec['name']}: z_l = {plane.z_l}, D_l = {plane.d_l:.2f} Mpc, "
        f"mag* = {plane.mag_star:.3f}")
    check_conversions(plane, log)
    models, kwargs, roles, members = build_lens(plane, spec, rng)
    lens = LensModel(models)
    solver = LensEquationSolver(lens)

    # Fine truth grid at D_ls/D_s = 1 (pixel centres).
    n = int(round(2 * FIELD_HALF / FINE_PIX))
    c1 = -FIELD_HALF + (np.arange(n) + 0.5) * FINE_PIX
    gx, gy = np.meshgrid(c1, c1)  # [j (y), i (x)]
    ax, ay, kap, g1, g2 = eval_grid(lens, kwargs, gx.ravel(), gy.ravel())
    ax, ay, kap, g1, g2 = (a.reshape(n, n) for a in (ax, ay, kap, g1, g2))
    shear = np.hypot(g1, g2)
    log(f"  fine grid {n}x{n} at {FINE_PIX} arcsec: {time.time() - t0:.1f} s")

    # Einstein radius at z_s = 2 (wslap's definition: area with 1 - f (kappa + |gamma|) < 0).
    f2 = plane.f(2.0)
    lam_t2 = 1 - f2 * (kap + shear)
    neg = lam_t2 < 0
    border = np.concatenate([neg[0], neg[-1], neg[:, 0], neg[:, -1]]).sum()
    assert border == 0, f"tangential region reaches the truth grid border ({border} px)"
    theta_e = np.sqrt(neg.sum() * FINE_PIX**2 / np.pi)
    # Tangential critical curves: closed zero contours of lambda_t (contourpy, marching squares).
    tang_lines = contourpy.contour_generator(c1, c1, lam_t2).lines(0.0)
    n_tang = sum(1 for ln in tang_lines if len(ln) > 2)
    log(f"  theta_E(z_s=2) = {theta_e:.3f} arcsec (f = {f2:.4f}); {n_tang} tangential curves")

    # Sources near the tangential caustics.
    systems = []
    stats = dict(draws=0, too_few=0, too_close=0, unverified=0)
    n_sys = spec["n_sys"]
    while len(systems) < n_sys:
        stats["draws"] += 1
        assert stats["draws"] < 40 * n_sys, stats
        z_s = 1.0 + 4.5 * rng.uniform() ** 1.6
        f = plane.f(z_s)
        lam_t = 1 - f * (kap + shear)
        near = np.abs(lam_t) < 0.03
        near &= (np.abs(gx) < IMAGE_LIMIT - 5) & (np.abs(gy) < IMAGE_LIMIT - 5)
        jj, ii = np.nonzero(near)
        k = rng.integers(len(jj))
        th = np.array([gx[jj[k], ii[k]], gy[jj[k], ii[k]]])
        al = np.array([ax[jj[k], ii[k]], ay[jj[k], ii[k]]])
        r_off = 4.0 * rng.uniform() ** 1.5
        t_off = rng.uniform(0, 2 * np.pi)
        beta = th - f * al + r_off * np.array([np.cos(t_off), np.sin(t_off)])
        bxg, byg = gx - f * ax, gy - f * ay
        cands = cluster_groups(triangle_candidates(gx, gy, bxg, byg, beta))
        kw_f = scaled_kwargs(kwargs, f)
        imgs, bad = solve_images(solver, lens, kw_f, beta, cands)
        if bad:
            stats["unverified"] += 1
        if any(all(np.hypot(cx - x, cy - y) > 1.5 for x, y in imgs) for cx, cy in cands):
            # a ray-shooting candidate without a converged image: redraw rather than guess
            stats["unverified"] += 1
            continue
        xs = np.array([p[0] for p in imgs])
        ys = np.array([p[1] for p in imgs])
        mu = lens.magnification(xs, ys, kw_f)
        keep = (np.abs(mu) >= MU_MIN) & (np.abs(xs) <= IMAGE_LIMIT) & (np.abs(ys) <= IMAGE_LIMIT)
        xs, ys, mu = xs[keep], ys[keep], mu[keep]
        if len(xs) < 2:
            stats["too_few"] += 1
            continue
        d = np.hypot(xs[:, None] - xs[None], ys[:, None] - ys[None]) + np.eye(len(xs)) * 1e9
        if d.min() < MIN_SEPARATION:
            stats["too_close"] += 1
            continue
        # time-delay order is not needed; sort by x for a stable listing
        order = np.argsort(-np.abs(mu))
        systems.append(dict(id=str(len(systems) + 1), z=round(z_s, 4), f=f,
                            beta=beta.tolist(), x=xs[order], y=ys[order], mu=mu[order]))
    log(f"  {n_sys} systems, {sum(len(s['x']) for s in systems)} images; draws {stats}; "
        f"{time.time() - t0:.1f} s")

    # Observed positions: 0.05 arcsec Gaussian noise per coordinate.
    for s in systems:
        s["x_obs"] = s["x"] + ASTROMETRIC_NOISE * rng.normal(size=len(s["x"]))
        s["y_obs"] = s["y"] + ASTROMETRIC_NOISE * rng.normal(size=len(s["x"]))
        s["m_src"] = rng.uniform(24.5, 27.0)

    # Image region: convex hull of all observed images.
    pts = np.array([(x, y) for s in systems for x, y in zip(s["x_obs"], s["y_obs"])])
    hull = ConvexHull(pts)
    hull_xy = pts[hull.vertices]
    eq = hull.equations
    inside = in_hull(eq, gx.ravel(), gy.ravel()).reshape(n, n)
    mass_region = kap[inside].sum() * FINE_PIX**2 * plane.sigma_cr_ref_arcsec2
    # divergence-theorem check: M = Sigma_cr/2 * closed integral of alpha . n dl
    hv = np.vstack([hull_xy, hull_xy[:1]])
    m_flux = 0.0
    for (xa, ya), (xb, yb) in zip(hv[:-1], hv[1:]):
        tt = (np.arange(400) + 0.5) / 400
        px, py = xa + tt * (xb - xa), ya + tt * (yb - ya)
        axe, aye = lens.alpha(px, py, kwargs)
        ln = np.hypot(xb - xa, yb - ya)
        nx, ny = (yb - ya) / ln, -(xb - xa) / ln  # outward for counter-clockwise vertices
        m_flux += np.sum(axe * nx + aye * ny) * ln / 400
    m_flux *= 0.5 * plane.sigma_cr_ref_arcsec2
    log(f"  image region: hull of {len(hull_xy)} vertices, area {hull.volume:.0f} arcsec^2, "
        f"M = {mass_region:.4e} Msun (pixel sum), {m_flux:.4e} (divergence theorem)")
    assert abs(m_flux / mass_region - 1) < 5e-3

    # Truth deflection on a 2 arcsec grid inside the region, and at the images.
    lo = np.floor(hull_xy.min(axis=0) / DEFL_GRID_STEP) * DEFL_GRID_STEP
    hi = np.ceil(hull_xy.max(axis=0) / DEFL_GRID_STEP) * DEFL_GRID_STEP
    qx, qy = np.meshgrid(np.arange(lo[0], hi[0] + 1e-9, DEFL_GRID_STEP),
                         np.arange(lo[1], hi[1] + 1e-9, DEFL_GRID_STEP))
    qx, qy = qx.ravel(), qy.ravel()
    sel = in_hull(eq, qx, qy)
    qx, qy = qx[sel], qy[sel]
    qax, qay = lens.alpha(qx, qy, kwargs)
    defl_grid = np.stack([qx, qy, qax, qay], axis=1).astype(np.float32)

    # Member layer truth.
    member_idx = [k for k, r in enumerate(roles) if r == "member"]
    m_true = sum(m["mass_true_msun"] for m in members)
    m_cat = sum(m["mass_catalogue_msun"] for m in members)
    member_mass_region = None
    if member_idx:
        lm = LensModel([models[k] for k in member_idx])
        kk = lm.kappa(gx.ravel(), gy.ravel(), [kwargs[k] for k in member_idx]).reshape(n, n)
        member_mass_region = kk[inside].sum() * FINE_PIX**2 * plane.sigma_cr_ref_arcsec2

    # Stored kappa map (D_ls/D_s = 1): 2 arcsec blocks of the fine grid.
    b = KAPPA_MAP_BLOCK
    kmap = kap.reshape(n // b, b, n // b, b).mean(axis=(1, 3)).astype(np.float32)

    # ---------------------------------------------------------------------- write
    out = os.path.join(out_root, spec["name"])
    os.makedirs(out, exist_ok=True)
    hdr = f"#REFERENCE 3 {spec['ra0']:.6f} {spec['dec0']:.6f}\n"
    lines = [hdr, f"# lenstronomy {lenstronomy.__version__} synthetic cluster '{spec['name']}' "
             f"(seed {spec['seed']}), z_l = {plane.z_l}; point images with "
             f"{ASTROMETRIC_NOISE} arcsec Gaussian noise\n", "# id x y a b theta z mag\n"]
    for s in systems:
        for k in range(len(s["x"])):
            mag = s["m_src"] - 2.5 * np.log10(abs(s["mu"][k]))
            lines.append(f"{s['id']}.{k + 1} {s['x_obs'][k]:.4f} {s['y_obs'][k]:.4f} 0.1 0.1 0.0 "
                         f"{s['z']:.4f} {mag:.3f}\n")
    with open(os.path.join(out, "images.cat"), "w") as fh:
        fh.writelines(lines)
    if members:
        lines = [hdr, f"# lenstronomy synthetic cluster '{spec['name']}': members with "
                 f"mag = mag* - 2.5 log10(M_cat / 1e12 Msun), mag* = {plane.mag_star:.4f}; "
                 f"true masses scattered by {MASS_SCATTER_DEX} dex\n",
                 "# id x y a b theta mag lum\n"]
        for m in members:
            lines.append(f"{m['id']} {m['x']:.4f} {m['y']:.4f} {m['a']:.4f} {m['b']:.4f} "
                         f"{m['theta']:.2f} {m['mag']:.4f} {m['lum']:.5f}\n")
        with open(os.path.join(out, "members.cat"), "w") as fh:
            fh.writelines(lines)
    np.save(os.path.join(out, "truth_deflection_grid.npy"), defl_grid)
    np.save(os.path.join(out, "truth_kappa.npy"), kmap)

    r6 = lambda v: float(f"{v:.7g}")
    img_truth = []
    for s in systems:
        axi, ayi = lens.alpha(s["x_obs"], s["y_obs"], kwargs)
        axt, ayt = lens.alpha(s["x"], s["y"], kwargs)
        for k in range(len(s["x"])):
            img_truth.append(dict(
                id=f"{s['id']}.{k + 1}", z=s["z"], distance_ratio=r6(s["f"]),
                x_true=r6(s["x"][k]), y_true=r6(s["y"][k]),
                x_obs=r6(s["x_obs"][k]), y_obs=r6(s["y_obs"][k]),
                alpha_true=[r6(axt[k]), r6(ayt[k])], alpha_obs=[r6(axi[k]), r6(ayi[k])],
                magnification=r6(s["mu"][k])))
    truth = dict(
        name=spec["name"],
        description=spec["what"],
        made_with=dict(lenstronomy=lenstronomy.__version__, numpy=np.__version__,
                       astropy=astropy.__version__, script="tests/data/fidelity/make_clusters.py",
                       seed=spec["seed"]),
        note=("Lens kwargs are for D_ls/D_s = 1 (HFF convention): for a source at z_s multiply "
              "every alpha_Rs (and an external SHEAR's gamma1, gamma2) by D_ls/D_s. Positions are arcsec in wslap's frame of "
              "'#REFERENCE 3 ra0 dec0' (+x West, +y North); lenstronomy x, y are these x, y. "
              "Observed image positions = true positions + Gaussian noise of "
              f"{ASTROMETRIC_NOISE} arcsec per coordinate. Images with |mu| < {MU_MIN} or "
              f"|x| or |y| > {IMAGE_LIMIT} arcsec are dropped; sources were drawn near the "
              "tangential caustic of their redshift; images found by ray shooting on a "
              f"{FINE_PIX} arcsec grid, then lenstronomy's LensEquationSolver "
              "(precision_limit 1e-10) around each candidate."),
        z_lens=plane.z_l,
        reference=dict(ra=spec["ra0"], dec=spec["dec0"]),
        cosmology=dict(name="FlatLambdaCDM", H0=H0, Om0=OM0, Tcmb0=0.0),
        d_l_mpc=plane.d_l,
        sigma_cr_ref_msun_per_arcsec2=plane.sigma_cr_ref_arcsec2,
        lens_model_list=models,
        kwargs_lens=[{k: float(v) for k, v in kw.items()} for kw in kwargs],
        component_roles=roles,
        halos=spec["halos"], clumps=spec["clumps"],
        external_shear=spec.get("shear"),
        einstein_radius_z2_arcsec=theta_e,
        tangential_curves_z2=n_tang,
        einstein_radius_definition=(
            "sqrt(A/pi), A = area where 1 - f (kappa + |gamma|) < 0 at z_s = 2 "
            f"(f = {f2:.6f}), counted on a {FINE_PIX} arcsec grid over +-{FIELD_HALF} arcsec "
            "(includes members' own small loops, as wslap's closed tangential loops do)"),
        image_region=dict(
            definition="convex hull of all observed image positions (arcsec)",
            hull_xy=[[r6(a), r6(b)] for a, b in hull_xy],
            area_arcsec2=hull.volume,
            mass_msun=mass_region,
            mass_divergence_check_msun=m_flux,
            member_mass_msun=member_mass_region,
            mass_method=f"sum of lenstronomy kappa at the centres of {FINE_PIX} arcsec pixels "
                        "inside the hull times Sigma_cr(D_ls/D_s=1) times pixel area"),
        members=dict(
            count=len(members),
            mass_true_total_msun=m_true,
            mass_catalogue_total_msun=m_cat,
            c_true_mass_ratio=(m_true / m_cat) if members else None,
            upsilon=UPSILON, l_star_lsun=L_STAR, abs_mag_star=ABS_MAG_STAR,
            mag_star=plane.mag_star, r_s_star_kpc=RS_STAR_KPC, r_t_star_kpc=RT_STAR_KPC,
            scatter_dex=MASS_SCATTER_DEX,
            table=[{k: (r6(v) if isinstance(v, float) else v) for k, v in m.items()}
                   for m in members]),
        systems=[dict(id=s["id"], z=s["z"], distance_ratio=r6(s["f"]),
                      beta_true=[r6(v) for v in s["beta"]], n_images=len(s["x"]))
                 for s in systems],
        images=img_truth,
        deflection_grid=dict(
            file="truth_deflection_grid.npy",
            columns=["x", "y", "alpha_x", "alpha_y"], dtype="float32",
            step_arcsec=DEFL_GRID_STEP, points=int(len(defl_grid)),
            note="points of a 2 arcsec lattice inside the image region; alpha at D_ls/D_s = 1"),
        kappa_map=dict(
            file="truth_kappa.npy", dtype="float32", shape=list(kmap.shape),
            pixel_arcsec=FINE_PIX * b, extent_arcsec=[-FIELD_HALF, FIELD_HALF],
            note="kappa at D_ls/D_s = 1, row j = y, column i = x (pixel (0,0) at the "
                 "(-x, -y) corner), block means of the fine grid"),
    )
    with open(os.path.join(out, "truth.json"), "w") as fh:
        json.dump(truth, fh, indent=1)
    log(f"  wrote {out} in {time.time() - t0:.1f} s")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--only", action="append", help="cluster name (repeatable)")
    ap.add_argument("--seed-offset", type=int, default=0,
                    help="draw each recipe again with its seed plus this (members, sources and "
                         "scatter change, the halos stay); the folder is NAME-seedS. The "
                         "committed clusters are offset 0; other offsets test that the defaults "
                         "were not fitted to these draws (BENCHMARKS.md)")
    args = ap.parse_args()
    log = lambda s: print(s, flush=True)
    for spec in CLUSTERS:
        if args.only and spec["name"] not in args.only:
            continue
        if args.seed_offset:
            spec = dict(spec, seed=spec["seed"] + args.seed_offset)
            spec["name"] = f"{spec['name']}-seed{spec['seed']}"
        make_cluster(spec, args.out, log)


if __name__ == "__main__":
    sys.exit(main())

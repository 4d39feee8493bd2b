#!/usr/bin/env python3
"""Weak-lensing synthetic cluster for tests/inversion/shear.rs, made with lenstronomy.

Nothing here uses this project's code. The lens is the fidelity cluster `c_smooth` (one
elliptical NFW, M200 = 1.4e15 Msun, c = 7, q = 0.72, z_l = 0.32; its lenstronomy kwargs from
tests/data/fidelity/c_smooth/truth.json, made by tests/data/fidelity/make_clusters.py). Run
from the repository root:

    /tmp/refenv/bin/python tests/data/weak_lensing/make_weak_lensing.py

Writes into tests/data/weak_lensing/:
- images.cat: the first N_SYSTEMS systems of c_smooth's images.cat (point images found by
  lenstronomy's LensEquationSolver there), as written;
- arclets.cat: N_GALAXIES background galaxies uniform in the annulus R_MIN..R_MAX arcsec
  about the halo centre, redshifts uniform in Z_RANGE; each galaxy's intrinsic ellipticity
  has Gaussian components of scatter SHAPE_NOISE (|e_s| < 0.9), lensed by lenstronomy's
  reduced shear g = gamma / (1 - kappa) at its redshift: e = (e_s + g) / (1 + conj(g) e_s)
  (Seitz & Schneider 1997, for |g| < 1, the (a - b)/(a + b) ellipticity); written as
  a = 0.5 arcsec, b = a (1 - |e|)/(1 + |e|), theta = arg(e) / 2 in degrees counter-clockwise
  from +x;
- truth.json: the projected mass inside 60, 120 and 180 arcsec of the halo centre (lenstronomy
  kappa at D_ls/D_s = 1 summed on a 0.25 arcsec grid, times Sigma_cr_ref of c_smooth's
  truth.json), and the settings above;
- rows_reference.json: for the rows' unit test, a spherical NFW's kappa, gamma_1, gamma_2 at a
  few points (lenstronomy 'NFW', D_ls/D_s = 1) and, for a galaxy there at z = 1.5 with
  e = (0.12, -0.07), its rows' values in the NFW's column, f gamma_i, and their right-hand
  sides e_i (1 - f kappa) once kappa_0 is the NFW's (src/inversion/shear.rs).

Deterministic (numpy default_rng(SEED)).
"""

import argparse
import json
import os

import numpy as np
from astropy import constants as const
from astropy import units as u
from astropy.cosmology import FlatLambdaCDM

import lenstronomy
from lenstronomy.LensModel.lens_model import LensModel

HERE = os.path.dirname(os.path.abspath(__file__))
FIDELITY = os.path.join(HERE, "..", "fidelity", "c_smooth")
COSMO = FlatLambdaCDM(H0=70.0, Om0=0.3)
ARCSEC_RAD = np.pi / 180.0 / 3600.0
C2_4PIG = (const.c**2 / (4 * np.pi * const.G)).to(u.Msun / u.Mpc).value

SEED = 2407
N_SYSTEMS = 6
N_GALAXIES = 3000
R_MIN, R_MAX = 45.0, 240.0
Z_RANGE = (0.8, 2.5)
SHAPE_NOISE = 0.3
A_ARCSEC = 0.5
RADII = [60.0, 120.0, 180.0]
MASS_PIX = 0.25


def distance_ratio(z_l, z_s):
    d_s = COSMO.angular_diameter_distance(z_s).value
    return COSMO.angular_diameter_distance(z_l, z_s).value / d_s


def scaled(kwargs, f):
    out = []
    for kw in kwargs:
        kw = dict(kw)
        kw["alpha_Rs"] *= f
        out.append(kw)
    return out


def kappa_gamma(lens, kwargs, x, y):
    fxx, fxy, _, fyy = lens.hessian(x, y, kwargs)
    return 0.5 * (fxx + fyy), 0.5 * (fxx - fyy), fxy


def images_cat(path_in, path_out):
    """The header and the first N_SYSTEMS systems of c_smooth's catalogue."""
    keep, systems = [], []
    with open(path_in) as fh:
        for line in fh:
            if line.startswith("#"):
                keep.append(line)
                continue
            sys_id = line.split()[0].split(".")[0]
            if sys_id not in systems:
                systems.append(sys_id)
            if len(systems) <= N_SYSTEMS:
                keep.append(line)
    keep.insert(2, f"# the first {N_SYSTEMS} systems of tests/data/fidelity/c_smooth/images.cat\n")
    with open(path_out, "w") as fh:
        fh.writelines(keep)
    return systems[:N_SYSTEMS]


def lensed_ellipticity(e_s, g):
    """(a - b)/(a + b) ellipticity of a source of intrinsic e_s under reduced shear g."""
    small = np.abs(g) <= 1
    e = np.where(small, (e_s + g) / (1 + np.conj(g) * e_s),
                 (1 + g * np.conj(e_s)) / (np.conj(e_s) + np.conj(g)))
    return e


def arclets(rng, truth, lens, kwargs):
    z_l = truth["z_lens"]
    n = N_GALAXIES
    r = np.sqrt(rng.uniform(R_MIN**2, R_MAX**2, n))
    phi = rng.uniform(0, 2 * np.pi, n)
    x, y = r * np.cos(phi), r * np.sin(phi)
    z = rng.uniform(*Z_RANGE, n)
    e_s = np.empty(n, complex)
    for k in range(n):
        while True:
            v = complex(*rng.normal(0, SHAPE_NOISE, 2))
            if abs(v) < 0.9:
                e_s[k] = v
                break
    g = np.empty(n, complex)
    for k in range(n):
        f = distance_ratio(z_l, z[k])
        kap, g1, g2 = kappa_gamma(lens, scaled(kwargs, f), x[k], y[k])
        g[k] = complex(g1, g2) / (1 - kap)
    e = lensed_ellipticity(e_s, g)
    mod = np.abs(e)
    b = A_ARCSEC * (1 - mod) / (1 + mod)
    theta = np.degrees(0.5 * np.angle(e))
    return x, y, b, theta, z, g


def enclosed_masses(lens, kwargs, sigma_cr):
    half = max(RADII)
    n = int(round(2 * half / MASS_PIX))
    c = -half + (np.arange(n) + 0.5) * MASS_PIX
    gx, gy = np.meshgrid(c, c)
    kap = np.empty(gx.size)
    flat_x, flat_y = gx.ravel(), gy.ravel()
    for s in range(0, flat_x.size, 500_000):
        kap[s:s + 500_000] = lens.kappa(flat_x[s:s + 500_000], flat_y[s:s + 500_000], kwargs)
    r = np.hypot(flat_x, flat_y)
    return [float(kap[r <= R].sum() * MASS_PIX**2 * sigma_cr) for R in RADII]


def rows_reference(z_l):
    d_l = COSMO.angular_diameter_distance(z_l).to(u.Mpc).value
    rho_c = COSMO.critical_density(z_l).to(u.Msun / u.Mpc**3).value
    m200, c200, centre = 8.0e14, 5.0, (3.0, -2.0)
    r200 = (3 * m200 / (800 * np.pi * rho_c)) ** (1 / 3)
    rs = r200 / c200
    rho_s = m200 / (4 * np.pi * rs**3 * (np.log1p(c200) - c200 / (1 + c200)))
    kappa_s = rho_s * rs / (C2_4PIG / d_l)
    rs_as = rs / (d_l * ARCSEC_RAD)
    kw = [{"Rs": rs_as, "alpha_Rs": 4 * kappa_s * rs_as * (1 - np.log(2)),
           "center_x": centre[0], "center_y": centre[1]}]
    lens = LensModel(["NFW"])
    z_s, e = 1.5, (0.12, -0.07)
    f = distance_ratio(z_l, z_s)
    points = []
    for p in [(20.0, 5.0), (-60.0, 45.0), (110.0, -150.0), (4.0, -1.0)]:
        kap, g1, g2 = (float(v) for v in kappa_gamma(lens, kw, *p))
        points.append(dict(x=p[0], y=p[1], kappa=kap, gamma1=g1, gamma2=g2,
                           row1=f * g1, row2=f * g2,
                           target1=e[0] * (1 - f * kap), target2=e[1] * (1 - f * kap)))
    return dict(
        generator="tests/data/weak_lensing/make_weak_lensing.py",
        lenstronomy_version=lenstronomy.__version__,
        z_lens=z_l, h0=70.0, omega_m=0.3,
        nfw=dict(m200_msun=m200, c200=c200, center=list(centre), r_s_arcsec=rs_as,
                 kappa_s=kappa_s),
        galaxy=dict(z=z_s, e=list(e), distance_ratio=f),
        points=points,
    )


def main():
    global HERE, SEED
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=SEED, help="another realisation (default: the stored one)")
    ap.add_argument("--out", default=HERE, help="output folder (default: this script's)")
    args = ap.parse_args()
    SEED, HERE = args.seed, args.out
    os.makedirs(HERE, exist_ok=True)
    rng = np.random.default_rng(SEED)
    with open(os.path.join(FIDELITY, "truth.json")) as fh:
        truth = json.load(fh)
    lens = LensModel(truth["lens_model_list"])
    kwargs = truth["kwargs_lens"]
    ids = images_cat(os.path.join(FIDELITY, "images.cat"), os.path.join(HERE, "images.cat"))
    x, y, b, theta, z, g = arclets(rng, truth, lens, kwargs)
    ref = truth["reference"]
    with open(os.path.join(HERE, "arclets.cat"), "w") as fh:
        fh.write(f"#REFERENCE 3 {ref['ra']:.6f} {ref['dec']:.6f}\n")
        fh.write(f"# lenstronomy {lenstronomy.__version__} weak lensing of fidelity cluster "
                 f"c_smooth (seed {SEED}): shape noise {SHAPE_NOISE} per component\n")
        fh.write("# id x y a b theta z\n")
        for k in range(len(x)):
            fh.write(f"{k + 1} {x[k]:.4f} {y[k]:.4f} {A_ARCSEC:.4f} {b[k]:.5f} "
                     f"{theta[k]:.3f} {z[k]:.4f}\n")
    masses = enclosed_masses(lens, kwargs, truth["sigma_cr_ref_msun_per_arcsec2"])
    out = dict(
        generator="tests/data/weak_lensing/make_weak_lensing.py",
        lenstronomy_version=lenstronomy.__version__,
        numpy_version=np.__version__,
        lens="tests/data/fidelity/c_smooth/truth.json",
        z_lens=truth["z_lens"],
        center_arcsec=[0.0, 0.0],
        systems=ids,
        galaxies=N_GALAXIES, r_min_arcsec=R_MIN, r_max_arcsec=R_MAX, z_range=list(Z_RANGE),
        shape_noise=SHAPE_NOISE, seed=SEED,
        reduced_shear_abs_max=float(np.abs(g).max()),
        reduced_shear_abs_median=float(np.median(np.abs(g))),
        radii_arcsec=RADII,
        mass_within_msun=masses,
        mass_definition=f"sum of lenstronomy kappa (D_ls/D_s = 1) on a {MASS_PIX} arcsec grid "
                        "inside each radius of the centre, times sigma_cr_ref",
    )
    with open(os.path.join(HERE, "truth.json"), "w") as fh:
        json.dump(out, fh, indent=1)
    with open(os.path.join(HERE, "rows_reference.json"), "w") as fh:
        json.dump(rows_reference(truth["z_lens"]), fh, indent=1)
    print(json.dumps({k: out[k] for k in ("mass_within_msun", "reduced_shear_abs_max",
                                          "reduced_shear_abs_median")}))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The lenstronomy side of the `maps` benchmark (BENCHMARKS.md).

Computes the same product set as `wslap maps` (kappa, gamma1, gamma2, alpha_x, alpha_y and the
magnification at z_s = 2) for benches/maps-model.json on a PIXELS x PIXELS grid, SIZE arcsec wide,
and prints the wall time. lenstronomy normalises to a source redshift, so it is set up for
z_s = 2 and its maps are divided by D_ls/D_s to compare with the D_ls/D_s = 1 maps of wslap.

Usage: python3 benches/maps_lenstronomy.py [PIXELS] [SIZE] [--compare DIR]
(--compare reads DIR/kappa.fits and DIR/x-arcsec-deflect.fits written by wslap and prints
the largest relative difference, as a check that both computed the same thing).
"""
import json
import os
import sys
import time

import numpy as np
from astropy.cosmology import FlatLambdaCDM
from lenstronomy.Cosmo.lens_cosmo import LensCosmo
from lenstronomy.LensModel.lens_model import LensModel
import lenstronomy.Util.param_util as param_util

HERE = os.path.dirname(os.path.abspath(__file__))
args = [a for a in sys.argv[1:] if not a.startswith("--")]
pixels = int(args[0]) if args else 1024
size = float(args[1]) if len(args) > 1 else 200.0
compare = sys.argv[sys.argv.index("--compare") + 1] if "--compare" in sys.argv else None

model = json.load(open(os.path.join(HERE, "maps-model.json")))
z_l, z_s = model["z_lens"], 2.0
cosmo = FlatLambdaCDM(H0=model["cosmology"]["h0"], Om0=model["cosmology"]["omega_m"], Tcmb0=0)
lc = LensCosmo(z_lens=z_l, z_source=z_s, cosmo=cosmo)
f = lc.dds / lc.ds  # D_ls / D_s

names, kwargs = [], []
for c in model["components"]:
    rs, alpha_rs = lc.nfw_physical2angle(M=c["m200"], c=c["c200"])
    if c["type"] == "nfw":
        phi = np.deg2rad(c.get("pa", 0.0))
        e1, e2 = param_util.phi_q2_ellipticity(phi=phi, q=c.get("q", 1.0))
        names.append("NFW_ELLIPSE_CSE")
        kwargs.append({"Rs": rs, "alpha_Rs": alpha_rs, "e1": e1, "e2": e2,
                       "center_x": c["x"], "center_y": c["y"]})
    else:
        names.append("TNFW")
        kwargs.append({"Rs": rs, "alpha_Rs": alpha_rs, "r_trunc": c["r_trunc"],
                       "center_x": c["x"], "center_y": c["y"]})
lens = LensModel(names)

pix = size / pixels
coords = (np.arange(pixels) + 0.5 - pixels / 2) * pix
x, y = np.meshgrid(coords, coords)
x, y = x.ravel(), y.ravel()

t0 = time.perf_counter()
ax, ay = lens.alpha(x, y, kwargs)
fxx, fxy, fyx, fyy = lens.hessian(x, y, kwargs)
kappa = 0.5 * (fxx + fyy) / f
gamma1 = 0.5 * (fxx - fyy) / f
gamma2 = fxy / f
mu = 1.0 / ((1.0 - f * kappa) ** 2 - f * f * (gamma1 ** 2 + gamma2 ** 2))
ax, ay = ax / f, ay / f
elapsed = time.perf_counter() - t0
print(f"lenstronomy: {pixels}x{pixels} map, {len(names)} components: {elapsed:.2f} s")

if compare:
    from astropy.io import fits
    ours_kappa = fits.getdata(os.path.join(compare, "kappa.fits")).astype(float).ravel()
    ours_ax = fits.getdata(os.path.join(compare, "x-arcsec-deflect.fits")).astype(float).ravel()
    r = np.hypot(x, y)
    away = r > 2.0 * pix
    print("max |kappa_wslap - kappa_lenstronomy| / max kappa:",
          np.max(np.abs(ours_kappa[away] - kappa[away])) / np.max(kappa[away]))
    print("max |alpha_x_wslap - alpha_x_lenstronomy| [arcsec]:",
          np.max(np.abs(ours_ax - ax)))

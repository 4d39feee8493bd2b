#!/usr/bin/env python3
"""Reference images for tests/physics/images.rs: lenstronomy's LensEquationSolver on the
elliptical NFW cluster of the tests.

Run from the repository root:  python3 tests/data/images_reference.py  > writes
tests/data/images.json

* Cosmology: astropy FlatLambdaCDM(H0=70, Om0=0.3, Tcmb0=0) (the crate's default); lens at
  z_l = 0.3, source at z_s = 2, f = D_ls/D_s from astropy.
* Halo: M200 = 1e15 Msun (200 rho_crit(z_l)), c200 = 5, q = 0.7, PA 30 deg, centre (1, -2)
  arcsec; r_s and kappa_s from astropy's CODATA 2018 constants as in tests/data/nfw_reference.py.
  lenstronomy 'NFW_ELLIPSE_CSE' with Rs = r_s and alpha_Rs = f * 4 kappa_s r_s (1 + ln 1/2)
  (the deflection at D_ls/D_s = f), e1 + i e2 = (1 - q)/(1 + q) exp(2 i PA).
* Images: LensEquationSolver.image_position_from_source (precision 1e-10 arcsec in the source
  plane, 120 arcsec window) and the signed magnification from LensModel.magnification.
"""

import json
import math
import os

from astropy import constants as const
from astropy import units as u
from astropy.cosmology import FlatLambdaCDM
from lenstronomy.LensModel.lens_model import LensModel
from lenstronomy.LensModel.Solver.lens_equation_solver import LensEquationSolver

COSMO = FlatLambdaCDM(H0=70.0, Om0=0.3, Tcmb0=0.0)
Z_LENS = 0.3
Z_SOURCE = 2.0
ARCSEC = math.pi / 180.0 / 3600.0
CENTER = [1.0, -2.0]
M200, C200, Q, PA_DEG = 1.0e15, 5.0, 0.7, 30.0
# Source offsets from the halo centre, arcsec: inside the inner caustics (5 images), near a
# fold (3 images) and outside every caustic (1 image).
SOURCE_OFFSETS = [[0.8, 0.5], [-1.2, 0.4], [2.2, -0.5], [2.0, 1.5], [15.0, 12.0]]


def scales(m200, c200):
    """r_s [arcsec] and kappa_s (D_ls/D_s = 1) with astropy constants."""
    d_l = COSMO.angular_diameter_distance(Z_LENS).to(u.Mpc).value
    rho_c = COSMO.critical_density(Z_LENS).to(u.Msun / u.Mpc**3).value
    r200 = (3.0 * m200 / (800.0 * math.pi * rho_c)) ** (1.0 / 3.0)
    r_s = r200 / c200
    rho_s = 200.0 / 3.0 * rho_c * c200**3 / (math.log1p(c200) - c200 / (1.0 + c200))
    sigma_cr = (const.c**2 / (4.0 * math.pi * const.G)).to(u.Msun / u.Mpc).value / d_l
    return r_s / (d_l * ARCSEC), rho_s * r_s / sigma_cr


def main():
    d_s = COSMO.angular_diameter_distance(Z_SOURCE).value
    # Flat universe: D_ls = (D_C(z_s) - D_C(z_l)) / (1 + z_s).
    d_c = [COSMO.comoving_distance(z).value for z in (Z_LENS, Z_SOURCE)]
    d_ls = (d_c[1] - d_c[0]) / (1.0 + Z_SOURCE)
    f = d_ls / d_s
    r_s, kappa_s = scales(M200, C200)
    e = (1.0 - Q) / (1.0 + Q)
    phi = math.radians(PA_DEG)
    kw = [dict(Rs=r_s, alpha_Rs=f * 4.0 * kappa_s * r_s * (1.0 + math.log(0.5)),
               e1=e * math.cos(2 * phi), e2=e * math.sin(2 * phi),
               center_x=CENTER[0], center_y=CENTER[1])]
    model = LensModel(["NFW_ELLIPSE_CSE"])
    solver = LensEquationSolver(model)
    sources = []
    for dx, dy in SOURCE_OFFSETS:
        beta = [CENTER[0] + dx, CENTER[1] + dy]
        xs, ys = solver.image_position_from_source(
            beta[0], beta[1], kw, min_distance=0.05, search_window=120.0,
            precision_limit=1e-10, num_iter_max=200, arrival_time_sort=False)
        mus = model.magnification(xs, ys, kw)
        images = [dict(x=float(x), y=float(y), magnification=float(m))
                  for x, y, m in zip(xs, ys, mus)]
        sources.append(dict(beta=beta, images=images))
    out = dict(
        generator="tests/data/images_reference.py",
        lenstronomy_version=__import__("lenstronomy").__version__,
        z_lens=Z_LENS, z_source=Z_SOURCE, f=f, center=CENTER, m200_msun=M200, c200=C200,
        q=Q, pa_deg=PA_DEG, r_s_arcsec=r_s, kappa_s=kappa_s, sources=sources,
    )
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "images.json")
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")
    print("wrote", path)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Reference potentials and time delays for tests/physics/time_delays.rs: lenstronomy's
LensModel.potential and LensModel.arrival_time at the images its LensEquationSolver finds.

Run from the repository root with numpy, astropy and lenstronomy installed:
    python3 tests/data/time_delays_reference.py      > writes tests/data/time_delays.json

* Cosmology: astropy FlatLambdaCDM(H0=70, Om0=0.3, Tcmb0=0) (the crate's default); lens at
  z_l = 0.3, source at z_s = 2; f = D_ls/D_s from astropy.
* Models, given to lenstronomy at the source's normalisation (every deflection times f):
  - "sis": theta_E = f * 25 arcsec at (1, -2);
  - "nfw": M200 = 1e15 Msun, c200 = 5 at (0, 0) ('NFW', Rs and alpha_Rs as below);
  - "nfw_ellipse": the same halo with q = 0.7, PA 30 deg at (1, -2) ('NFW_ELLIPSE_CSE');
  - "mixed": nfw_ellipse + an SIS of theta_E = f * 3 arcsec at (12, 6) + external shear
    gamma = f * 0.05 along PA 20 deg ('SHEAR' about (0, 0)).
  r_s and kappa_s come from astropy's CODATA 2018 constants as in tests/data/nfw_reference.py;
  alpha_Rs = f * 4 kappa_s r_s (1 + ln 1/2); e1 + i e2 = (1 - q)/(1 + q) exp(2 i PA).
* For each model and source: the images (precision 1e-10 arcsec), the potential psi (at f,
  arcsec^2) and the arrival time (days) of each. Only differences between images are compared.
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
M200, C200 = 1.0e15, 5.0


def scales(m200, c200):
    """r_s [arcsec] and kappa_s (D_ls/D_s = 1) with astropy constants."""
    d_l = COSMO.angular_diameter_distance(Z_LENS).to(u.Mpc).value
    rho_c = COSMO.critical_density(Z_LENS).to(u.Msun / u.Mpc**3).value
    r200 = (3.0 * m200 / (800.0 * math.pi * rho_c)) ** (1.0 / 3.0)
    r_s = r200 / c200
    rho_s = 200.0 / 3.0 * rho_c * c200**3 / (math.log1p(c200) - c200 / (1.0 + c200))
    sigma_cr = (const.c**2 / (4.0 * math.pi * const.G)).to(u.Msun / u.Mpc).value / d_l
    return r_s / (d_l * ARCSEC), rho_s * r_s / sigma_cr


def models(f):
    r_s, kappa_s = scales(M200, C200)
    alpha_rs = f * 4.0 * kappa_s * r_s * (1.0 + math.log(0.5))
    e = (1.0 - 0.7) / (1.0 + 0.7)
    phi = math.radians(30.0)
    ell = dict(Rs=r_s, alpha_Rs=alpha_rs, e1=e * math.cos(2 * phi), e2=e * math.sin(2 * phi),
               center_x=1.0, center_y=-2.0)
    g = f * 0.05
    shear = dict(gamma1=g * math.cos(2 * math.radians(20.0)),
                 gamma2=g * math.sin(2 * math.radians(20.0)), ra_0=0.0, dec_0=0.0)
    return [
        ("sis", ["SIS"], [dict(theta_E=f * 25.0, center_x=1.0, center_y=-2.0)],
         [[1.5, -1.2], [-3.0, -0.5]]),
        ("nfw", ["NFW"], [dict(Rs=r_s, alpha_Rs=alpha_rs, center_x=0.0, center_y=0.0)],
         [[2.0, 1.0], [0.3, -0.4]]),
        ("nfw_ellipse", ["NFW_ELLIPSE_CSE"], [ell], [[1.8, -1.5], [-0.2, -1.6]]),
        ("mixed", ["NFW_ELLIPSE_CSE", "SIS", "SHEAR"],
         [ell, dict(theta_E=f * 3.0, center_x=12.0, center_y=6.0), shear],
         [[1.8, -1.5], [3.0, -2.5]]),
    ]


def main():
    d_s = COSMO.angular_diameter_distance(Z_SOURCE).value
    d_c = [COSMO.comoving_distance(z).value for z in (Z_LENS, Z_SOURCE)]
    f = (d_c[1] - d_c[0]) / (1.0 + Z_SOURCE) / d_s
    r_s, kappa_s = scales(M200, C200)
    cases = []
    for name, kinds, kw, betas in models(f):
        model = LensModel(kinds, z_lens=Z_LENS, z_source=Z_SOURCE, cosmo=COSMO)
        solver = LensEquationSolver(LensModel(kinds))
        sources = []
        for beta in betas:
            xs, ys = solver.image_position_from_source(
                beta[0], beta[1], kw, min_distance=0.05, search_window=120.0,
                precision_limit=1e-10, num_iter_max=200, arrival_time_sort=True)
            psi = model.potential(xs, ys, kw)
            t = model.arrival_time(xs, ys, kw, x_source=beta[0], y_source=beta[1])
            images = [dict(x=float(x), y=float(y), psi=float(p), arrival_days=float(a))
                      for x, y, p, a in zip(xs, ys, psi, t)]
            sources.append(dict(beta=beta, images=images))
        cases.append(dict(name=name, lenstronomy_models=kinds, sources=sources))
    out = dict(
        generator="tests/data/time_delays_reference.py",
        lenstronomy_version=__import__("lenstronomy").__version__,
        z_lens=Z_LENS, z_source=Z_SOURCE, f=f, m200_msun=M200, c200=C200,
        r_s_arcsec=r_s, kappa_s=kappa_s,
        time_delay_distance_mpc=float((1 + Z_LENS) * COSMO.angular_diameter_distance(Z_LENS).value
                                      / f),
        cases=cases,
    )
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "time_delays.json")
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")
    print("wrote", path)


if __name__ == "__main__":
    main()

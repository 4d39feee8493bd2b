"""Reference fields of the SIS, point mass and Gaussian for tests/physics/physics.rs, from
lenstronomy.

Lens plane z_l = 0.3 in FlatLambdaCDM(H0=70, Om0=0.3, Tcmb0=0). Physical parameters are
converted to lenstronomy's angular ones with astropy constants, as the Rust code does:
  SIS       theta_E = 4 pi (sigma_v/c)^2 rad           (D_ls/D_s = 1)
  POINT     theta_E = sqrt(4 G m / (c^2 D_l)) rad
  GAUSSIAN  amp = m / Sigma_cr_ref [Msun/arcsec^2]     (kappa = amp/(2 pi s^2) exp(-r^2/2s^2))
Hessians are [f_xx, f_xy, f_yy]; deflections and positions in arcsec.

Run: python3 tests/data/simple_profiles_reference.py > tests/data/simple_profiles.json
"""

import json

import astropy.units as u
import lenstronomy
import numpy as np
from astropy import constants as const
from astropy.cosmology import FlatLambdaCDM
from lenstronomy.LensModel.lens_model import LensModel

Z_LENS = 0.3
COSMO = FlatLambdaCDM(H0=70.0, Om0=0.3, Tcmb0=0)
D_L = COSMO.angular_diameter_distance(Z_LENS)
ARCSEC = (1 * u.arcsec).to(u.rad).value

# Sample points (arcsec); none is at a component centre.
POINTS = [
    (0.7, 0.2),
    (-3.1, 4.4),
    (12.5, -7.25),
    (25.0, 30.0),
    (-41.0, -2.0),
    (8.0, -4.0),
    (-2.5, 3.5),
    (1.0, 2.5),
]


def sis_case(x, y, sigma_v_km_s):
    theta_e = 4 * np.pi * ((sigma_v_km_s * u.km / u.s) / const.c).decompose().value ** 2 / ARCSEC
    return (
        {"type": "sis", "x": x, "y": y, "sigma_v": sigma_v_km_s},
        "SIS",
        {"theta_E": theta_e, "center_x": x, "center_y": y},
    )


def point_case(x, y, mass_msun):
    theta_e2 = (4 * const.G * mass_msun * u.Msun / (const.c**2 * D_L)).decompose().value
    return (
        {"type": "point", "x": x, "y": y, "mass": mass_msun},
        "POINT_MASS",
        {"theta_E": np.sqrt(theta_e2) / ARCSEC, "center_x": x, "center_y": y},
    )


def gaussian_case(x, y, mass_msun, sigma_arcsec):
    sigma_cr = (const.c**2 / (4 * np.pi * const.G * D_L)).to(u.Msun / u.Mpc**2).value
    mpc_per_arcsec = D_L.to(u.Mpc).value * ARCSEC
    amp = mass_msun / (sigma_cr * mpc_per_arcsec**2)
    return (
        {"type": "gaussian", "x": x, "y": y, "mass": mass_msun, "sigma": sigma_arcsec},
        "GAUSSIAN",
        {"amp": amp, "sigma": sigma_arcsec, "center_x": x, "center_y": y},
    )


def evaluate(case):
    spec, name, kwargs = case
    model = LensModel([name])
    rows = []
    for px, py in POINTS:
        ax, ay = model.alpha(px, py, [kwargs])
        fxx, fxy, _, fyy = model.hessian(px, py, [kwargs])
        rows.append(
            {
                "x": px,
                "y": py,
                "kappa": float(model.kappa(px, py, [kwargs])),
                "alpha": [float(ax), float(ay)],
                "hessian": [float(fxx), float(fxy), float(fyy)],
            }
        )
    return {"component": spec, "lenstronomy": {name: kwargs}, "samples": rows}


CASES = [
    sis_case(10.0, -5.0, 250.0),
    sis_case(0.0, 0.0, 1000.0),
    point_case(1.5, 2.0, 1.0e12),
    gaussian_case(-3.0, 4.0, 1.0e13, 5.0),
    gaussian_case(0.5, -0.5, 2.0e11, 1.2),
]

print(
    json.dumps(
        {
            "generator": "tests/data/simple_profiles_reference.py, "
            f"lenstronomy {lenstronomy.__version__}",
            "z_lens": Z_LENS,
            "cosmology": {"h0": 70.0, "omega_m": 0.3},
            "cases": [evaluate(c) for c in CASES],
        },
        indent=1,
    )
)

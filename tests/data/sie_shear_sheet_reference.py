"""Reference fields of the SIE, external shear and mass sheet for
tests/physics/sie_shear_sheet.rs, from lenstronomy.

Conversions, as the Rust code does them:
  SIE     theta_E = 4 pi (sigma_v/c)^2 rad (product-averaged, D_ls/D_s = 1);
          e1, e2 = phi_q2_ellipticity(pa in radians, q), pa CCW from +x.
  SHEAR   gamma1, gamma2 as given, about the origin.
  CONVERGENCE  kappa as given, about the origin.
lenstronomy's SIE (NIE with s = 1e-10) takes its Hessian by finite differences of step 1e-10
arcsec, so its Hessian holds about 6 digits: the test's Hessian tolerance says so.
Hessians are [f_xx, f_xy, f_yy]; deflections and positions in arcsec.

Run: python3 tests/data/sie_shear_sheet_reference.py > tests/data/sie_shear_sheet.json
"""

import json

import astropy.units as u
import lenstronomy
import numpy as np
from astropy import constants as const
from lenstronomy.LensModel.lens_model import LensModel
from lenstronomy.Util import param_util

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


def sie_case(x, y, sigma_v_km_s, q, pa_deg):
    theta_e = 4 * np.pi * ((sigma_v_km_s * u.km / u.s) / const.c).decompose().value ** 2 / ARCSEC
    e1, e2 = param_util.phi_q2_ellipticity(np.radians(pa_deg), q)
    return (
        {"type": "sie", "x": x, "y": y, "sigma_v": sigma_v_km_s, "q": q, "pa": pa_deg},
        "SIE",
        {"theta_E": theta_e, "e1": e1, "e2": e2, "center_x": x, "center_y": y},
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
    sie_case(10.0, -5.0, 250.0, 0.7, 30.0),
    sie_case(0.0, 0.0, 1000.0, 0.4, -70.0),
    sie_case(-2.0, 1.0, 600.0, 0.95, 120.0),
    sie_case(1.0, 1.0, 400.0, 1.0, 0.0),
    ({"type": "shear", "gamma1": 0.07, "gamma2": -0.03}, "SHEAR", {"gamma1": 0.07, "gamma2": -0.03}),
    ({"type": "sheet", "kappa": 0.12}, "CONVERGENCE", {"kappa": 0.12}),
]

print(
    json.dumps(
        {
            "generator": "tests/data/sie_shear_sheet_reference.py, "
            f"lenstronomy {lenstronomy.__version__}",
            "z_lens": 0.3,
            "cosmology": {"h0": 70.0, "omega_m": 0.3},
            "cases": [evaluate(c) for c in CASES],
        },
        indent=1,
    )
)

"""Reference distances for tests/physics/physics.rs, from astropy's FlatLambdaCDM (Tcmb0 = 0).

Run: python3 tests/data/cosmology_reference.py > tests/data/cosmology.json
"""

import json

import astropy
import numpy as np
import astropy.units as u
from astropy import constants as const
from astropy.cosmology import FlatLambdaCDM

COSMOLOGIES = [(70.0, 0.3), (67.7, 0.31)]
REDSHIFTS = [0.05, 0.19, 0.3, 0.5, 1.0, 2.0, 3.0, 5.5]
PAIRS = [(0.19, 1.0), (0.3, 0.5), (0.3, 2.0), (0.5, 3.0), (0.19, 5.5)]


def one(h0, om):
    cosmo = FlatLambdaCDM(H0=h0, Om0=om, Tcmb0=0)
    c2_4pig = (const.c**2 / (4 * np.pi * const.G)).to(u.Msun / u.Mpc).value
    rad_per_arcsec = (1 * u.arcsec).to(u.rad).value
    return {
        "h0": h0,
        "omega_m": om,
        "distances": [
            {
                "z": z,
                "d_a_mpc": cosmo.angular_diameter_distance(z).to(u.Mpc).value,
                "rho_crit_msun_per_mpc3": cosmo.critical_density(z).to(u.Msun / u.Mpc**3).value,
                # Sigma_cr_ref = c^2 / (4 pi G D_l) converted to Msun/arcsec^2 on the plane at z.
                "sigma_cr_ref_msun_per_arcsec2": c2_4pig
                / cosmo.angular_diameter_distance(z).to(u.Mpc).value
                * (cosmo.angular_diameter_distance(z).to(u.Mpc).value * rad_per_arcsec) ** 2,
            }
            for z in REDSHIFTS
        ],
        "pairs": [
            {
                "z1": z1,
                "z2": z2,
                "d_a_z1z2_mpc": cosmo.angular_diameter_distance(z1, z2).to(u.Mpc).value,
                "distance_ratio": (
                    cosmo.angular_diameter_distance(z1, z2) / cosmo.angular_diameter_distance(z2)
                ).decompose().value,
            }
            for z1, z2 in PAIRS
        ],
    }


print(
    json.dumps(
        {
            "generator": f"tests/data/cosmology_reference.py, astropy {astropy.__version__}",
            "cosmologies": [one(h0, om) for h0, om in COSMOLOGIES],
        },
        indent=1,
    )
)

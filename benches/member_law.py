#!/usr/bin/env python3
"""An L* member's deflection under wslap's member law against published Lenstool fits.

wslap's member prior (src/inversion/members.rs) gives an L* galaxy (5e10 Lsun, M/L 20) a
truncated NFW of 1e12 Msun with r_s = 10 kpc and r_t = 40 kpc. Published Lenstool models fit
their members as dPIE halos scaled from a reference galaxy (`potfile`: sigma, cut radius and
core at magnitude `mag0`, with sigma ~ L^(1/4), r_cut and r_core ~ L^(1/2)). This script puts
both at the L* magnitude of each cluster (M* = -21.5 at z_l, as wslap does) and prints their
deflections (D_ls/D_s = 1) at 1 - 50 kpc, the ratios at 2 and 5 kpc, and the total masses.

The published values (the best fits' potfile blocks, or where the .par lists every member, its
brightest galaxy) are written below with their files; those are in
github.com/cerschae/Lenstool-HPC (GPL-3, commit af57aac, Benchmarks/ConfigFiles/hff_slmodels/)
and, for SMACS J0723, tests/data/lenstool/smacs0723 (CC0).

    /tmp/refenv/bin/python benches/member_law.py
"""

import sys
from pathlib import Path

import numpy as np
from lenstronomy.LensModel.Profiles.pseudo_jaffe import PseudoJaffe
from lenstronomy.LensModel.Profiles.tnfw import TNFW

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
sys.path[:0] = [str(DATA / "fidelity"), str(DATA)]
import make_clusters as mc  # noqa: E402  (wslap's member law, written independently of it)
from dpie_reference import b0_arcsec  # noqa: E402  (Lenstool's dPIE strength, 6 pi (sigma/c)^2)

# name, z_l, mag0, sigma (km/s), r_cut (kpc; None: given in arcsec), r_core (kpc), where
MODELS = [
    ("A2744 CATS", 0.308, 19.44, 155.47, 13.69, 0.15, "A2744/bestopt.par potfile1"),
    ("A370 CATS", 0.375, 19.7838, 179.95, 10.53, 0.15, "A370/bestopt.par potfile0"),
    ("AS1063 CATS gold", 0.3475, 19.6875, 100.11, 45.0, 0.15, "AS1063/cats_gold/bestopt.par"),
    ("AS1063 CATS silver", 0.3475, 19.6875, 102.10, 45.0, 0.15, "AS1063/cats_silver/bestopt.par"),
    ("M1149 CATS", 0.544, 20.645, 151.63, 59.13, 0.15, "M1149/m1149_catsv4/bestopt.par"),
    # mod.par's potfile (mag0, core) with bayes.dat's smallest-chi2 sample (Pot0 rcut 9.146",
    # sigma 140.18 km/s)
    ("M1149 Jauzac16", 0.544, 20.645, 140.18, ("arcsec", 9.146), 0.15, "M1149/m1149_jauzac16"),
    # best.par's galaxy 1 (mag 18.28): v_disp, cut_radius_kpc, core_radius_kpc
    ("SMACS0723 Mahler23", 0.39, 18.2818, 240.81, 97.57, 0.2207, "smacs0723/best.par"),
]
RADII_KPC = np.array([1, 2, 5, 10, 20, 50])


def dpie_alpha(r, b0, a, s):
    """Deflection at radius r of Lenstool's circular dPIE of strength b0, core a and cut s
    (lenstronomy's PJAFFE, as in tests/data/dpie_reference.py: sigma0 = b0 / (2 a))."""
    fx, fy = PseudoJaffe().derivatives(r, 0 * r, sigma0=b0 / (2 * a), Ra=a, Rs=s)
    return np.hypot(fx, fy)


def main():
    print("| model | sigma, r_cut of its L* (km/s, kpc) | published alpha at "
          + " / ".join(f"{r:g}" for r in RADII_KPC) + " kpc (\") | wslap's (C = 1) | "
          "published / wslap at 2 / 5 kpc | total mass published / wslap |")
    print("|---|---|---|---|---|---|")
    for name, z, mag0, sig0, cut0, core0, _ in MODELS:
        plane = mc.Plane(z)
        arcsec_per_kpc = 1e-3 / plane.mpc_per_arcsec
        if isinstance(cut0, tuple):
            cut0 = cut0[1] / arcsec_per_kpc
        lum = 10 ** (-0.4 * (plane.mag_star - mag0))  # L* / L(mag0)
        sig, cut, core = sig0 * lum**0.25, cut0 * lum**0.5, core0 * lum**0.5
        b0 = b0_arcsec(sig)
        r = RADII_KPC * arcsec_per_kpc
        ours = mc.tnfw_kwargs(plane, mc.M_STAR, 0.0, 0.0)
        fx, fy = TNFW().derivatives(r, 0 * r, Rs=ours["Rs"], alpha_Rs=ours["alpha_Rs"],
                                    r_trunc=ours["r_trunc"])
        a_ours = np.hypot(fx, fy)
        a_pub = dpie_alpha(r, b0, core * arcsec_per_kpc, cut * arcsec_per_kpc)
        m_pub = np.pi * b0 * cut * arcsec_per_kpc * plane.sigma_cr_ref_arcsec2
        print(f"| {name} | {sig:.0f}, {cut:.1f} | " + " / ".join(f"{v:.2f}" for v in a_pub)
              + " | " + " / ".join(f"{v:.2f}" for v in a_ours)
              + f" | {a_pub[1] / a_ours[1]:.2f} / {a_pub[2] / a_ours[2]:.2f} | {m_pub / mc.M_STAR:.2f} |")


if __name__ == "__main__":
    main()

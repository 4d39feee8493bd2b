#!/usr/bin/env python3
"""Cross-check of the fidelity truth against `wslap maps` (frame, units, normalisation).

For each cluster, writes the truth lens as a wslap model file (elliptical NFW halos with
q and pa = lenstronomy's phi, spherical NFW clumps, TNFW members with the parent NFW's M200 and
c200 recovered from the lenstronomy kwargs), runs `wslap maps` on a 200 arcsec, 0.2 arcsec-pixel
map and compares with truth.json: the deflection on the truth grid (D_ls/D_s = 1), the
Einstein radius at z_s = 2 and the mass in the image region. Agreement means that the truth
files are in wslap's frame and normalisation (wslap's profiles follow the same published
formulae as lenstronomy's but are an independent implementation).

    /tmp/refenv/bin/python tests/data/fidelity/check_with_wslap_maps.py --wslap /tmp/wslap-base
"""

import argparse
import json
import os
import subprocess
import sys

import numpy as np
from astropy import units as u
from astropy.cosmology import FlatLambdaCDM
from scipy.optimize import brentq

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "benches"))
from fidelity import FitsMap, in_hull  # noqa: E402
from scipy.spatial import ConvexHull  # noqa: E402


def nfw_mu(c):
    return np.log1p(c) - c / (1 + c)


def model_from_truth(t):
    cosmo = FlatLambdaCDM(H0=t["cosmology"]["H0"], Om0=t["cosmology"]["Om0"])
    z = t["z_lens"]
    d_l = t["d_l_mpc"]
    mpc_per_as = d_l * np.pi / 180 / 3600
    sigma_cr = t["sigma_cr_ref_msun_per_arcsec2"] / mpc_per_as**2  # Msun / Mpc^2
    rho_c = cosmo.critical_density(z).to(u.Msun / u.Mpc**3).value
    comps = []
    for h in t["halos"]:
        comps.append(dict(type="nfw", x=h["x"], y=h["y"], m200=h["m200"], c200=h["c"],
                          q=h["q"], pa=h["phi"]))
    for c in t["clumps"]:
        comps.append(dict(type="nfw", x=c["x"], y=c["y"], m200=c["m200"], c200=c["c"]))
    for name, kw, role in zip(t["lens_model_list"], t["kwargs_lens"], t["component_roles"]):
        if role == "external shear":
            assert name == "SHEAR"
            comps.append(dict(type="shear", gamma1=kw["gamma1"], gamma2=kw["gamma2"]))
            continue
        if role != "member":
            continue
        assert name == "TNFW"
        rs = kw["Rs"] * mpc_per_as
        kappa_s = kw["alpha_Rs"] / (4 * kw["Rs"] * (1 - np.log(2)))
        rho_s = kappa_s * sigma_cr / rs
        c = brentq(lambda c: 200 / 3 * rho_c * c**3 / nfw_mu(c) - rho_s, 1e-3, 1e3, xtol=1e-14,
                   rtol=1e-14)
        m200 = 4 * np.pi * rho_s * rs**3 * nfw_mu(c)
        comps.append(dict(type="tnfw", x=kw["center_x"], y=kw["center_y"], m200=m200, c200=c,
                          r_trunc=kw["r_trunc"]))
    return dict(cosmology=dict(h0=t["cosmology"]["H0"], omega_m=t["cosmology"]["Om0"]),
                z_lens=z, reference=t["reference"], components=comps)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--wslap", default="target/release/wslap")
    ap.add_argument("--clusters", default=HERE)
    ap.add_argument("--out", default="target/fidelity-check")
    args = ap.parse_args()
    worst = 0.0
    for name in sorted(os.listdir(args.clusters)):
        tp = os.path.join(args.clusters, name, "truth.json")
        if not os.path.exists(tp):
            continue
        t = json.load(open(tp))
        if "PJAFFE" in t["lens_model_list"]:
            # A wslap model file has no dPIE; tests/physics/dpie.rs checks wslap's dPIE against
            # lenstronomy's PJAFFE (tests/data/dpie_reference.py) instead.
            print(f"{name}: dPIE members (lenstronomy PJAFFE), not written as a model file: "
                  "skipped")
            continue
        out = os.path.join(args.out, name)
        os.makedirs(out, exist_ok=True)
        mp = os.path.join(out, "model.json")
        json.dump(model_from_truth(t), open(mp, "w"), indent=1)
        subprocess.run([args.wslap, "maps", "--model", mp, "--out", out, "--size", "200",
                        "--pixels", "1000"], check=True, stdout=subprocess.DEVNULL)
        s = json.load(open(os.path.join(out, "summary.json")))
        axm = FitsMap(os.path.join(out, "x-arcsec-deflect.fits"))
        aym = FitsMap(os.path.join(out, "y-arcsec-deflect.fits"))
        kap = FitsMap(os.path.join(out, "kappa.fits"))
        g = np.load(os.path.join(args.clusters, name, "truth_deflection_grid.npy")).astype(float)
        d = np.hypot(axm.sample(g[:, 0], g[:, 1]) - g[:, 2], aym.sample(g[:, 0], g[:, 1]) - g[:, 3])
        im = t["images"]
        xo = np.array([i["x_obs"] for i in im])
        yo = np.array([i["y_obs"] for i in im])
        ao = np.array([i["alpha_obs"] for i in im])
        di = np.hypot(axm.sample(xo, yo) - ao[:, 0], aym.sample(xo, yo) - ao[:, 1])
        hull = np.array(t["image_region"]["hull_xy"])
        px, py = kap.pixel_centres()
        m = kap.data[in_hull(ConvexHull(hull).equations, px, py)].sum() * kap.pixel**2 \
            * s["sigma_cr_ref_msun_per_arcsec2"]
        te = s["einstein_radius_arcsec"]
        rel_te = te / t["einstein_radius_z2_arcsec"] - 1
        rel_m = m / t["image_region"]["mass_msun"] - 1
        print(f"{name}: |d alpha| grid median {np.median(d):.4f} max {d.max():.4f} arcsec, "
              f"at images max {di.max():.4f}; theta_E {te:.3f} vs {t['einstein_radius_z2_arcsec']:.3f}"
              f" ({100 * rel_te:+.2f}%); M(region) {100 * rel_m:+.3f}%")
        worst = max(worst, np.median(d))
    print(f"worst median deflection difference {worst:.4f} arcsec")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The mass at large radius of the weak-lensing synthetic cluster (tests/data/weak_lensing),
with and without its arclets and with each regulariser: BENCHMARKS.md "Weak lensing".

    cargo build --release
    /tmp/refenv/bin/python benches/weak_lensing.py [--wslap target/release/wslap] [--seed N]

Each run is `wslap reconstruct --images images.cat [--shear arclets.cat] --z-lens 0.32` with
the settings of the row; the mass inside 60, 120 and 180 arcsec of the truth centre is summed
from its kappa.fits (D_ls/D_s = 1, times summary.json's Sigma_cr_ref) and divided by the truth
(truth.json, from lenstronomy). `--seed N` first makes another noise realisation of the
arclets with tests/data/weak_lensing/make_weak_lensing.py (same lens, same systems).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from astropy.io import fits

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "tests", "data", "weak_lensing")

# (label, arclets?, objective settings)
RUNS = [
    ("without arclets, density 0.01", False, {"regulariser": "density", "strength": 0.01}),
    ("without arclets, gradient 0.1", False, {"regulariser": "gradient", "strength": 0.1}),
    ("arclets, defaults (\"auto\")", True, {}),
    ("arclets, density 0.01", True, {"regulariser": "density", "strength": 0.01}),
    ("arclets, density 0.003", True, {"regulariser": "density", "strength": 0.003}),
    ("arclets, density 0.03", True, {"regulariser": "density", "strength": 0.03}),
    ("arclets, gradient 0.1", True, {"regulariser": "gradient", "strength": 0.1}),
    ("arclets, curvature 0.1", True, {"regulariser": "curvature", "strength": 0.1}),
]
MAP_WIDTH = 540.0  # arcsec: every run's maps reach 3 arcmin
MAP_PIXELS = 360


def masses(out, truth):
    kappa = fits.open(os.path.join(out, "kappa.fits"))[0].data.astype(float)
    summary = json.load(open(os.path.join(out, "summary.json")))
    maps = summary["maps"]
    n = kappa.shape[0]
    pix = maps["map_size_arcsec"] / n
    c = -maps["map_size_arcsec"] / 2 + (np.arange(n) + 0.5) * pix
    gx, gy = np.meshgrid(c, c)
    r = np.hypot(gx - truth["center_arcsec"][0], gy - truth["center_arcsec"][1])
    sigma = maps["sigma_cr_ref_msun_per_arcsec2"]
    got = [kappa[r <= radius].sum() * pix**2 * sigma for radius in truth["radii_arcsec"]]
    return got, summary


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--wslap", default=os.path.join(ROOT, "target", "release", "wslap"))
    ap.add_argument("--seed", type=int, help="another noise realisation of the arclets")
    args = ap.parse_args()
    work = tempfile.mkdtemp(prefix="wslap-wl-")
    data = DATA
    if args.seed is not None:
        data = os.path.join(work, f"seed{args.seed}")
        subprocess.run([sys.executable, os.path.join(DATA, "make_weak_lensing.py"),
                        "--seed", str(args.seed), "--out", data], check=True,
                       stdout=subprocess.DEVNULL)
    truth = json.load(open(os.path.join(DATA, "truth.json")))
    radii = truth["radii_arcsec"]
    print("| run | " + " | ".join(f"M(<{r:.0f}″) / truth" for r in radii)
          + " | Einstein radius z_s=2 | χ² per arclet | time |")
    print("|---|" + "---|" * (len(radii) + 3))
    for k, (label, shear, objective) in enumerate(RUNS):
        config = os.path.join(work, f"config{k}.json")
        with open(config, "w") as fh:
            json.dump({"objective": objective,
                       "products": {"size_arcsec": MAP_WIDTH, "pixels": MAP_PIXELS}}, fh)
        out = os.path.join(work, f"run{k}")
        cmd = [args.wslap, "reconstruct", "--images", os.path.join(data, "images.cat"),
               "--z-lens", str(truth["z_lens"]), "--config", config, "--out", out]
        if shear:
            cmd += ["--shear", os.path.join(data, "arclets.cat")]
        t0 = time.time()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        seconds = time.time() - t0
        got, summary = masses(out, truth)
        ratios = " | ".join(f"{g / m:.3f}" for g, m in zip(got, truth["mass_within_msun"]))
        wl = summary.get("weak_lensing")
        chi2 = f"{wl['chi2_per_arclet']:.2f}" if wl else "–"
        print(f"| {label} | {ratios} | {summary['einstein_radius_arcsec']:.1f}″ | {chi2} "
              f"| {seconds:.1f} s |")
    print(f"\ntruth (lenstronomy): " + ", ".join(
        f"M(<{r:.0f}″) = {m:.3e} Msun" for r, m in zip(radii, truth["mass_within_msun"])))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Is the ensemble's spread honest? `wslap reconstruct --ensemble N` (defaults otherwise) on the
synthetic clusters of tests/data/fidelity (lenstronomy truth), scored against the truth:

- the Einstein radius at z_s = 2: is the truth inside the ensemble's 16th - 84th percentile
  range (summary.json einstein_radius_interval_arcsec)? The main run's error against the
  range's half width;
- kappa in the image region (the convex hull of the images, truth.json): the actual error of the
  main run's map, rms over the pixels of (kappa.fits - truth kappa), against the ensemble's
  spread, the rms of kappa-std.fits over the same pixels: their ratio (issue #22 asks that
  kappa-std be not smaller than the actual error, i.e. a ratio at most about 1). Reported on the
  maps' own pixels and with both maps smoothed by a Gaussian of 3 arcsec (about a grid cell:
  the scale the grid can represent; the truth's member galaxies are sharper than any cell).
  The truth kappa (D_ls/D_s = 1) is lenstronomy's, from truth.json.

Usage: /tmp/refenv/bin/python benches/ensemble_calibration.py [--wslap PATH] [--members N]
           [--out DIR] [--jobs N] [--only NAME ...]
Writes OUT/calibration.md and OUT/calibration.json and prints the table.
"""

import argparse
import concurrent.futures as cf
import json
import os
import subprocess
import sys
import time

import numpy as np
from scipy import ndimage
from scipy.spatial import ConvexHull

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fidelity import FitsMap, in_hull  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLUSTERS = os.path.join(ROOT, "tests", "data", "fidelity")
SMOOTH_ARCSEC = 3.0


def truth_kappa(truth, xs, ys):
    from lenstronomy.LensModel.lens_model import LensModel
    lm = LensModel(truth["lens_model_list"])
    return lm.kappa(xs.ravel(), ys.ravel(), truth["kwargs_lens"]).reshape(xs.shape)


def run(wslap, name, members, out):
    cdir = os.path.join(CLUSTERS, name)
    truth = json.load(open(os.path.join(cdir, "truth.json")))
    cmd = [wslap, "reconstruct", "--images", os.path.join(cdir, "images.cat"),
           "--z-lens", repr(truth["z_lens"]), "--ensemble", str(members), "--out", out]
    if os.path.exists(os.path.join(cdir, "members.cat")):
        cmd += ["--members", os.path.join(cdir, "members.cat")]
    os.makedirs(out, exist_ok=True)
    t = time.time()
    with open(os.path.join(out, "log.txt"), "w") as log:
        if subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT) != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed, see {out}/log.txt")
    seconds = time.time() - t
    summary = json.load(open(os.path.join(out, "summary.json")))
    te_true = truth["einstein_radius_z2_arcsec"]
    te = summary["einstein_radius_arcsec"]
    lo, hi = summary["einstein_radius_interval_arcsec"]
    kap = FitsMap(os.path.join(out, "kappa.fits"))
    std = FitsMap(os.path.join(out, "kappa-std.fits"))
    px, py = kap.pixel_centres()
    inside = in_hull(ConvexHull(np.array(truth["image_region"]["hull_xy"])).equations, px, py)
    true = truth_kappa(truth, px, py)
    sigma_px = SMOOTH_ARCSEC / kap.pixel

    def ratio(model, spread, reference):
        err = np.sqrt(np.mean((model - reference)[inside] ** 2))
        s = np.sqrt(np.mean(spread[inside] ** 2))
        return float(err), float(s), float(err / s)

    raw = ratio(kap.data, std.data, true)
    smooth = ratio(ndimage.gaussian_filter(kap.data, sigma_px),
                   ndimage.gaussian_filter(std.data, sigma_px),
                   ndimage.gaussian_filter(true, sigma_px))
    return dict(name=name, members=members, theta_e_true=te_true, theta_e=te, interval=[lo, hi],
                inside=lo <= te_true <= hi, kappa_err=raw[0], kappa_std=raw[1], ratio=raw[2],
                kappa_err_smooth=smooth[0], kappa_std_smooth=smooth[1], ratio_smooth=smooth[2],
                seconds=seconds)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--wslap", default=os.path.join(ROOT, "target", "release", "wslap"))
    ap.add_argument("--members", type=int, default=20)
    ap.add_argument("--out", default="/tmp/wslap-calibration")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", nargs="*")
    args = ap.parse_args()
    names = sorted(n for n in os.listdir(CLUSTERS)
                   if os.path.isfile(os.path.join(CLUSTERS, n, "truth.json")))
    if args.only:
        names = [n for n in names if n in args.only]
    t0 = time.time()
    with cf.ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(lambda n: run(args.wslap, n, args.members,
                                              os.path.join(args.out, n)), names))
    lines = ["| cluster | θE true (\") | θE (\") | ensemble 16 - 84% (\") | truth inside | "
             "κ error rms | κ-std rms | ratio | ratio, 3\" smoothed | time (s) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r['name']} | {r['theta_e_true']:.2f} | {r['theta_e']:.2f} | "
                     f"{r['interval'][0]:.2f} - {r['interval'][1]:.2f} | "
                     f"{'✓' if r['inside'] else '✗'} | {r['kappa_err']:.3f} | {r['kappa_std']:.3f} | "
                     f"{r['ratio']:.1f} | {r['ratio_smooth']:.1f} | {r['seconds']:.0f} |")
    inside = sum(r["inside"] for r in results)
    lines.append(f"\nTruth inside the Einstein radius range: {inside} of {len(results)}. "
                 f"Wall time {time.time() - t0:.0f} s, --jobs {args.jobs}, {args.members} members.")
    text = "\n".join(lines)
    os.makedirs(args.out, exist_ok=True)
    open(os.path.join(args.out, "calibration.md"), "w").write(text + "\n")
    json.dump(results, open(os.path.join(args.out, "calibration.json"), "w"), indent=1)
    print(text)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""How strongly a catalogue's images hold a map's mass scale: the image-plane misfit of the
map rescaled along the mass-sheet direction, `alpha_L - theta = L (alpha - theta)`.

Rescaled so, a system at D_ls/D_s = f sees the original lens at `f' = f L / (1 - f (1 - L))`
(its source plane is only shrunk by `1 - f (1 - L)`, which moves no image), so the misfit at
L is the original map's misfit with every system at its f'. For each system the images are
back-projected with f', the source is their mean weighted by `M^T M` (`M` the inverse lens
Jacobian at each image, each axis capped at 10, from finite differences of the deflection
maps), and the misfit is the rms of `M (beta_i - beta)` over the images (to first order, how
far from each image the model puts it). L = 1 is the map as it is. With sources at one
redshift every L fits equally; only their spread in f tells the maps apart.

Usage: /tmp/refenv/bin/python benches/sheet_profile.py MAP_DIR SOURCES_DIR Z_LENS
  MAP_DIR: x/y-arcsec-deflect.fits (HFF style, D_ls/D_s = 1); SOURCES_DIR: a `wslap
  reconstruct --out` folder whose sources.json gives each system's images and redshift.
Cosmology: flat LCDM, H0 70, Omega_m 0.3 (wslap's default).
"""

import json
import os
import sys

import numpy as np
from astropy.cosmology import FlatLambdaCDM
from scipy.ndimage import map_coordinates

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deflection_vs_truth import load  # noqa: E402

SCALES = [0.5, 0.7, 0.85, 1.0, 1.2, 1.5, 2.0, 3.0]
MAX_STRETCH = 10.0


def main():
    model, sources_dir, z_lens = sys.argv[1], sys.argv[2], float(sys.argv[3])
    cosmology = FlatLambdaCDM(70, 0.3)
    ax, ay, xs, ys, pixel = load(model)
    dax_dy, dax_dx = np.gradient(ax, pixel)
    day_dy, day_dx = np.gradient(ay, pixel)

    def sample(m, p):
        return map_coordinates(m, [(p[:, 1] - ys[0]) / pixel, (p[:, 0] - xs[0]) / pixel], order=1)

    systems = []
    for s in json.load(open(os.path.join(sources_dir, "sources.json"))):
        pos = np.array([o["position_arcsec"] for o in s["observed"]])
        if len(pos) < 2:
            continue
        f = (cosmology.angular_diameter_distance_z1z2(z_lens, s["z"])
             / cosmology.angular_diameter_distance(s["z"])).value
        alpha = np.stack([sample(ax, pos), sample(ay, pos)], 1)
        jac = np.stack([np.stack([sample(dax_dx, pos), sample(dax_dy, pos)], 1),
                        np.stack([sample(day_dx, pos), sample(day_dy, pos)], 1)], 1)
        systems.append((f, pos, alpha, jac))

    def misfit(fs):
        total, n = 0.0, 0
        for (_, pos, alpha, jac), f in zip(systems, fs):
            beta = pos - f * alpha
            ms = []
            for k in range(len(pos)):
                u, sv, vt = np.linalg.svd(np.eye(2) - f * jac[k])
                ms.append(vt.T @ np.diag(1.0 / np.maximum(sv, 1.0 / MAX_STRETCH)) @ u.T)
            w = sum(m.T @ m for m in ms)
            b = np.linalg.solve(w, sum(m.T @ m @ beta[k] for k, m in enumerate(ms)))
            total += sum(np.sum((m @ (beta[k] - b)) ** 2) for k, m in enumerate(ms))
            n += len(pos)
        return np.sqrt(total / n)

    f0 = np.array([s[0] for s in systems])
    print(f"{len(systems)} systems, D_ls/D_s {f0.min():.3f} - {f0.max():.3f}")
    for scale in SCALES:
        fs = f0 * scale / (1 - f0 * (1 - scale))
        print(f"L {scale:4.2f}: image-plane misfit rms {misfit(fs):6.2f}\"")


if __name__ == "__main__":
    main()

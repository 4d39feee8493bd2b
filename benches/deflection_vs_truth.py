#!/usr/bin/env python3
"""Median deflection error of a reconstruction against a truth given as deflection maps.

Both folders hold HFF-style `x-arcsec-deflect.fits` and `y-arcsec-deflect.fits` on the same
sky reference (e.g. `wslap paper`'s `truth/` and a `wslap reconstruct --out` folder fitted to
that run's `images.cat`). The model's maps are sampled (bilinear) on the truth's pixels inside
a circle of radius R arcsec about the map centre; the mean difference (a constant deflection,
which only moves every source) is removed; the median and 90th percentile of the remaining
|difference| are printed, as `wslap paper` and benches/fidelity.py report theirs.

It also fits the model by a mass-sheet transform of the truth, `alpha_model - theta = lambda
(alpha_truth - theta) + c` (least squares over the same pixels): `lambda` = 1 is the truth's
own scale, `lambda` < 1 a map with `1 - lambda` of a uniform sheet (kappa at D_ls/D_s = 1) in
place of that share of the truth's structure. Image positions of sources at one redshift
cannot tell these maps apart (only the spread of the sources' redshifts can), so the error
left after the transform, printed too, is what the degeneracy does not explain.

Usage: /tmp/refenv/bin/python benches/deflection_vs_truth.py TRUTH_DIR MODEL_DIR [R]   (R: 71)
"""

import sys

import numpy as np
from astropy.io import fits
from scipy.ndimage import map_coordinates


def load(folder):
    hx = fits.open(f"{folder}/x-arcsec-deflect.fits")[0]
    hy = fits.open(f"{folder}/y-arcsec-deflect.fits")[0]
    h = hx.header
    pixel = abs(h["CDELT1"]) * 3600.0
    # Arcsec from the map centre along +x (West) and +y (North) of each column and row.
    xs = (np.arange(h["NAXIS1"]) + 1 - h["CRPIX1"]) * pixel
    ys = (np.arange(h["NAXIS2"]) + 1 - h["CRPIX2"]) * pixel
    return hx.data.astype(float), hy.data.astype(float), xs, ys, pixel


def main():
    truth, model = sys.argv[1], sys.argv[2]
    radius = float(sys.argv[3]) if len(sys.argv) > 3 else 71.0
    tx, ty, txs, tys, _ = load(truth)
    mx, my, mxs, mys, mp = load(model)
    x, y = np.meshgrid(txs, tys)
    fx, fy = (x - mxs[0]) / mp, (y - mys[0]) / mp
    ok = ((np.hypot(x, y) < radius) & (fx >= 0) & (fy >= 0)
          & (fx <= len(mxs) - 1) & (fy <= len(mys) - 1))
    dx = map_coordinates(mx, [fy[ok], fx[ok]], order=1) - tx[ok]
    dy = map_coordinates(my, [fy[ok], fx[ok]], order=1) - ty[ok]
    err = np.hypot(dx - dx.mean(), dy - dy.mean())
    print(f"deflection error median {np.median(err):.2f}\" p90 {np.percentile(err, 90):.2f}\" "
          f"over {ok.sum()} pixels (r < {radius:g}\", constant removed)")
    lam, left = mass_sheet_fit(x[ok], y[ok], tx[ok] + dx, ty[ok] + dy, tx[ok], ty[ok])
    print(f"best mass-sheet transform of the truth: lambda {lam:.3f}, error left median "
          f"{np.median(left):.2f}\" p90 {np.percentile(left, 90):.2f}\"")


def mass_sheet_fit(x, y, mx, my, tx, ty):
    """lambda and the |residual| per pixel of `m - theta = lambda (t - theta) + c`."""
    n = len(x)
    a = np.zeros((2 * n, 3))
    a[:n, 0], a[n:, 0] = tx - x, ty - y
    a[:n, 1], a[n:, 2] = 1.0, 1.0
    b = np.concatenate([mx - x, my - y])
    sol = np.linalg.lstsq(a, b, rcond=None)[0]
    r = b - a @ sol
    return sol[0], np.hypot(r[:n], r[n:])


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Real clusters the defaults never saw, against their published Lenstool models.

The HFF CATS models of Abell 2744, Abell 370 and MACS J1149, and Jauzac et al. (2016)'s of
MACS J1149 (image catalogue, member catalogue and the published `bestopt.par`, for the last
`best.par.20170201103232`) are in github.com/cerschae/Lenstool-HPC (GPL-3, commit
af57aacf74d3bf8841cea1a113f8d863f9d003c9), `Benchmarks/ConfigFiles/hff_slmodels/`. They are
not copied into this repository; clone that one and point this script at the folder.
Mahler et al. (2023)'s first JWST model of SMACS J0723 (CC0) is read from this repository's
tests/data/lenstool/smacs0723 (`--only SMACS0723` needs no clone, but `--models` all the same):

    git clone https://github.com/cerschae/Lenstool-HPC /tmp/lenstool-hpc
    cargo build --release
    /tmp/refenv/bin/python benches/published.py \
        --models /tmp/lenstool-hpc/Benchmarks/ConfigFiles/hff_slmodels --out /tmp/published

For each cluster it runs, with target/release/wslap:
  - `wslap reconstruct --images I --members M --z-lens Z --folds 5 --out OUT/NAME/ours`, the
    defaults (the published model's galaxies that the member catalogue leaves out, e.g. the
    BCGs, are then missing: the run warns);
  - the same with `--par` the published model (those galaxies fitted as members; its
    `z_m_limit` lines, the model's fitted redshifts, set those systems' redshifts),
    OUT/NAME/with-par;
  - where the modeller's starting `.par` is there too, the same with `--par` it: its
    `z_m_limit` lines are the priors the model's redshifts were fitted under, and the
    systems without a catalogue redshift are estimated within them, OUT/NAME/with-priors;
  - `wslap maps --lenstool` the published model `--z-source 2 --out OUT/NAME/published`
    (A370's group at z = 1.05 in the single-plane approximation);
and compares: the Einstein radius at z_s = 2 (summary.json, the same definition for both:
every tangential loop that reaches the lens, member galaxies' too) and the main curve's alone
(`sqrt(area / pi)` of the largest tangential curve in critical-curves.json),
the held-out images' median offset (crossval.json), the fitted images' median, the tangential
curves, and the deflection difference from the published model (D_ls/D_s = 1, both maps
sampled at the same sky positions through their WCS, the mean difference removed): at the
observed images and on a 1" lattice within 40" of their centre. The published model is a
model, not the truth: what the images do not constrain, two models may draw differently.

Writes OUT/published.md and OUT/published.json and prints the table.
"""

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from astropy.io import fits
from astropy.wcs import WCS
from scipy.ndimage import map_coordinates

ROOT = Path(__file__).resolve().parent.parent
WSLAP = ROOT / "target" / "release" / "wslap"

# name, folder under --models, images, members, z_lens, extra `wslap maps` arguments, the
# published model, the modeller's starting .par whose `z_m_limit` lines set the redshift priors
# (None: no such file)
CLUSTERS = [
    ("A2744", "A2744", "img_mul_constraints.cat", "new_potfile_with_ASTRODEEP_data.txt", 0.308, [],
     "bestopt.par", None),
    ("A370", "A370", "mul_a370_specMosaic.cat", "galsortcutI_mosaicBright_noBCGsV2.5.cat", 0.375,
     ["--single-plane"], "bestopt.par", None),
    ("M1149", "M1149/m1149_catsv4", "imawcs_spiral_secured.mul", "m1149_newgal_cc-muse_arsec.cat",
     0.542, [], "bestopt.par", "m1149.par"),
    # Jauzac et al. 2016's model of the same cluster: its own catalogues, 43 of 145 images
    # without a redshift (the model fits theirs).
    ("M1149-J16", "M1149/m1149_jauzac16", "imawcs_spiral_secured.mul", "galaxies_v2.cat", 0.544,
     [], "best.par.20170201103232", "mod.par"),
    # Mahler et al. (2023)'s first JWST model of SMACS J0723 (CC0), kept in this repository:
    # 21 systems, 16 of them without a spectroscopic redshift. Any --models reaches it.
    ("SMACS0723", ROOT / "tests" / "data" / "lenstool" / "smacs0723", "arcs.dat", "galcat.cat",
     0.39, [], "best.par", None),
]
RADIUS_ARCSEC = 40.0


def run(wslap, args, log):
    t = time.time()
    with open(log, "w") as out:
        subprocess.run([str(wslap), *map(str, args)], check=True, stdout=out, stderr=out)
    return time.time() - t


def load(folder):
    hx = fits.open(folder / "x-arcsec-deflect.fits")[0]
    hy = fits.open(folder / "y-arcsec-deflect.fits")[0]
    return hx.data.astype(float), hy.data.astype(float), WCS(hx.header), hx.header


def sample(maps, ra, dec):
    x, y = maps[2].all_world2pix(ra, dec, 0)
    return np.array([map_coordinates(maps[i], [y, x], order=1, mode="constant", cval=np.nan)
                     for i in (0, 1)]).T


def deflection_difference(published, ours):
    """Median and 90th percentile (arcsec) of |alpha_ours - alpha_published - mean| at the observed
    images, within RADIUS_ARCSEC of their centre, and at the images of the systems whose redshift
    the run estimated (the mean taken over all the observed images for the first and the last)."""
    p, o = load(published), load(ours)
    ra0, dec0 = o[3]["CRVAL1"], o[3]["CRVAL2"]
    sources = json.loads((ours / "sources.json").read_text())
    images = np.array([im["position_arcsec"] for s in sources for im in s["observed"]])
    estimated = np.array([im["position_arcsec"] for s in sources if s.get("z_estimate")
                          for im in s["observed"]]).reshape(-1, 2)

    def difference(xy):
        # The frame's +x is West: RA falls with x.
        ra = ra0 - xy[:, 0] / 3600.0 / np.cos(np.radians(dec0))
        dec = dec0 + xy[:, 1] / 3600.0
        d = sample(o, ra, dec) - sample(p, ra, dec)
        return d[np.all(np.isfinite(d), axis=1)]

    def stats(d, mean):
        if len(d) == 0:
            return None
        e = np.hypot(*(d - mean).T)
        return float(np.median(e)), float(np.percentile(e, 90))

    g = np.arange(-RADIUS_ARCSEC, RADIUS_ARCSEC + 0.5, 1.0)
    gx, gy = np.meshgrid(g, g)
    inside = np.hypot(gx, gy) <= RADIUS_ARCSEC
    lattice = difference(np.c_[gx[inside], gy[inside]] + images.mean(axis=0))
    at_images = difference(images)
    mean = at_images.mean(axis=0)
    return dict(at_images=stats(at_images, mean), region=stats(lattice, lattice.mean(axis=0)),
                at_estimated=stats(difference(estimated), mean))


def main_curve_radius(folder):
    """sqrt(A / pi) of the largest tangential critical curve of `folder`'s critical-curves.json
    (a curve cut by the map's border closed by its chord), arcsec; None without one. The
    Einstein radius of summary.json counts every tangential loop that reaches the lens (member
    galaxies' and a neighbouring group's too); this is the main curve's alone, the figure
    published models are usually quoted by."""
    curves = json.loads((folder / "critical-curves.json").read_text())["tangential"]
    if not curves:
        return None
    def area(points):
        x, y = np.asarray(points, dtype=float).T
        return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    return float(np.sqrt(max(area(c) for c in curves) / np.pi))


def scores(folder, published):
    s = json.loads((folder / "summary.json").read_text())
    cv = json.loads((folder / "crossval.json").read_text())
    curves = json.loads((folder / "critical-curves.json").read_text())
    v = s["verdict"]
    return dict(
        theta_e=s["einstein_radius_arcsec"],
        theta_e_main=main_curve_radius(folder),
        held_out=cv["holdout_image_offset_median_arcsec"],
        held_out_rms=cv["holdout_image_plane_rms_arcsec"],
        fitted=s["image_offset_median_arcsec"],
        z_estimates={src["id"]: src["z_estimate"] for src in
                     json.loads((folder / "sources.json").read_text()) if src.get("z_estimate")},
        c=s["c_per_layer"],
        tangential=len(curves["tangential"]),
        main_share=v.get("main_curve_share"),
        verdict=v["words"],
        deflection=deflection_difference(published, folder),
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", required=True, type=Path, help="hff_slmodels folder")
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--only", help="one cluster name")
    ap.add_argument("--wslap", type=Path, default=WSLAP, help="the binary (default: %(default)s)")
    a = ap.parse_args()
    rows = []
    for name, sub, images, members, z, maps_args, model, start in CLUSTERS:
        if a.only and a.only != name:
            continue
        src, out = a.models / sub, a.out / name
        out.mkdir(parents=True, exist_ok=True)
        par = src / model
        run(a.wslap, ["maps", "--lenstool", par, *maps_args, "--z-source", 2, "--out", out / "published"],
            out / "published.log")
        pub = json.loads((out / "published" / "summary.json").read_text())
        row = dict(name=name, model=model, start=start, z_lens=z,
                   theta_e_published=pub["einstein_radius_arcsec"],
                   theta_e_main_published=main_curve_radius(out / "published"),
                   published_tangential=pub["tangential_curves"])
        kinds = [("ours", []), ("with-par", ["--par", par])]
        if start:
            kinds.append(("with-priors", ["--par", src / start]))
        for kind, extra in kinds:
            secs = run(a.wslap, ["reconstruct", "--images", src / images, "--members", src / members,
                        "--z-lens", z, "--folds", 5, *extra, "--out", out / kind],
                       out / f"{kind}.log")
            row[kind] = scores(out / kind, out / "published")
            row[kind]["seconds"] = secs
            print(f"{name} {kind}: {json.dumps(row[kind])}", file=sys.stderr)
        rows.append(row)
    (a.out / "published.json").write_text(json.dumps(rows, indent=1))
    lines = [
        "| cluster | run | θE(z=2) ours / published (\") | ΔθE | main curve's ours / published (\") "
        "| held-out median / rms (\") "
        "| fitted median (\") | Δα at images / within 40\" / at estimated-z images (median, \") "
        "| tangential curves ours / published | main share | C | s |",
        "|---|---|---|---:|---|---|---:|---|---|---:|---:|---:|",
    ]
    for r in rows:
        for kind in ("ours", "with-par", "with-priors"):
            if kind not in r:
                continue
            k = r[kind]
            run_name = {"ours": "defaults", "with-par": f"--par {r['model']}",
                        "with-priors": f"--par {r['start']} (its z priors)"}[kind]
            lines.append(
                f"| {r['name']} | {run_name} "
                f"| {k['theta_e']:.2f} / {r['theta_e_published']:.2f} "
                f"| {100 * (k['theta_e'] / r['theta_e_published'] - 1):+.1f}% "
                f"| {k['theta_e_main'] or 0:.2f} / {r['theta_e_main_published'] or 0:.2f} "
                f"| {k['held_out']:.2f} / {k['held_out_rms']:.2f} | {k['fitted']:.2f} "
                f"| {k['deflection']['at_images'][0]:.2f} / {k['deflection']['region'][0]:.2f} / "
                f"{'—' if (est := k['deflection']['at_estimated']) is None else f'{est[0]:.2f}'} "
                f"| {k['tangential']} / {r['published_tangential']} "
                f"| {k['main_share']:.2f} | {', '.join(f'{c:.2f}' for c in k['c'])} "
                f"| {k['seconds']:.0f} |")
    table = "\n".join(lines) + "\n"
    (a.out / "published.md").write_text(table)
    print(table)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Fidelity benchmark: `wslap reconstruct` (default settings) on lenstronomy-made clusters,
scored against their truth (tests/data/fidelity/, see its README.md).

For each cluster directory (images.cat, optional members.cat, truth.json,
truth_deflection_grid.npy) two reconstructions are run:
  full:    wslap reconstruct --images images.cat [--members members.cat] --z-lens Z --out OUT/NAME/full
  holdout: the same with --holdout (every fourth system in catalogue order: the 4th, 8th, ...)
and scored:
  - theta_E: Einstein radius at z_s = 2 (summary.json) against the truth's, relative error;
  - M(region): projected mass inside the image region (the convex hull of all observed images,
    truth.json image_region.hull_xy): sum over the pixels of kappa.fits (D_ls/D_s = 1) whose
    centres fall inside the hull, times the pixel area and Sigma_cr at D_ls/D_s = 1
    (summary.json maps.sigma_cr_ref_msun_per_arcsec2), against the truth's; relative error.
    Also from the deflection maps by the divergence theorem (JSON only, a consistency check);
  - deflection error: x/y-arcsec-deflect.fits (D_ls/D_s = 1, arcsec) bilinearly interpolated at
    the truth grid points (2 arcsec lattice inside the image region), minus the truth; the
    component-wise median difference vector (a constant deflection only shifts every source
    plane) is removed and the median of the remaining norms reported; also (JSON, and the
    column "λ (sheet)") the map fitted by a mass-sheet transform of the truth,
    alpha - theta = lambda (alpha_true - theta) + c (benches/deflection_vs_truth.py), with the
    error left after it: lambda near 1 means the map keeps the truth's mass scale;
  - fitted: median offset between observed and nearest predicted image over the fitted systems
    (sources.json, full run); held-out: the same over the held-out systems of the holdout run.
    Images with no predicted counterpart (offset null) are left out of the medians and counted;
  - C per layer (summary.json) beside the truth's mass ratio sum(M_true)/sum(M_catalogue), and
    the number of tangential critical curves at z_s = 2.

Writes OUT/fidelity.md (the table) and OUT/fidelity.json (every number), and prints the table.
Runs with the Python of /tmp/refenv (numpy, scipy, astropy; lenstronomy only if an image region
leaves a reconstruction's map).

Usage: python benches/fidelity.py [--wslap PATH] [--clusters DIR] [--out DIR] [--jobs N]
                                  [--extra-args "..."] [--only NAME ...]
"""

import argparse
import concurrent.futures as cf
import json
import os
import shlex
import subprocess
import sys
import time

import numpy as np
from astropy.io import fits
from scipy import ndimage
from scipy.spatial import ConvexHull

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deflection_vs_truth import mass_sheet_fit  # noqa: E402

TARGETS = dict(theta_e_pct=5.0, deflection_arcsec=1.0, fitted_arcsec=0.5, held_out_arcsec=1.0)


# ----------------------------------------------------------------------------------------------
# Reading wslap's outputs


class FitsMap:
    """A wslap FITS map and its geometry in the arcsec frame of the catalogues.

    wslap writes (src/fits/mod.rs): CDELT1 = -pixel/3600 (pixel i grows to +x, West),
    CDELT2 = +pixel/3600, CRPIX = n/2 + 0.5 (the map centre), CRVAL the sky position of the map
    centre, REFRA/REFDEC the frame origin (or NOSKYREF = T). Pixel (i, j) has its centre at
    centre + ((i + 0.5 - n/2) p, (j + 0.5 - n/2) p) (src/grid.rs). The frame is Lenstool's
    x = -(RA - RA0) cos(Dec0) 3600, y = (Dec - Dec0) 3600 (src/sky.rs).
    """

    def __init__(self, path):
        with fits.open(path) as hdul:
            h = hdul[0].header
            self.data = np.asarray(hdul[0].data, dtype=np.float64)  # [j (y), i (x)]
        self.n = int(h["NAXIS1"])
        assert int(h["NAXIS2"]) == self.n, path
        assert h["CDELT1"] < 0 < h["CDELT2"], path
        self.pixel = abs(h["CDELT1"]) * 3600.0
        assert abs(h["CDELT2"] * 3600.0 / self.pixel - 1) < 1e-9, path
        if h.get("NOSKYREF", False):
            ra0, dec0 = 0.0, 0.0
        else:
            ra0, dec0 = h["REFRA"], h["REFDEC"]
        d_ra = (h["CRVAL1"] - ra0 + 180.0) % 360.0 - 180.0
        cx = -d_ra * np.cos(np.deg2rad(dec0)) * 3600.0
        cy = (h["CRVAL2"] - dec0) * 3600.0
        # CRPIX is n/2 + 0.5 as written; allow others.
        off_i = (self.n / 2 + 0.5) - h["CRPIX1"]
        off_j = (self.n / 2 + 0.5) - h["CRPIX2"]
        self.center = np.array([cx + off_i * self.pixel, cy + off_j * self.pixel])
        self.bunit = h.get("BUNIT", "")

    def axis(self):
        """Pixel-centre coordinates along one axis (x for i, y for j, after adding the centre)."""
        return (np.arange(self.n) + 0.5 - self.n / 2) * self.pixel

    def pixel_centres(self):
        a = self.axis()
        return np.meshgrid(self.center[0] + a, self.center[1] + a)  # [j, i]

    def covers(self, x, y):
        half = self.n / 2 * self.pixel
        return (np.abs(x - self.center[0]) <= half - 0.5 * self.pixel) & (
            np.abs(y - self.center[1]) <= half - 0.5 * self.pixel)

    def sample(self, x, y):
        """Bilinear interpolation at arcsec positions (NaN outside the pixel centres' span)."""
        fi = (np.asarray(x) - self.center[0]) / self.pixel + self.n / 2 - 0.5
        fj = (np.asarray(y) - self.center[1]) / self.pixel + self.n / 2 - 0.5
        v = ndimage.map_coordinates(self.data, [fj, fi], order=1, mode="nearest")
        return np.where(self.covers(x, y), v, np.nan)


def in_hull(eq, x, y, tol=1e-9):
    return np.all(eq[:, 0:1] * x.ravel()[None] + eq[:, 1:2] * y.ravel()[None] + eq[:, 2:3] <= tol,
                  axis=0).reshape(np.shape(x))


def hull_flux_mass(ax_map, ay_map, hull_xy, sigma_cr, per_edge=400):
    """M = Sigma_cr / 2 * closed integral of alpha . n dl over the hull (div alpha = 2 kappa)."""
    hv = np.vstack([hull_xy, hull_xy[:1]])
    total = 0.0
    for (xa, ya), (xb, yb) in zip(hv[:-1], hv[1:]):
        t = (np.arange(per_edge) + 0.5) / per_edge
        px, py = xa + t * (xb - xa), ya + t * (yb - ya)
        ln = np.hypot(xb - xa, yb - ya)
        nx, ny = (yb - ya) / ln, -(xb - xa) / ln  # outward for counter-clockwise vertices
        total += np.sum(ax_map.sample(px, py) * nx + ay_map.sample(px, py) * ny) * ln / per_edge
    return 0.5 * sigma_cr * total


def median_or_none(v):
    return float(np.median(v)) if len(v) else None


def image_offsets(sources, held_out):
    offs, unmatched = [], 0
    for s in sources:
        if bool(s.get("held_out")) != held_out:
            continue
        for im in s.get("observed", []):
            o = im.get("offset_arcsec")
            if o is None:
                unmatched += 1
            else:
                offs.append(o)
    return offs, unmatched


def truth_mass_on_pixels(truth, xs, ys, pixel):
    """Truth mass on given pixel centres, recomputed with lenstronomy from truth.json."""
    from lenstronomy.LensModel.lens_model import LensModel
    lm = LensModel(truth["lens_model_list"])
    k = np.concatenate([lm.kappa(xs[s:s + 100000], ys[s:s + 100000], truth["kwargs_lens"])
                        for s in range(0, xs.size, 100000)])
    return float(k.sum() * pixel**2 * truth["sigma_cr_ref_msun_per_arcsec2"])


# ----------------------------------------------------------------------------------------------


def system_ids(images_cat):
    ids = []
    with open(images_cat) as fh:
        for line in fh:
            t = line.strip()
            if not t or t.startswith("#"):
                continue
            sid = t.split()[0].split(".")[0]
            if sid not in ids:
                ids.append(sid)
    return ids


def run_wslap(wslap, cdir, truth, out, extra, holdout=None):
    cmd = [wslap, "reconstruct", "--images", os.path.join(cdir, "images.cat")]
    if os.path.exists(os.path.join(cdir, "members.cat")):
        cmd += ["--members", os.path.join(cdir, "members.cat")]
    cmd += ["--z-lens", repr(truth["z_lens"]), "--out", out]
    if holdout:
        cmd += ["--holdout", ",".join(holdout)]
    cmd += extra
    os.makedirs(out, exist_ok=True)
    t0 = time.time()
    with open(os.path.join(out, "wslap.log"), "w") as log:
        log.write(" ".join(shlex.quote(c) for c in cmd) + "\n")
        log.flush()
        rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
    return dict(cmd=cmd, rc=rc, seconds=time.time() - t0)


def score(cdir, truth, full_dir, hold_dir):
    r = {}
    summ = json.load(open(os.path.join(full_dir, "summary.json")))
    maps = summ["maps"]
    sigma_cr = maps["sigma_cr_ref_msun_per_arcsec2"]
    r["sigma_cr_ratio_wslap_over_truth"] = sigma_cr / truth["sigma_cr_ref_msun_per_arcsec2"]

    # Einstein radius at z_s = 2.
    te_true = truth["einstein_radius_z2_arcsec"]
    te = summ.get("einstein_radius_arcsec", maps.get("einstein_radius_arcsec"))
    r.update(theta_e_true=te_true, theta_e=te, theta_e_rel_err=te / te_true - 1,
             einstein_radius_map_arcsec=maps.get("einstein_radius_map_arcsec"),
             einstein_z_source=summ.get("einstein_radius_z_source"))

    # Mass in the image region.
    kap = FitsMap(os.path.join(full_dir, "kappa.fits"))
    axm = FitsMap(os.path.join(full_dir, "x-arcsec-deflect.fits"))
    aym = FitsMap(os.path.join(full_dir, "y-arcsec-deflect.fits"))
    region = truth["image_region"]
    hull_xy = np.array(region["hull_xy"])
    eq = ConvexHull(hull_xy).equations
    px, py = kap.pixel_centres()
    inside = in_hull(eq, px, py)
    m_rec = float(kap.data[inside].sum() * kap.pixel**2 * sigma_cr)
    covered = bool(np.all(kap.covers(hull_xy[:, 0], hull_xy[:, 1])))
    m_true = region["mass_msun"]
    if not covered:
        # The region leaves the map: compare on the covered pixels only.
        m_true = truth_mass_on_pixels(truth, px[inside], py[inside], kap.pixel)
    r.update(region_covered_by_map=covered, mass_region_true=m_true, mass_region=m_rec,
             mass_region_rel_err=m_rec / m_true - 1,
             mass_region_divergence=hull_flux_mass(axm, aym, hull_xy, sigma_cr) if covered
             else None,
             map_center_arcsec=kap.center.tolist(), map_pixel_arcsec=kap.pixel,
             map_pixels=kap.n)

    # Deflection error on the truth grid.
    g = np.load(os.path.join(cdir, truth["deflection_grid"]["file"])).astype(np.float64)
    ax = axm.sample(g[:, 0], g[:, 1])
    ay = aym.sample(g[:, 0], g[:, 1])
    ok = np.isfinite(ax) & np.isfinite(ay)
    dx, dy = ax[ok] - g[ok, 2], ay[ok] - g[ok, 3]
    shift = np.array([np.median(dx), np.median(dy)])
    err = np.hypot(dx - shift[0], dy - shift[1])
    lam, left = mass_sheet_fit(g[ok, 0], g[ok, 1], ax[ok], ay[ok], g[ok, 2], g[ok, 3])
    r.update(deflection_sheet_lambda=float(lam),
             deflection_err_after_sheet_median=float(np.median(left)))
    r.update(deflection_points=int(ok.sum()), deflection_points_outside_map=int((~ok).sum()),
             deflection_err_median=float(np.median(err)),
             deflection_err_p90=float(np.percentile(err, 90)),
             deflection_err_median_raw=float(np.median(np.hypot(dx, dy))),
             deflection_shift=shift.tolist(),
             deflection_true_median_norm=float(np.median(np.hypot(g[ok, 2], g[ok, 3]))))

    # Image offsets.
    src = json.load(open(os.path.join(full_dir, "sources.json")))
    offs, unmatched = image_offsets(src, held_out=False)
    r.update(fitted_median=median_or_none(offs), fitted_images=len(offs),
             fitted_unmatched=unmatched,
             fitted_median_summary=summ.get("image_offset_median_arcsec"),
             fitted_rms_summary=summ.get("image_plane_rms_arcsec"))
    if hold_dir and os.path.exists(os.path.join(hold_dir, "sources.json")):
        hsrc = json.load(open(os.path.join(hold_dir, "sources.json")))
        hsum = json.load(open(os.path.join(hold_dir, "summary.json")))
        hoffs, hun = image_offsets(hsrc, held_out=True)
        foffs, _ = image_offsets(hsrc, held_out=False)
        r.update(held_out_median=median_or_none(hoffs), held_out_images=len(hoffs),
                 held_out_unmatched=hun, holdout_run_fitted_median=median_or_none(foffs),
                 held_out_median_summary=hsum.get("holdout_image_offset_median_arcsec"),
                 holdout_run_theta_e=hsum.get("einstein_radius_arcsec"))

    # Layers, curves.
    r.update(layers=summ.get("layers"), c_per_layer=summ.get("c_per_layer"),
             c_unmeasured=summ.get("c_unmeasured"),
             c_true_mass_ratio=truth["members"]["c_true_mass_ratio"],
             tangential_curves=maps.get("tangential_curves"),
             tangential_curves_true=truth.get("tangential_curves_z2"),
             grid_mass_msun=summ.get("grid_mass_msun"),
             systems_fitted=len(summ.get("systems_fitted", [])),
             systems_excluded=summ.get("systems_excluded"),
             warnings=summ.get("warnings"))
    return r


def process(name, args, extra):
    cdir = os.path.join(args.clusters, name)
    truth = json.load(open(os.path.join(cdir, "truth.json")))
    out = os.path.join(args.out, name)
    ids = system_ids(os.path.join(cdir, "images.cat"))
    holdout = ids[3::4]
    runs = dict(full=run_wslap(args.wslap, cdir, truth, os.path.join(out, "full"), extra))
    runs["holdout"] = run_wslap(args.wslap, cdir, truth, os.path.join(out, "holdout"), extra,
                                holdout=holdout)
    res = dict(name=name, description=truth.get("description"), z_lens=truth["z_lens"],
               systems=len(ids), images=len(truth["images"]), held_out_ids=holdout,
               members=truth["members"]["count"], runs=runs)
    if runs["full"]["rc"] != 0:
        res["error"] = f"wslap failed (rc {runs['full']['rc']}), see {out}/full/wslap.log"
        return res
    hold_dir = os.path.join(out, "holdout") if runs["holdout"]["rc"] == 0 else None
    try:
        res.update(score(cdir, truth, os.path.join(out, "full"), hold_dir))
    except Exception as e:  # keep the other clusters going; the error is reported
        res["error"] = f"scoring failed: {type(e).__name__}: {e}"
    return res


# ----------------------------------------------------------------------------------------------
# Table


def fmt(v, f, pct=False):
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return "—"
    return format(100 * v if pct else v, f)


def mark(ok):
    return "" if ok is None or ok else " ✗"


COLUMNS = [
    # header, getter, format, target check
    ("θE true (\")", lambda r: r.get("theta_e_true"), ".2f", None),
    ("θE (\")", lambda r: r.get("theta_e"), ".2f", None),
    ("ΔθE %", lambda r: _pct(r.get("theta_e_rel_err")), "+.1f",
     lambda v: abs(v) <= TARGETS["theta_e_pct"]),
    ("ΔM(region) %", lambda r: _pct(r.get("mass_region_rel_err")), "+.1f", None),
    ("defl. err (\")", lambda r: r.get("deflection_err_median"), ".2f",
     lambda v: v < TARGETS["deflection_arcsec"]),
    ("λ (sheet)", lambda r: r.get("deflection_sheet_lambda"), ".3f", None),
    ("fitted (\")", lambda r: r.get("fitted_median"), ".2f",
     lambda v: v < TARGETS["fitted_arcsec"]),
    ("held-out (\")", lambda r: r.get("held_out_median"), ".2f",
     lambda v: v < TARGETS["held_out_arcsec"]),
    ("C", lambda r: _first(r.get("c_per_layer")), ".2f", None),
    ("C true", lambda r: r.get("c_true_mass_ratio"), ".2f", None),
    ("tang. curves", lambda r: r.get("tangential_curves"), "d", None),
    ("tang. true", lambda r: r.get("tangential_curves_true"), "d", None),
    ("time (s)", lambda r: r.get("runs", {}).get("full", {}).get("seconds"), ".0f", None),
]


def _pct(v):
    return None if v is None else 100 * v


def _first(v):
    if not v:
        return None
    return v[0] if len(v) == 1 else None


def table(results):
    head = ["cluster"] + [c[0] for c in COLUMNS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    tgt = {"ΔθE %": f"±{TARGETS['theta_e_pct']:g}", "defl. err (\")":
           f"< {TARGETS['deflection_arcsec']:g}", "fitted (\")": f"< {TARGETS['fitted_arcsec']:g}",
           "held-out (\")": f"< {TARGETS['held_out_arcsec']:g}"}
    lines.append("| *target* | " + " | ".join(tgt.get(c[0], "") for c in COLUMNS) + " |")
    cols = {c[0]: [] for c in COLUMNS}
    for r in results:
        cells = [r["name"]]
        if "error" in r and "theta_e" not in r:
            cells += ["—"] * len(COLUMNS)
            cells[1] = "error: " + r["error"]
        else:
            for h, get, f, check in COLUMNS:
                v = get(r)
                if h == "C" and r.get("c_per_layer") and len(r["c_per_layer"]) > 1:
                    cells.append("/".join(format(c, ".2f") for c in r["c_per_layer"]))
                    continue
                if v is not None:
                    cols[h].append(abs(v) if h in ("ΔθE %", "ΔM(region) %") else v)
                cells.append(fmt(v, f) + (mark(check(v)) if (check and v is not None) else ""))
        lines.append("| " + " | ".join(cells) + " |")
    med = ["median (|Δ| for %)"]
    for h, _, f, check in COLUMNS:
        v = cols[h]
        if not v or h in ("C true", "tang. true"):
            med.append("")
            continue
        m = float(np.median(v))
        med.append(fmt(m if f != "d" else int(round(m)), f.lstrip("+")))
    lines.append("| " + " | ".join(med) + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--wslap", default="target/release/wslap")
    ap.add_argument("--clusters", default="tests/data/fidelity")
    ap.add_argument("--out", default="target/fidelity")
    ap.add_argument("--extra-args", default="", help="passed through to wslap reconstruct")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--only", action="append", help="cluster name (repeatable)")
    args = ap.parse_args()
    extra = shlex.split(args.extra_args)
    names = sorted(d for d in os.listdir(args.clusters)
                   if os.path.exists(os.path.join(args.clusters, d, "truth.json")))
    if args.only:
        missing = set(args.only) - set(names)
        if missing:
            sys.exit(f"no such cluster(s) in {args.clusters}: {', '.join(sorted(missing))}")
        names = [n for n in names if n in args.only]
    if not names:
        sys.exit(f"no clusters (directories with truth.json) in {args.clusters}")
    os.makedirs(args.out, exist_ok=True)
    t0 = time.time()
    with cf.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as ex:
        results = list(ex.map(lambda n: process(n, args, extra), names))
    md = table(results)
    wall = time.time() - t0
    header = (f"# wslap fidelity benchmark\n\nwslap: `{args.wslap}`"
              f"{'  extra args: `' + args.extra_args + '`' if args.extra_args else ''}; "
              f"clusters: `{args.clusters}`; wall {wall:.0f} s.\n\n"
              "ΔθE: Einstein radius at z_s = 2; ΔM(region): mass inside the convex hull of the "
              "images; defl. err: median |Δα| (D_ls/D_s = 1) on a 2\" grid in that hull after "
              "removing the median Δα; fitted / held-out: median image offset (held-out: every "
              "4th system left out); C: member-layer factor (C true: ΣM_true/ΣM_catalogue); "
              "✗: misses the target.\n\n")
    with open(os.path.join(args.out, "fidelity.md"), "w") as fh:
        fh.write(header + md + "\n")
    with open(os.path.join(args.out, "fidelity.json"), "w") as fh:
        json.dump(dict(wslap=args.wslap, extra_args=args.extra_args, targets=TARGETS,
                       wall_seconds=wall, clusters=results), fh, indent=1)
    print(md)
    for r in results:
        if "error" in r:
            print(f"{r['name']}: {r['error']}", file=sys.stderr)
    print(f"\nwrote {args.out}/fidelity.md and {args.out}/fidelity.json ({wall:.0f} s)")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Redshifts for systems without one: blank known redshifts, let `wslap reconstruct` estimate
them (its defaults otherwise), and compare the estimates with the redshifts blanked.

- The synthetic clusters of tests/data/fidelity (lenstronomy truth): every third system in
  catalogue order (the 3rd, 6th, ...) is named with --free-z, one run per cluster; with
  `--pick outer`, the third of the systems farthest from the centre instead (the median
  distance of a system's images from the frame's origin), whose images lie where the lens
  of the other systems is least constrained, as in real catalogues, where the redshifts
  measured are mostly of the bright inner arcs.
- AS1063 gold (../shared/data, with its member catalogue): each system in turn, one run per
  system (z_lens 0.348).

Scores over the systems blanked: the median |z_estimate - z| / (1 + z) (target below 0.1), the
share of systems whose true z lies inside z_interval (target at least 60%), and per run the
fitted median image offset of the systems that kept their redshift, without and with the
estimated systems (summary.json free_redshifts: adding them must not spoil those).

Writes OUT/free_z.md and OUT/free_z.json and prints the table.

Usage: python3 benches/free_z.py [--wslap PATH] [--out DIR] [--jobs N] [--only synthetic|as1063]
                                 [--pick every-third|outer] [--extra-args "..."]
"""

import argparse
import concurrent.futures as cf
import json
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIDELITY = os.path.join(ROOT, "tests", "data", "fidelity")
AS1063 = os.path.join(ROOT, "..", "shared", "data", "AS1063", "lenstool_cats")


def catalogue_systems(path):
    """System ids in catalogue order, their redshift (the first image's z column) and the
    median distance of their images from the frame's origin (arcsec, for a catalogue in
    arcsec about a reference)."""
    order, z, r = [], {}, {}
    for line in open(path):
        parts = line.split()
        if not parts or parts[0].startswith("#"):
            continue
        sid = parts[0].rsplit(".", 1)[0] if "." in parts[0] else parts[0]
        if sid not in z:
            order.append(sid)
            z[sid] = float(parts[6])
        r.setdefault(sid, []).append((float(parts[1]) ** 2 + float(parts[2]) ** 2) ** 0.5)
    return order, z, {sid: statistics.median(d) for sid, d in r.items()}


def run(wslap, images, members, z_lens, free, out, extra):
    cmd = [wslap, "reconstruct", "--images", images, "--z-lens", repr(z_lens), "--out", out,
           "--free-z", ",".join(free), *extra]
    if members:
        cmd += ["--members", members]
    os.makedirs(out, exist_ok=True)
    t = time.time()
    with open(os.path.join(out, "log.txt"), "w") as log:
        rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
    if rc != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed, see {out}/log.txt")
    sources = json.load(open(os.path.join(out, "sources.json")))
    summary = json.load(open(os.path.join(out, "summary.json")))
    est = {s["id"]: (s["z_estimate"], s["z_interval"]) for s in sources
           if s.get("z_estimate") is not None}
    fz = summary.get("free_redshifts") or {}
    best = {sid: e["z_median"] for sid, e in fz.get("systems", [])}
    return dict(estimates=est, best=best, seconds=time.time() - t,
                known_without=fz.get("known_fit_median_without_arcsec"),
                known_with=fz.get("known_fit_median_with_arcsec"),
                not_estimated=fz.get("not_estimated", []))


def jobs_list(only, pick):
    jobs = []
    if only in (None, "synthetic"):
        for name in sorted(os.listdir(FIDELITY)):
            cdir = os.path.join(FIDELITY, name)
            if not os.path.isfile(os.path.join(cdir, "truth.json")):
                continue
            truth = json.load(open(os.path.join(cdir, "truth.json")))
            images = os.path.join(cdir, "images.cat")
            members = os.path.join(cdir, "members.cat")
            order, z, radius = catalogue_systems(images)
            if pick == "outer":
                free = sorted(order, key=lambda sid: -radius[sid])[:len(order) // 3]
            else:
                free = order[2::3]
            jobs.append(dict(set="synthetic", name=name, images=images,
                             members=members if os.path.exists(members) else None,
                             z_lens=truth["z_lens"], free=free, z=z))
    if only in (None, "as1063"):
        images = os.path.join(AS1063, "cats_gold_mul_gold.cat")
        members = os.path.join(AS1063, "cats_gold_ref_potential_w_clumpNE.cat")
        if os.path.exists(images):
            order, z, _ = catalogue_systems(images)
            for sid in order:
                jobs.append(dict(set="AS1063 gold", name=f"AS1063 gold, system {sid}",
                                 images=images, members=members, z_lens=0.348, free=[sid], z=z))
        else:
            print(f"skipping AS1063: {images} not found", file=sys.stderr)
    return jobs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--wslap", default=os.path.join(ROOT, "target", "release", "wslap"))
    ap.add_argument("--out", default="/tmp/wslap-free-z")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", choices=["synthetic", "as1063"])
    ap.add_argument("--pick", choices=["every-third", "outer"], default="every-third",
                    help="which systems of a synthetic cluster lose their redshift")
    ap.add_argument("--extra-args", default="", help="passed through to wslap reconstruct")
    args = ap.parse_args()
    jobs = jobs_list(args.only, args.pick)
    t0 = time.time()
    with cf.ThreadPoolExecutor(args.jobs) as pool:
        futures = [pool.submit(run, args.wslap, j["images"], j["members"], j["z_lens"], j["free"],
                               os.path.join(args.out, j["name"].replace(" ", "_").replace(",", "")),
                               args.extra_args.split())
                   for j in jobs]
        results = [f.result() for f in futures]
    rows, per_set = [], {}
    for j, r in zip(jobs, results):
        for sid in j["free"]:
            zt = j["z"][sid]
            if sid not in r["estimates"]:
                rows.append(dict(set=j["set"], run=j["name"], id=sid, z=zt, estimate=None))
                continue
            ze, (lo, hi) = r["estimates"][sid]
            row = dict(set=j["set"], run=j["name"], id=sid, z=zt, estimate=ze, interval=[lo, hi],
                       z_median=r["best"].get(sid), dz=abs(ze - zt) / (1 + zt),
                       dz_best=abs(r["best"].get(sid, ze) - zt) / (1 + zt), inside=lo <= zt <= hi,
                       known_without=r["known_without"], known_with=r["known_with"],
                       seconds=r["seconds"])
            rows.append(row)
            per_set.setdefault(j["set"], []).append(row)
    lines = ["| set | run | system | z | z_estimate | 68% interval | inside | |Δz|/(1+z) "
             "| known fitted median without / with (\") | time (s) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["estimate"] is None:
            lines.append(f"| {r['set']} | {r['run']} | {r['id']} | {r['z']:.3f} | — | — | ✗ | — | | |")
            continue
        kw = r["known_without"]
        kh = r["known_with"]
        known = f"{kw:.2f} / {kh:.2f}" if kw is not None and kh is not None else "—"
        lines.append(f"| {r['set']} | {r['run']} | {r['id']} | {r['z']:.3f} | {r['estimate']:.2f} "
                     f"| {r['interval'][0]:.2f} – {r['interval'][1]:.2f} | "
                     f"{'✓' if r['inside'] else '✗'} | {r['dz']:.3f} | {known} | {r['seconds']:.0f} |")
    summary = {}
    lines.append("")
    lines.append("| set | systems | median |Δz|/(1+z) (target < 0.1) | with the posterior median instead | "
                 "inside the 68% interval (target ≥ 60%) | not estimated |")
    lines.append("|---|---|---|---|---|---|")
    for name, rs in per_set.items():
        missing = sum(1 for r in rows if r["set"] == name and r["estimate"] is None)
        med = statistics.median(r["dz"] for r in rs)
        med_best = statistics.median(r["dz_best"] for r in rs)
        inside = sum(r["inside"] for r in rs) / len(rs)
        summary[name] = dict(systems=len(rs), median_dz=med, median_dz_posterior_median=med_best,
                             inside=inside, not_estimated=missing)
        lines.append(f"| {name} | {len(rs)} | {med:.3f} | {med_best:.3f} | {100 * inside:.0f}% | {missing} |")
    lines.append(f"\nWall time {time.time() - t0:.0f} s with --jobs {args.jobs}.")
    text = "\n".join(lines)
    os.makedirs(args.out, exist_ok=True)
    open(os.path.join(args.out, "free_z.md"), "w").write(text + "\n")
    json.dump(dict(rows=rows, summary=summary), open(os.path.join(args.out, "free_z.json"), "w"),
              indent=1)
    print(text)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""How well does "auto" choose? On the lenstronomy clusters of tests/data/fidelity, the
candidate that cross-validation chose beside every candidate's own distance from the truth.

For each cluster: one default run (`wslap reconstruct`, which scores every candidate of
objective.auto_* by its held-out images and keeps the best, summary.json strength_choice),
then each candidate alone as fixed settings (`--config {"objective": {"regulariser": R,
"strength": S}, "grid": {"cells": N}}`), scored against the truth by benches/fidelity.py
(deflection error median in the image region, constant removed; Einstein radius at z_s = 2).
Prints, per cluster: the chosen candidate's deflection error, the best any candidate reaches
(the oracle, which needs the truth), the median over all candidates, and what two other rules
would have chosen: the one-standard-error rule (the strongest regulariser of the chosen kind
and grid whose held-out median is within one bootstrap standard error of the best) and the
smallest held-out rms.

Usage: /tmp/refenv/bin/python benches/selection_study.py [--out DIR] [--jobs N]
(about 11 minutes with --jobs 2 on the machine of BENCHMARKS.md; runs already in DIR are kept).
"""

import argparse
import concurrent.futures as cf
import json
import os
import random
import statistics as st
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import fidelity as F  # noqa: E402

ROOT = os.path.dirname(HERE)
REGULARISERS = ["gradient", "curvature", "density"]
STRENGTHS = [0.01, 0.1, 1.0]
CELLS = [16, 24, 32]


def tag(reg, strength, cells):
    return f"{reg}-{strength}-{cells}"


def run(args, name, label, config):
    cdir = os.path.join(args.clusters, name)
    truth = json.load(open(os.path.join(cdir, "truth.json")))
    out = os.path.join(args.out, name, label)
    if not os.path.exists(os.path.join(out, "summary.json")):
        extra = []
        if config is not None:
            os.makedirs(out, exist_ok=True)
            path = os.path.join(out, "config.json")
            json.dump(config, open(path, "w"))
            extra = ["--config", path]
        F.run_wslap(args.wslap, cdir, truth, out, extra)
    r = F.score(cdir, truth, out, None)
    return name, label, dict(deflection=r["deflection_err_median"],
                             theta_e_pct=100 * r["theta_e_rel_err"])


def bootstrap_se(candidate, rounds=200):
    """Standard error of the held-out median, resampling systems."""
    systems = candidate["holdout_by_system"]
    rnd = random.Random(1)
    medians = []
    for _ in range(rounds):
        pick = [rnd.choice(systems) for _ in systems]
        medians.append(st.median(o for s in pick for o in s["offsets_arcsec"]))
    return st.pstdev(medians)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--wslap", default=os.path.join(ROOT, "target/release/wslap"))
    ap.add_argument("--clusters", default=os.path.join(ROOT, "tests/data/fidelity"))
    ap.add_argument("--out", default="/tmp/selection-study")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    names = sorted(d for d in os.listdir(args.clusters)
                   if os.path.isdir(os.path.join(args.clusters, d)))
    jobs = []
    for n in names:
        jobs.append((n, "default", None))
        for reg in REGULARISERS:
            for s in STRENGTHS:
                for c in CELLS:
                    config = {"objective": {"regulariser": reg, "strength": s},
                              "grid": {"cells": c}}
                    jobs.append((n, tag(reg, s, c), config))
    scores = {}
    with cf.ThreadPoolExecutor(args.jobs) as ex:
        for n, label, r in ex.map(lambda j: run(args, *j), jobs):
            scores.setdefault(n, {})[label] = r
    json.dump(scores, open(os.path.join(args.out, "selection.json"), "w"), indent=1)

    print("| cluster | chosen | its error (\") | ΔθE % | oracle (\") | median of all (\") "
          "| one-SE rule (\") | smallest rms (\") |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for n in names:
        d = scores[n]
        choice = json.load(open(os.path.join(args.out, n, "default", "summary.json")))[
            "strength_choice"]
        cands = choice["candidates"]
        label = lambda c: tag(c["regulariser"], c["strength"], c["cells"])  # noqa: E731
        chosen = tag(choice["chosen_regulariser"], choice["chosen"], choice["chosen_cells"])
        fixed = [k for k in d if k != "default"]
        oracle = min(d[k]["deflection"] for k in fixed)
        best = min(cands, key=lambda c: (c["holdout_unmatched"], c["holdout_median_arcsec"]))
        limit = best["holdout_median_arcsec"] + bootstrap_se(best)
        near = [c for c in cands if c["regulariser"] == best["regulariser"]
                and c["cells"] == best["cells"]
                and c["holdout_unmatched"] <= best["holdout_unmatched"]
                and c["holdout_median_arcsec"] <= limit]
        one_se = label(max(near, key=lambda c: c["strength"]))
        rms = label(min(cands, key=lambda c: (c["holdout_unmatched"], c["holdout_rms_arcsec"])))
        print(f"| {n} | {chosen} | {d[chosen]['deflection']:.2f} | "
              f"{d[chosen]['theta_e_pct']:+.1f} | {oracle:.2f} | "
              f"{st.median(d[k]['deflection'] for k in fixed):.2f} | "
              f"{d[one_se]['deflection']:.2f} | {d[rms]['deflection']:.2f} |")


if __name__ == "__main__":
    main()

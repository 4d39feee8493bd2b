#!/usr/bin/env python3
"""How well a reconstruction's predicted images match the observed ones, and how many it adds.

Reads the `sources.json` of one or more `wslap reconstruct --out` folders (or of `wslap paper`'s
case folders, e.g. `OUT/case-galaxy-model`). For each fitted system the run has already solved
the lens equation forward from the system's source (`predicted`: every image the map makes,
with its magnification); each observed image carries its nearest predicted image and the
offset to it. Printed per folder:

- observed: the observed images (arc centroids for `wslap paper`'s arcs);
- predicted: the predicted images with |mu| >= MU_MIN (fainter ones would not be seen);
- extra: predicted images (|mu| >= MU_MIN) more than FAR arcsec from every observed image of
  their system: images the map makes where the data show none (the null space GRALE
  constrains);
- far: observed images whose nearest predicted image is more than FAR arcsec away, or none;
- median offset: the median offset of the observed images to their predicted ones.

Usage: python3 benches/predicted_images.py DIR [DIR ...] [--far 3] [--mu-min 0.5]
"""

import argparse
import json
import math
import os
import statistics


def score(folder, far, mu_min):
    with open(os.path.join(folder, "sources.json")) as f:
        sources = json.load(f)
    observed = predicted = extra = missed = 0
    offsets = []
    for system in sources:
        seen = [o["position_arcsec"] for o in system["observed"]]
        shown = [p for p in system["predicted"] if abs(p["magnification"] or 0.0) >= mu_min]
        observed += len(seen)
        predicted += len(shown)
        extra += sum(min(math.dist(p["position_arcsec"], o) for o in seen) > far for p in shown)
        for o in system["observed"]:
            d = o["offset_arcsec"]
            missed += d is None or d > far
            if d is not None:
                offsets.append(d)
    median = statistics.median(offsets) if offsets else float("nan")
    return observed, predicted, extra, missed, median


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folders", nargs="+")
    parser.add_argument("--far", type=float, default=3.0, help="arcsec (default 3)")
    parser.add_argument("--mu-min", type=float, default=0.5, help="|mu| (default 0.5)")
    a = parser.parse_args()
    print("| folder | observed | predicted | extra | far | median offset (\") |")
    print("|---|---:|---:|---:|---:|---:|")
    for folder in a.folders:
        observed, predicted, extra, missed, median = score(folder, a.far, a.mu_min)
        print(f"| {folder} | {observed} | {predicted} | {extra} | {missed} | {median:.2f} |")


if __name__ == "__main__":
    main()

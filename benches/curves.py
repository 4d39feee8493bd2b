#!/usr/bin/env python3
"""The shape of the tangential critical curves of one or more lens maps.

For each critical-curves.json (what `wslap maps` and `wslap reconstruct` write), prints the
number of tangential curves, the share of the area inside them that the largest one holds
(a nested loop counts as a hole, as wslap's Einstein radius counts it), and the sizes of the
others as equivalent radii sqrt(area / pi): the median, the largest, and how many exceed 1
and 2 arcsec. A member galaxy's own loop is a few tenths of an arcsec; a loop of several
arcsec is a structure the map's reader will notice.

Usage: python3 benches/curves.py NAME=DIR/critical-curves.json ...
"""

import json
import math
import sys


def signed_area(points):
    n = len(points)
    return 0.5 * sum(
        points[i][0] * points[(i + 1) % n][1] - points[(i + 1) % n][0] * points[i][1]
        for i in range(n)
    )


def describe(path):
    with open(path) as f:
        curves = json.load(f)
    # Tangential loops run clockwise around their supercritical inside (negative area).
    areas = sorted((-signed_area(c) for c in curves["tangential"]), reverse=True)
    inside = sum(areas)
    others = [math.sqrt(max(a, 0.0) / math.pi) for a in areas[1:]]
    others.sort()
    return dict(
        curves=len(areas),
        einstein=curves["einstein_radius_arcsec"],
        main_share=areas[0] / inside if inside > 0 else float("nan"),
        median=others[len(others) // 2] if others else 0.0,
        largest=others[-1] if others else 0.0,
        over1=sum(r > 1.0 for r in others),
        over2=sum(r > 2.0 for r in others),
    )


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    print("| map | θE (\") | tangential curves | main curve's share | other loops: median r (\") "
          "| largest r (\") | r > 1\" | r > 2\" |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for arg in sys.argv[1:]:
        name, _, path = arg.rpartition("=")
        d = describe(path)
        print(f"| {name or path} | {d['einstein']:.2f} | {d['curves']} | {d['main_share']:.3f} "
              f"| {d['median']:.2f} | {d['largest']:.2f} | {d['over1']} | {d['over2']} |")


if __name__ == "__main__":
    main()

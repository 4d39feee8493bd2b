#!/usr/bin/env python3
"""Writes an arc file of N_PIXELS constraint pixels (default 20000) for the memory benchmark
(BENCHMARKS.md): 30 systems of 3 arcs each at redshifts 1 to 5, pixels on a 0.1 arcsec lattice
in elongated patches within 70 arcsec of the centre. The lens it implies is meaningless; only
the size of the linear system matters here.

Usage: python3 benches/memory_arcs.py OUT.json [N_PIXELS]
"""
import json
import sys

import numpy as np

out = sys.argv[1]
n_pixels = int(sys.argv[2]) if len(sys.argv) > 2 else 20000
rng = np.random.default_rng(7)
per_image = n_pixels // 90
systems = []
for s in range(30):
    images = []
    for _ in range(3):
        r, phi = rng.uniform(10, 70), rng.uniform(0, 2 * np.pi)
        cx, cy = r * np.cos(phi), r * np.sin(phi)
        t = np.arange(per_image) * 0.1
        along = (t - t.mean())
        # an arc: a thin patch along the tangential direction
        x = cx - np.sin(phi) * along * 0.3 + 0.1 * (np.arange(per_image) % 3)
        y = cy + np.cos(phi) * along * 0.3
        images.append([[round(float(a), 4), round(float(b), 4)] for a, b in zip(x, y)])
    systems.append({"id": str(s + 1), "z": round(float(rng.uniform(1.0, 5.0)), 3), "images": images})
json.dump({"systems": systems}, open(out, "w"))
print(f"wrote {out}: {30 * 3 * per_image} pixels")

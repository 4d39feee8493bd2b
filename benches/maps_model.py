#!/usr/bin/env python3
"""Writes benches/maps-model.json: the model of the `maps` benchmark (BENCHMARKS.md).

One elliptical NFW cluster halo and 100 truncated-NFW member galaxies at z = 0.35, placed with a
fixed seed so that the Rust and lenstronomy runs evaluate exactly the same lens.
"""
import json
import os

import numpy as np

rng = np.random.default_rng(20261122)
components = [{"type": "nfw", "x": 0.0, "y": 0.0, "m200": 1.5e15, "c200": 5.0, "q": 0.75, "pa": 30.0}]
for _ in range(100):
    r = 80.0 * np.sqrt(rng.uniform(0.0, 1.0))
    phi = rng.uniform(0.0, 2.0 * np.pi)
    m200 = float(10 ** rng.uniform(10.5, 12.3))
    components.append({
        "type": "tnfw",
        "x": round(float(r * np.cos(phi)), 3),
        "y": round(float(r * np.sin(phi)), 3),
        "m200": float(f"{m200:.4e}"),
        "c200": 10.0,
        "r_trunc": round(3.0 * (m200 / 1e12) ** (1.0 / 3.0), 3),
    })
model = {"cosmology": {"h0": 70.0, "omega_m": 0.3}, "z_lens": 0.35, "components": components}
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "maps-model.json")
with open(out, "w") as f:
    json.dump(model, f, indent=1)
print(f"wrote {out}")

#!/usr/bin/env python3
"""Writes the seed inputs of every fuzz target into fuzz/corpus/<target>/ from the
repository's own test and example files plus small hand-written ones (never from
../shared/data: pass that directory to `cargo fuzz run` as an extra corpus instead).
The committed corpus, fuzz/corpus/<target>/, is these seeds merged with what the fuzzers
found, minimised with `cargo fuzz cmin` (see fuzz/README.md).

Run from the repository root: python3 fuzz/seeds.py
"""
import base64
import json
import os
import re
import struct

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fuzz", "corpus")


def read(path):
    """The file at `path`, or (after a reorganisation) the one file of that name in the
    same top directory."""
    full = os.path.join(ROOT, path)
    if not os.path.exists(full):
        top, name = path.split("/")[0], os.path.basename(path)
        found = [os.path.join(d, name) for d, _, files in os.walk(os.path.join(ROOT, top))
                 if name in files and "target" not in d]
        if len(found) != 1:
            raise SystemExit(f"seeds.py: {path} not found; update the path")
        full = found[0]
    with open(full, "rb") as f:
        return f.read()


def put(target, name, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def first_lines(data, n):
    return b"".join(data.splitlines(keepends=True)[:n])


# Lenstool image catalogues: the teaching example, the head of two test catalogues, and the
# header variants (absolute degrees, sexagesimal reference, CRLF and BOM, comments, ids).
put("image_catalog", "teaching.cat", read("www/examples/teaching/images.cat"))
put("image_catalog", "fidelity_d.cat", first_lines(read("tests/data/fidelity/d_few_systems/images.cat"), 14))
put("image_catalog", "a1689.cat", first_lines(read("www/examples/a1689-sim/images.cat"), 14))
put("image_catalog", "absolute.cat",
    "#REFERENCE 0\n1.1 342.1901 -44.5268 0.5 0.3 12 1.2 25.1\n1.2 342.1755 -44.5351 0.4 0.4 0 1.2\n"
    "2a.1 342.1838 -44.5211 0.3 0.2 -40 0 24\n2a.2 342.1797 -44.5390 0.3 0.2 80 2.4 24\n")
put("image_catalog", "no_header.cat",
    "\ufeff# id ra dec a b theta z mag\r\n\t1.1  197.8779 -1.3338 0.2 0.2 0 3.04 25\r\n"
    "  # an indented comment\r\n1.2 197.8701 -1.3402 0.2 0.2 0 3.0405 25 extra\r\n")
put("image_catalog", "sexagesimal.cat",
    "#REFERENCE 1 22:48:43.97 -44:31:51.2\n14c.1 -3.2 10.5 0.2 0.1 45 1.0\n14c.2 4.1 -8.8 0.2 0.1 45 1.0\n")

# Arclet catalogues (weak lensing): the head of the synthetic one, and header variants.
put("arclet_catalog", "weak_lensing.cat", first_lines(read("tests/data/weak_lensing/arclets.cat"), 14))
put("arclet_catalog", "absolute.cat",
    "#REFERENCE 0\n1 342.1901 -44.5268 0.5 0.3 12 1.2\n2 342.1755 -44.5351 0.4 0.4 0 1.9\n"
    "g3 342.1838 -44.5211 0.3 0.2 -40 0.9 extra\n")
put("arclet_catalog", "round_and_edge_on.cat",
    "#REFERENCE 3 342.1832 -44.5309\n1 60.0 10.0 0.5 0.5 20 1.5\n2 -70.0 5.0 0.5 0 135 2.5\n"
    "3 0.0 0.0 1e-3 0 -90 3\n")

# Member catalogues.
put("member_catalog", "fidelity_d.cat", first_lines(read("tests/data/fidelity/d_few_systems/members.cat"), 14))
put("member_catalog", "a1689.cat", first_lines(read("www/examples/a1689-sim/members.cat"), 14))
put("member_catalog", "absolute.cat",
    "# id ra dec a b theta mag lum\n1 342.18322 -44.53092 1.2 0.8 30 17.2 3.1\n"
    "2 342.1801 -44.5302 0.6 0.5 -10 19.5\n2 342.1855 -44.5322 0.3 0.3 0 21.0 0.2\n")
# Commented-out rows, as Lenstool set-ups keep a BCG the .par models: kept aside when they read.
put("member_catalog", "commented.cat",
    "#REFERENCE 3 292.95682 -26.575718\n#(string name) X Y A B THETA MAG LUM\n"
    "  #1009.0 0.0 0.0 1.98 1.13 58.82 17.325 0.35\n##7 1 2 0.3 0.2 10 19.5\n#8 1 2 -0.3 0.2 10 nan\n"
    "853.0 -18.18 -26.42 0.51 0.34 78.61 20.12 0.34\n")

# Arc pixel files (JSON): both layouts, numeric ids, null and 0 redshifts.
arcs = json.loads(read("www/examples/a1689-sim/arcs.json"))
small = {"systems": [{"id": s["id"], "z": s["z"], "images": [im[:3] for im in s["images"][:2]]}
                     for s in arcs["systems"][:2]]}
put("arcs_json", "a1689_head.json", json.dumps(small))
put("arcs_json", "layouts.json",
    '{"systems": [\n {"id": "1", "z": 2.1, "pixels": [[1.0, 2.0], [1.2, 2.0]]},\n'
    ' {"id": 2, "z": null, "images": [[[-3.5, 0.25]], [[4.0, -1e-3], [4.2, 0.0]]]},\n'
    ' {"id": "3b", "z": 0, "pixels": [[10, 10]]}\n]}\n')

# DS9 regions: the files the tests write, and arcs marked on an image (the format's doc).
for name in ["files_ours_fk5.reg", "files_ours_image.reg", "files_ours_marks_fk5.reg",
             "files_ours_marks_image.reg"]:
    put("ds9_regions", name, read("tests/data/" + name))
put("ds9_regions", "arcs.reg",
    "# Region file format: DS9 version 4.1\n"
    'global color=green dashlist=8 3 width=1 font="helvetica 10 normal roman"\nfk5\n'
    "polygon(197.8779,-1.3338,197.8781,-1.3335,197.8776,-1.3331) # text={1.1 z=3.04}\n"
    'ellipse(197.8701,-1.3402,2.1",0.6",35) # text={1.2}\n'
    'circle(197.8712,-1.3399,0.4") # text={2.1 z=1.8}\npoint(197.8688,-1.3381) # text={2.2}\n'
    '-circle(197.8700,-1.3401,0.3")\nbox(13:11:29.1,-01:20:24.5,1\',3",20) # text="3.1" color=red\n'
    "icrs; circle point 197.87 -1.34 # text={3.2}\n")

# Lenstool .par: the CATS-like file of tests/physics/dpie.rs.
def test_source_with(marker):
    for d, _, files in os.walk(os.path.join(ROOT, "tests")):
        for name in sorted(files):
            if name.endswith(".rs"):
                text = open(os.path.join(d, name), encoding="utf-8").read()
                if marker in text:
                    return text
    raise SystemExit(f"seeds.py: no test source holds {marker!r}")


par = re.search(r'const PAR: &str = "(.*?)";', test_source_with('const PAR: &str = "'),
                re.S).group(1).replace("\\t", "\t")
put("lenstool_par", "cats_like.par", par)
put("lenstool_par", "minimal.par",
    "runmode\n\treference 3 150.0 2.2\n\tend\npotential 1\n\tprofile 81\n\tx_centre 0\n"
    "\ty_centre 0\n\tellipticity 0.2\n\tangle_pos 10\n\tcore_radius 2.0\n\tcut_radius 300\n"
    "\tv_disp 900\n\tz_lens 0.3\n\tend\nfini\n")

# FITS: the three test files (ours, astropy float32 and int16 with BSCALE).
for name in ["files_ours.fits", "files_astropy_f32.fits", "files_astropy_i16.fits"]:
    put("fits_read", name, read("tests/data/" + name))


# The FITS writer's inputs: side byte, flags, pixel (f64), centre (2 f64), reference (2 f64),
# values (f32), all little-endian.
def roundtrip(side, flags, pixel, cx, cy, ra, dec, values):
    b = bytes([side, flags]) + struct.pack("<5d", pixel, cx, cy, ra, dec)
    return b + b"".join(struct.pack("<f", v) for v in values)


put("fits_roundtrip", "small_ref", roundtrip(3, 1, 0.5, 1.0, -2.0, 342.18, -44.53,
                                            [0.0, -1.5, 3.25, 1e-30, 7e30, -0.0, 2.0, 1.0, 0.5]))
put("fits_roundtrip", "no_ref", roundtrip(1, 0, 0.03, 0.0, 0.0, 0.0, 0.0, [1.0, 2.0, 3.0, 4.0]))

# Model files: the examples, the demo cluster, every component type.
put("model_json", "teaching.json", read("www/examples/teaching/model.json"))
demo = read("src/demo.rs").decode()
put("model_json", "cluster.json", re.search(r'CLUSTER_MODEL_JSON: &str = r#"(.*?)"#;', demo, re.S).group(1))
put("model_json", "all_types.json",
    '{"cosmology": {"h0": 70.0, "omega_m": 0.3}, "z_lens": 0.3,'
    ' "reference": {"ra": 150.0, "dec": 2.2}, "components": ['
    '{"type": "nfw", "x": 0.0, "y": 0.0, "m200": 1.0e15, "c200": 5.0, "q": 0.8, "pa": 30.0},'
    '{"type": "tnfw", "x": 20.0, "y": 3.0, "m200": 1.0e12, "c200": 10.0, "r_trunc": 15.0},'
    '{"type": "sis", "x": 10.0, "y": -5.0, "sigma_v": 250.0},'
    '{"type": "point", "x": 0.0, "y": 0.0, "mass": 1.0e12},'
    '{"type": "gaussian", "x": 0.0, "y": 0.0, "mass": 1.0e13, "sigma": 5.0}]}')

# Settings: the README's CONFIG.json, a paper-like one, and the app's settings.
readme = read("README.md").decode()
put("settings_json", "readme_config.json", re.search(r'```json\n(\{\n  "grid".*?)```', readme, re.S).group(1))
put("settings_json", "paper.json",
    '{"solver": {"method": "qadp", "iterations": 500}, "objective": {"regulariser": "none",'
    ' "strength": 0}, "members": {"layers": "per_galaxy"}, "products": {"z_source": 3.0,'
    ' "pixels": 64, "size_arcsec": 80}}')
put("settings_json", "app.json",
    '{"z_lens": 0.3, "h0": 68, "omega_m": 0.31, "holdout": ["2", "14c"],'
    ' "reconstruct": {"grid": {"cells": 16}, "constraints": {"mode": "points", "default_z": 2.5}}}')

# Projects: data texts, settings, a stored FITS, a result without X.
teaching_cat = read("www/examples/teaching/images.cat").decode()
project = {"format": "wslap-project", "version": 1, "name": "teaching",
           "data": {"images": {"name": "images.cat", "text": teaching_cat},
                    "model": {"name": "model.json", "text": read("www/examples/teaching/model.json").decode()}},
           "settings": {"z_lens": 0.3, "reconstruct": {"grid": {"cells": 12}, "products": {"pixels": 32}}},
           "result": {"kind": "reconstruct", "summary": {"note": "no X"}, "iterations": 0}}
put("project_json", "teaching.wslap", json.dumps(project, indent=1))
fits = base64.b64encode(read("tests/data/files_ours.fits")).decode()
put("project_json", "deflection.wslap", json.dumps(
    {"format": "wslap-project", "version": 1,
     "data": {"deflection_x": {"name": "x.fits", "fits_base64": fits},
              "deflection_y": {"name": "y.fits", "fits_base64": fits}}}))

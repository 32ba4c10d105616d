#!/usr/bin/env python3
"""The eight record-12 layouts of dataset 58, ASCII against binary, read by lamdyn and by pyuff.

Usage: python3 tools/uff/pairs_vs_pyuff.py [path/to/lamdyn]  (default target/release/lamdyn)
Prints a markdown table (docs/uff.md): points read and the largest relative difference between
the ASCII and binary twin of each case, for both readers.
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import pyuff

LAMDYN = sys.argv[1] if len(sys.argv) > 1 else "target/release/lamdyn"
DIR = os.path.join(os.path.dirname(__file__), "../../crates/lamdyn-uff/tests/fixtures/ufffiles-jl")


def lamdyn_read(path, tmp):
    out = os.path.join(tmp, os.path.basename(path) + ".json")
    subprocess.run([LAMDYN, "uff", "convert", path, out, "--to", "json"], check=True)
    d = json.load(open(out))["datasets"][0]["dataset"]
    data = d["data"]
    y = np.array([c[0] + 1j * c[1] for c in data["Complex"]]) if "Complex" in data else np.array(data["Real"])
    ab = d["abscissa"]
    x = np.array(ab["Uneven"]) if "Uneven" in ab else ab["Even"]["start"] + ab["Even"]["step"] * np.arange(len(y))
    return x, y


def diff(a, b):
    if len(a[1]) != len(b[1]):
        return "lengths differ"
    return f"{np.max(np.abs(a[1] - b[1])) / np.max(np.abs(a[1])):.1e}"


print(f"| case | layout | lamdyn points (ascii/binary) | lamdyn max rel diff | pyuff {pyuff.__version__} points | pyuff max rel diff |")
print("|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for c in range(1, 9):
        a, b = (os.path.join(DIR, f"dataset58_case{c}_{k}.unv") for k in ("ascii", "binary"))
        la, lb = lamdyn_read(a, tmp), lamdyn_read(b, tmp)
        pa, pb = (pyuff.UFF(p).read_sets(0) for p in (a, b))
        pa, pb = (np.asarray(pa["x"]), np.asarray(pa["data"])), (np.asarray(pb["x"]), np.asarray(pb["data"]))
        layout = ["real single", "complex single", "real double", "complex double"][(c - 1) // 2] + (", uneven" if c % 2 == 0 else ", even")
        print(f"| {c} | {layout} | {len(la[1])}/{len(lb[1])} | {diff(la, lb)} | {len(pa[1])}/{len(pb[1])} | {diff(pa, pb)} |")

#!/usr/bin/env python3
"""Writes the free-free beam FRFs (crates/lamdyn-ema/tests/fixtures/free-free-beam, three
accelerance FRFs at 1 Hz, one reference) as a lamdyn CSV FRF set: OUT/channels.csv, OUT/frf.csv.

Usage: python3 tools/ema/beam_to_csv.py OUT
The points are named 1, 2, 3 along the beam (positions 0, 0.5, 1 m: the data gives none).
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DIR = os.path.join(HERE, "../../crates/lamdyn-ema/tests/fixtures/free-free-beam")


def main(out):
    os.makedirs(out, exist_ok=True)
    frf = np.array([np.loadtxt(os.path.join(DIR, f"meas_point_{i}.txt"), dtype=complex) for i in (1, 2, 3)])
    with open(os.path.join(out, "channels.csv"), "w") as f:
        f.write("name,role,x_m,y_m,z_m,dx,dy,dz\n")
        for i, x in enumerate((0.0, 0.5, 1.0)):
            f.write(f"{i + 1},response,{x},0,0,0,0,1\n")
        f.write("hammer,reference,0,0,0,0,0,1\n")
    with open(os.path.join(out, "frf.csv"), "w") as f:
        f.write("# quantity = accelerance\nf_hz," + ",".join(f"{i}@hammer:re,{i}@hammer:im" for i in (1, 2, 3)) + "\n")
        for k in range(frf.shape[1]):
            f.write(f"{float(k)}," + ",".join(f"{float(v.real)!r},{float(v.imag)!r}" for v in frf[:, k]) + "\n")
    return frf


if __name__ == "__main__":
    main(sys.argv[1])

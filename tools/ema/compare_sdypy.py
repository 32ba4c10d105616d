#!/usr/bin/env python3
"""The measured free-free beam identified by lamdyn and by sdypy-EMA, side by side.

sdypy-EMA 0.31 (pip install sdypy-EMA): LSCF, pol_order_high = 30 (orders 2-60), band 10-1000 Hz,
poles picked with select_closest_poles near lamdyn's frequencies, residues by its LSFD.
lamdyn: `lamdyn ema` on the same data (automatic selection, refined poles).
Both regenerate the FRFs; the correlation is the FRAC over the band.

Usage: python3 tools/ema/compare_sdypy.py [path/to/lamdyn]  -> a markdown table (docs/ema.md)
"""
import json
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np
import sdypy.EMA as EMA

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from beam_to_csv import main as beam_to_csv  # noqa: E402

LAMDYN = sys.argv[1] if len(sys.argv) > 1 else "target/release/lamdyn"
warnings.simplefilter("ignore")


def frac(a, b):
    return abs(np.vdot(b, a)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)


with tempfile.TemporaryDirectory() as tmp:
    frf = beam_to_csv(tmp)
    out = subprocess.run([LAMDYN, "ema", "--channels", os.path.join(tmp, "channels.csv"), "--frf", os.path.join(tmp, "frf.csv"),
                          "--band-hz", "10,1000", "--json"], capture_output=True, text=True, check=False)
    doc = json.loads(out.stdout)
lam = [(r["freq_hz"], r["damping_ratio"]) for r in doc["rows"]]
lam_frac = [r["frac"] for r in doc["sections"]["correlation"]]

freq = np.arange(frf.shape[1]) * 1.0
m = EMA.Model(frf=frf, freq=freq, lower=10, upper=1000, pol_order_high=30, frf_type="accelerance")
m.get_poles(show_progress=False)
m.select_closest_poles([f for f, _ in lam])
H, A = m.get_constants(whose_poles="own", FRF_ind="all")
# sdypy reconstructs lines 0 .. upper-1 (1000 lines): compare on 10-999 Hz.
sd_frac = [frac(frf[i, 10:H.shape[1]], H[i, 10:]) for i in range(frf.shape[0])]

print("| mode | lamdyn f [Hz] | sdypy f [Hz] | diff | lamdyn zeta [%] | sdypy zeta [%] |")
print("|---|---|---|---|---|---|")
for k, ((f, z), fs, zs) in enumerate(zip(lam, m.nat_freq, m.nat_xi)):
    print(f"| {k + 1} | {f:.3f} | {fs:.3f} | {f / fs - 1:+.1e} | {100 * z:.4f} | {100 * zs:.4f} |")
print()
print("| FRF | lamdyn FRAC | sdypy FRAC |")
print("|---|---|---|")
for i, (a, b) in enumerate(zip(lam_frac, sd_frac)):
    print(f"| point {i + 1} | {a:.4f} | {b:.4f} |")

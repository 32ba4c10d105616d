#!/usr/bin/env python3
"""Whole process on the measured dam, lamdyn ema against sdypy-EMA (issue 45.5): 26 accelerance
FRFs x 337 lines of 2-12.5 Hz (0.03125 Hz lines, one reference; the fixture with its BSD
licence), orders 2-60 (sdypy: pol_order_high = 30).

- lamdyn: `lamdyn ema --uff dam0.unv --band-hz 2,12.5 --json` (UFF 58 ASCII, the automatic
  selection with the CMIF peaks' rescue, the checked refinement, residues, sds, verdicts), one
  process per run; its step times from the JSON (details.seconds).
- sdypy-EMA: `python3 -c ...` reading the same FRFs from .npy (its fastest input), LSCF,
  the stable pole of its diagram nearest each of lamdyn's frequencies (it has no automatic
  selection; its select_closest_poles drifts between close modes, see the script), its LSFD
  (get_constants), one process per run (Python start-up and imports included, as a user pays).

Each is timed REPEATS times back to back (wall clock of the process); the median is reported.
Accuracy without a truth: the FRAC of each tool's regenerated FRFs against the measured ones
over the band (sdypy's from its get_constants FRFs), and the two tools' poles side by side.

Needs: the lamdyn binary (cargo build --release), the Python package (pip install ./python) to
read the UFF, numpy and sdypy-EMA.

Usage: python3 tools/ema/bench_dam_vs_sdypy.py [REPEATS] [path/to/lamdyn]
"""
import json
import os
import statistics
import sys
import tempfile

import numpy as np

import lamdyn
from bench_long_vs_sdypy import timed  # the process's wall clock, its stdout

REPEATS = int(sys.argv[1]) if len(sys.argv) > 1 else 5
LAMDYN = sys.argv[2] if len(sys.argv) > 2 else "target/release/lamdyn"
DAM = "crates/lamdyn-ema/tests/fixtures/dam/dam0.unv"
BAND = (2.0, 12.5)

SDYPY = """
import sys, json, warnings
import numpy as np
import sdypy.EMA as EMA
from sdypy.EMA import stabilization
warnings.simplefilter("ignore")
f = np.load(sys.argv[1]); frf = np.load(sys.argv[2])
m = EMA.Model(frf=frf, freq=f, lower=2, upper=12.5, pol_order_high=30, frf_type="accelerance")
m.get_poles(show_progress=False)
# Its stable poles (select_closest_poles' own criteria), each target's nearest one picked as on
# its stabilization chart: select_closest_poles' window search (+-2 Hz at its narrowest) drifts
# between the dam's modes 0.1-0.5 Hz apart.
fn, xi, tf, tx = stabilization._stabilization(m.all_poles, m.n_bands * m.pol_order_high, err_fn=0.001, err_xi=0.05)
stable = (tf > 0) & (tx > 0) & (xi > 0)
fs = np.where(stable, np.nan_to_num(fn), np.inf)
pole_ind = []
for fr in json.loads(sys.argv[3]):
    i, order = np.unravel_index(np.argmin(np.abs(fs - fr)), fs.shape)
    p = -xi[i, order] * 2 * np.pi * fn[i, order] + 1j * 2 * np.pi * fn[i, order] * np.sqrt(1 - xi[i, order] ** 2)
    pole_ind.append([order, int(np.argmin(np.abs(m.all_poles[order] - p)))])
m.pole_ind = np.asarray(pole_ind, dtype=int)
m.nat_freq = [float(fn[np.unravel_index(np.argmin(np.abs(fs - fr)), fs.shape)]) for fr in json.loads(sys.argv[3])]
m.nat_xi = [float(xi[np.unravel_index(np.argmin(np.abs(fs - fr)), fs.shape)]) for fr in json.loads(sys.argv[3])]
H, A = m.get_constants(whose_poles="own", FRF_ind="all")
ff = m.freq  # sdypy keeps the lines below its upper limit
band = (ff >= 2) & (ff <= 12.5)
h, g = frf[:, : ff.size][:, band], H[:, band]
frac = (np.abs(np.sum(h * g.conj(), 1)) ** 2 / (np.sum(np.abs(h) ** 2, 1) * np.sum(np.abs(g) ** 2, 1)))
print(json.dumps({"f": list(map(float, m.nat_freq)), "z": list(map(float, m.nat_xi)), "frac": list(map(float, frac))}))
"""


def main():
    data = lamdyn.read_uff(DAM)
    f, frf = data.freqs_hz, data.frf[:, 0, :]
    with tempfile.TemporaryDirectory() as tmp:
        fn, hn = os.path.join(tmp, "f.npy"), os.path.join(tmp, "frf.npy")
        np.save(fn, f)
        np.save(hn, frf)
        lam_cmd = [LAMDYN, "ema", "--uff", DAM, "--band-hz", f"{BAND[0]},{BAND[1]}", "--json"]
        _, out = timed(lam_cmd)
        lam = json.loads(out)
        picks = [r["freq_hz"] for r in lam["rows"]]
        lam_t, sd_t, steps = [], [], []
        for _ in range(REPEATS):
            dt, out = timed(lam_cmd)
            lam_t.append(dt)
            steps.append(json.loads(out)["details"]["seconds"])
            dt, out = timed([sys.executable, "-c", SDYPY, fn, hn, json.dumps(picks)])
            sd_t.append(dt)
            sd = json.loads(out)
    tl, ts = statistics.median(lam_t), statistics.median(sd_t)
    print(f"dam: {frf.shape[0]} FRFs x {int(np.sum((f >= BAND[0]) & (f <= BAND[1])))} lines in "
          f"{BAND[0]}-{BAND[1]} Hz, orders 2-60, {os.cpu_count()} cores, median of {REPEATS}")
    print(f"whole process: lamdyn {tl:.3f} s, sdypy-EMA {ts:.3f} s, ratio {ts / tl:.1f}x")
    order = ["read", "diagram", "selection", "refinement", "check", "residues", "deviations", "modes"]
    print("lamdyn steps (median, s): " + ", ".join(
        f"{k} {statistics.median(s[k] for s in steps):.3f}" for k in order))
    lam_frac = [c["frac"] for c in lam["sections"]["correlation"]]
    print(f"FRAC over the 26 FRFs: lamdyn mean {np.mean(lam_frac):.4f} (min {min(lam_frac):.4f}), "
          f"sdypy mean {np.mean(sd['frac']):.4f} (min {min(sd['frac']):.4f})")
    print("| mode | lamdyn f [Hz] | sdypy f [Hz] | lamdyn zeta [%] | sdypy zeta [%] |")
    print("|---|---|---|---|---|")
    for k, r in enumerate(lam["rows"]):
        print(f"| {k + 1} | {r['freq_hz']:.4f} | {sd['f'][k]:.4f} | {100 * r['damping_ratio']:.3f} | "
              f"{100 * sd['z'][k]:.3f} |")


if __name__ == "__main__":
    main()

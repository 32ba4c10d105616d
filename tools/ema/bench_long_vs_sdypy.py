#!/usr/bin/env python3
"""Whole process on a long record, lamdyn ema against sdypy-EMA (issue 17.2): 9 accelerance
FRFs x 50 001 lines (0.02-1000 Hz), four modes (51.5, 142.2, 278.7, 460.4 Hz; zeta 0.2-1 %),
40 dB complex noise, band 20-1000 Hz, orders 2-60 (sdypy: pol_order_high = 30).

- lamdyn: `lamdyn ema --uff long.uff --band-hz 20,1000 --json` (binary 58b, the automatic
  selection, the checked refinement, residues, sds, verdicts, CMIF), one process per run; its
  step times from the JSON (details.seconds).
- sdypy-EMA: `python3 -c ...` reading the same FRFs from .npy (its fastest input), LSCF,
  select_closest_poles at the true frequencies (it has no automatic selection), its LSFD
  (get_constants), one process per run (Python start-up and imports included, as a user pays).

Each is timed REPEATS times (wall clock of the process); the median is reported with the
poles' errors against the truth. Needs: the lamdyn binary (cargo build --release), the
Python package (pip install ./python) to write the UFF, numpy and sdypy-EMA.

Usage: python3 tools/ema/bench_long_vs_sdypy.py [REPEATS] [path/to/lamdyn]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import lamdyn

REPEATS = int(sys.argv[1]) if len(sys.argv) > 1 else 5
LAMDYN = sys.argv[2] if len(sys.argv) > 2 else "target/release/lamdyn"
MODES = [(51.5, 0.003), (142.2, 0.002), (278.7, 0.004), (460.4, 0.01)]


def shape(r, o):
    x = (o + 0.5) / 24
    return np.sin((r + 1) * np.pi * x + 0.3 * r) + 0.2 * np.cos((r + 2) * x)


def synthetic():
    f = np.arange(1, 50_002) * 0.02
    s = 2j * np.pi * f
    rng = np.random.default_rng(11)
    frf = np.zeros((9, f.size), complex)
    for o in range(9):
        h = 0
        for r, (fr, z) in enumerate(MODES):
            w = 2 * np.pi * fr
            p = complex(-z * w, w * np.sqrt(1 - z * z))
            a = shape(r, 2 * o) * shape(r, 0) / (2j * p.imag)
            h = h + a / (s - p) + np.conj(a) / (s - np.conj(p))
        h = h * s * s
        rms = np.sqrt(np.mean(np.abs(h) ** 2))
        sd = rms * 10 ** (-40 / 20) / np.sqrt(2)
        frf[o] = h + sd * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
    return f, frf


SDYPY = """
import sys, json, warnings
import numpy as np
import sdypy.EMA as EMA
warnings.simplefilter("ignore")
f = np.load(sys.argv[1]); frf = np.load(sys.argv[2])
m = EMA.Model(frf=frf, freq=f, lower=20, upper=1000, pol_order_high=30, frf_type="accelerance")
m.get_poles(show_progress=False)
m.select_closest_poles(json.loads(sys.argv[3]))
H, A = m.get_constants(whose_poles="own", FRF_ind="all")
print(json.dumps({"f": list(map(float, m.nat_freq)), "z": list(map(float, m.nat_xi))}))
"""


def timed(cmd):
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    dt = time.perf_counter() - t
    if p.returncode not in (0, 1):
        raise SystemExit(f"{cmd[0]} failed: {p.stderr[-2000:]}")
    return dt, p.stdout


def main():
    f, frf = synthetic()
    with tempfile.TemporaryDirectory() as tmp:
        uff = os.path.join(tmp, "long.uff")
        lamdyn.write_uff(uff, f, frf[:, None, :], [f"{o + 1}+Z" for o in range(9)], ["100+Z"], binary=True)
        fn, hn = os.path.join(tmp, "f.npy"), os.path.join(tmp, "frf.npy")
        np.save(fn, f)
        np.save(hn, frf)
        truth = [m[0] for m in MODES]
        lam_t, sd_t, steps = [], [], []
        for _ in range(REPEATS):
            dt, out = timed([LAMDYN, "ema", "--uff", uff, "--band-hz", "20,1000", "--json"])
            lam_t.append(dt)
            lam = json.loads(out)
            steps.append(lam["details"]["seconds"])
            dt, out = timed([sys.executable, "-c", SDYPY, fn, hn, json.dumps(truth)])
            sd_t.append(dt)
            sd = json.loads(out)
    lf = [r["freq_hz"] for r in lam["rows"]]
    lz = [r["damping_ratio"] for r in lam["rows"]]
    tl, ts = statistics.median(lam_t), statistics.median(sd_t)
    print(f"9 FRFs x {f.size} lines, band 20-1000 Hz, orders 2-60, {os.cpu_count()} cores, median of {REPEATS}")
    print(f"whole process: lamdyn {tl:.3f} s, sdypy-EMA {ts:.3f} s, ratio {ts / tl:.1f}x")
    order = ["read", "diagram", "selection", "refinement", "check", "residues", "deviations", "modes"]
    print("lamdyn steps (median, s): " + ", ".join(
        f"{k} {statistics.median(s[k] for s in steps):.3f}" for k in order))
    print("| mode | true f [Hz] | lamdyn f err | sdypy f err | true zeta [%] | lamdyn zeta err | sdypy zeta err |")
    print("|---|---|---|---|---|---|---|")
    for k, (ft, zt) in enumerate(MODES):
        print(f"| {k + 1} | {ft} | {lf[k] / ft - 1:+.1e} | {sd['f'][k] / ft - 1:+.1e} | {100 * zt:.2f} | "
              f"{lz[k] / zt - 1:+.1e} | {sd['z'][k] / zt - 1:+.1e} |")


if __name__ == "__main__":
    main()

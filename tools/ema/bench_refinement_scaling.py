#!/usr/bin/env python3
"""How the refinement's cost grows with lines and channels (issue 45.5): the four-mode long
record of bench_long_vs_sdypy.py (0.02-1000 Hz, zeta 0.2-1 %, 40 dB noise) made with 9, 18 and
36 responses and with 12 500, 25 000 and 50 000 lines over the same band, each run through
`lamdyn ema --uff ... --band-hz 20,1000 --json`; the step times (details.seconds, median of
REPEATS) of the refinement, the check, the standard deviations and the whole identification.

The refinement fits at most 4000 lines spread over the band plus the lines near each pole
(lsfd::RefineLines), so above that its cost grows with the lines near the poles only; the
check's context model and the final residues use the same lines and every line of the band.

Usage: python3 tools/ema/bench_refinement_scaling.py [REPEATS] [path/to/lamdyn]
Needs: the lamdyn binary (cargo build --release), the Python package (pip install ./python).
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np

import lamdyn

REPEATS = int(sys.argv[1]) if len(sys.argv) > 1 else 3
LAMDYN = sys.argv[2] if len(sys.argv) > 2 else "target/release/lamdyn"
MODES = [(51.5, 0.003), (142.2, 0.002), (278.7, 0.004), (460.4, 0.01)]


def record(n_out, n_lines, seed):
    f = np.linspace(1000.0 / n_lines, 1000.0, n_lines)
    s = 2j * np.pi * f
    rng = np.random.default_rng(seed)
    frf = np.zeros((n_out, n_lines), complex)
    for o in range(n_out):
        x = (o + 0.5) / n_out
        h = 0
        for r, (fr, z) in enumerate(MODES):
            w = 2 * np.pi * fr
            p = complex(-z * w, w * np.sqrt(1 - z * z))
            a = np.sin((r + 1) * np.pi * x + 0.3 * r) * np.sin((r + 1) * np.pi * 0.02 + 0.3 * r) / (2j * p.imag)
            h = h + a / (s - p) + np.conj(a) / (s - np.conj(p))
        h = h * s * s
        sd = np.sqrt(np.mean(np.abs(h) ** 2)) * 10 ** (-40 / 20) / np.sqrt(2)
        frf[o] = h + sd * (rng.standard_normal(n_lines) + 1j * rng.standard_normal(n_lines))
    return f, frf


def steps(path):
    runs = []
    for _ in range(REPEATS):
        p = subprocess.run([LAMDYN, "ema", "--uff", path, "--band-hz", "20,1000", "--json"],
                           capture_output=True, text=True)
        if p.returncode not in (0, 1):
            raise SystemExit(p.stderr[-2000:])
        runs.append(json.loads(p.stdout)["details"]["seconds"])
    return {k: statistics.median(r[k] for r in runs) for k in runs[0]}


def main():
    print(f"{os.cpu_count()} cores, median of {REPEATS}; seconds")
    print("| responses | lines | refinement | check | deviations | identification |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for n_out, n_lines in [(9, 50_000), (18, 50_000), (36, 50_000), (9, 12_500), (9, 25_000)]:
            f, frf = record(n_out, n_lines, 11)
            path = os.path.join(tmp, f"r{n_out}_{n_lines}.uff")
            lamdyn.write_uff(path, f, frf[:, None, :], [f"{o + 1}+Z" for o in range(n_out)], ["100+Z"],
                             binary=True)
            t = steps(path)
            ident = sum(v for k, v in t.items() if k != "read")
            print(f"| {n_out} | {n_lines} | {t['refinement']:.3f} | {t['check']:.3f} | "
                  f"{t['deviations']:.3f} | {ident:.3f} |")


if __name__ == "__main__":
    main()

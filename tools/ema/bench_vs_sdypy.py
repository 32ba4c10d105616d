#!/usr/bin/env python3
"""Side by side with sdypy-EMA's LSCF (pip install sdypy-EMA; tested with 0.31.0): the
stabilization diagram at orders 2-60 (sdypy: pol_order_high=30) on synthetic accelerance FRFs
with known poles and 40 dB noise, in two shapes: 243 FRFs x 321 lines and 9 FRFs x 51201 lines.

Timing: lamdyn `lscf_timing` (LSCF at every order + classification by frequency and damping,
as sdypy; a second figure adds mode vectors and the vector criterion) against sdypy
`Model.get_poles()`, each the median of REPEATS calls within one process (warm: thread pools,
FFT plans and imports set up), on this machine's cores.
Accuracy: for each true mode, the pole nearest to it at the highest order, from each tool's
diagram (the same LSCF estimator), and lamdyn's refined poles (`lamdyn ema --near-hz`).

Usage: python3 tools/ema/bench_vs_sdypy.py [REPEATS]
Needs: cargo build --release -p lamdyn -p lamdyn-ema --example lscf_timing
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import sdypy.EMA as EMA

REPEATS = int(sys.argv[1]) if len(sys.argv) > 1 else 5
LAMDYN = "target/release/lamdyn"
TIMING = "target/release/examples/lscf_timing"
MODES = [(12.0, 0.010), (30.0, 0.008), (30.6, 0.012), (55.0, 0.050), (80.0, 0.010), (110.0, 0.005)]


def synthetic(n_out, n_lines, f_max, seed):
    freq = np.linspace(0.0, f_max, n_lines)
    s = 2j * np.pi * freq
    x = (np.arange(n_out) + 0.5) / n_out
    rng = np.random.default_rng(seed)
    frf = np.zeros((n_out, n_lines), complex)
    for r, (f, z) in enumerate(MODES):
        w = 2 * np.pi * f
        p = -z * w + 1j * w * np.sqrt(1 - z * z)
        phi = np.sin((r + 1) * np.pi * x + 0.3 * r) + 0.2 * np.cos((r + 2) * x)
        a = (phi * phi[0])[:, None] / (2j * p.imag)
        frf += a / (s - p) + np.conj(a) / (s - np.conj(p))
    frf *= s * s
    rms = np.sqrt(np.mean(np.abs(frf) ** 2, axis=1, keepdims=True))
    sd = rms * 10 ** (-40 / 20) / np.sqrt(2)
    frf += sd * (rng.normal(size=frf.shape) + 1j * rng.normal(size=frf.shape))
    return freq, frf


def write_csv(tmp, freq, frf):
    with open(os.path.join(tmp, "channels.csv"), "w") as f:
        f.write("name,role,x_m,y_m,z_m,dx,dy,dz\n")
        for i in range(frf.shape[0]):
            f.write(f"{i + 1},response,{i},0,0,0,0,1\n")
        f.write("hammer,reference,0,0,0,0,0,1\n")
    with open(os.path.join(tmp, "frf.csv"), "w") as f:
        f.write("# quantity = accelerance\nf_hz," + ",".join(f"{i + 1}@hammer:re,{i + 1}@hammer:im" for i in range(frf.shape[0])) + "\n")
        for k in range(frf.shape[1]):
            f.write(f"{float(freq[k])!r}," + ",".join(f"{float(v.real)!r},{float(v.imag)!r}" for v in frf[:, k]) + "\n")


def nearest_errors(poles_hz, poles_xi):
    out = []
    for f, z in MODES:
        i = int(np.nanargmin(np.abs(poles_hz - f)))
        out.append((poles_hz[i] / f - 1, poles_xi[i] / z - 1))
    return out


def run_case(n_out, n_lines, f_max):
    freq, frf = synthetic(n_out, n_lines, f_max, 1)
    with tempfile.TemporaryDirectory() as tmp:
        write_csv(tmp, freq, frf)
        ch, fr = os.path.join(tmp, "channels.csv"), os.path.join(tmp, "frf.csv")
        # Warm timings on both sides: lamdyn's median over REPEATS calls in one process, sdypy's
        # over REPEATS calls of get_poles in this one.
        lam = [float(subprocess.run([TIMING, ch, fr, "5", str(f_max), str(REPEATS)], check=True, capture_output=True, text=True).stdout)]
        # The same with mode vectors and the vector criterion (sdypy has none).
        lam_v = float(subprocess.run([TIMING, ch, fr, "5", str(f_max), str(REPEATS), "vectors"], check=True, capture_output=True, text=True).stdout)
        sd = []
        for _ in range(REPEATS):
            m = EMA.Model(frf=frf, freq=freq, lower=5, upper=f_max, pol_order_high=30, frf_type="accelerance")
            t = time.perf_counter()
            m.get_poles(show_progress=False)
            sd.append(time.perf_counter() - t)
        # sdypy's diagram: the highest order's poles.
        last = np.asarray(m.all_poles[-1])
        last = last[(last.imag > 0)]
        sd_err = nearest_errors(np.abs(last) / (2 * np.pi), -last.real / np.abs(last))
        # lamdyn's diagram (no refinement) and refined, picked near the true frequencies.
        near = ",".join(str(f) for f, _ in MODES)
        res = {}
        for label, extra in (("diagram", ["--no-refine"]), ("refined", [])):
            out = subprocess.run([LAMDYN, "ema", "--channels", ch, "--frf", fr, "--band-hz", f"5,{f_max}", "--near-hz", near, "--window-hz", "0.3", "--json"] + extra, capture_output=True, text=True).stdout
            rows = json.loads(out)["rows"]
            res[label] = nearest_errors(np.array([r["freq_hz"] for r in rows]), np.array([r["damping_ratio"] for r in rows]))
    return statistics.median(lam), statistics.median(sd), sd_err, res, lam_v


def fmt(errs):
    return f"{max(abs(e[0]) for e in errs):.1e} / {max(abs(e[1]) for e in errs):.1e}"


print(f"{os.cpu_count()} cores; sdypy-EMA {getattr(EMA, '__version__', '?')}; median of {REPEATS}; orders 2-60 step 2; 6 modes, 40 dB noise")
print()
print("| data | lamdyn diagram | sdypy get_poles | ratio | lamdyn diagram + mode vectors | max freq / damping error: sdypy diagram | lamdyn diagram | lamdyn refined |")
print("|---|---|---|---|---|---|---|---|")
for n_out, n_lines, f_max in ((243, 321, 130.0), (9, 51201, 130.0)):
    tl, ts, sd_err, res, tv = run_case(n_out, n_lines, f_max)
    print(f"| {n_out} FRFs x {n_lines} lines | {tl * 1e3:.1f} ms | {ts * 1e3:.1f} ms | {ts / tl:.1f}x | {tv * 1e3:.1f} ms ({ts / tv:.1f}x) | {fmt(sd_err)} | {fmt(res['diagram'])} | {fmt(res['refined'])} |")

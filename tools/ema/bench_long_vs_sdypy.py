#!/usr/bin/env python3
"""Whole process on long records, lamdyn ema against sdypy-EMA (issues 17.2 and 45.5): 9
accelerance FRFs x 50 001 lines (0.02-1000 Hz), band 20-1000 Hz, orders 2-60 (sdypy:
pol_order_high = 30). Two records:

- `four`: four modes (51.5, 142.2, 278.7, 460.4 Hz; zeta 0.2-1 %), 40 dB complex noise.
- `beam`: a stand-in for a measured roving-hammer beam: a free-free Euler beam's first seven
  bending modes (51.5-1290 Hz, the seventh above the band; zeta 0.2-1 %), hammer at nine points,
  one accelerometer near an end, the rigid-body mass line, complex noise of 1 % of each curve's
  RMS.
- `beam8`: the same beam with two weakly excited modes more in the band, as a measured beam
  shows them (an out-of-plane bending mode at 323 Hz and a torsional one at 581 Hz, a tenth of
  the bending modes' residues): eight modes in the band, where the time of the pole fits grows
  faster than sdypy-EMA's.

- lamdyn: `lamdyn ema --uff long.uff --band-hz 20,1000 --json` (binary 58b, the automatic
  selection, the checked refinement, residues, sds, verdicts, CMIF), one process per run; its
  step times from the JSON (details.seconds). The same FRFs are written twice: as nine responses
  to one reference (a roving accelerometer, a shaker) and as one response to nine references (a
  roving hammer), and lamdyn runs on both.
- sdypy-EMA: `python3 -c ...` reading the same FRFs from .npy (its fastest input), LSCF,
  select_closest_poles at the true frequencies (it has no automatic selection), its LSFD
  (get_constants), one process per run (Python start-up and imports included, as a user pays).

Each is timed REPEATS times (wall clock of the process, the three in turn, each round starting
with the next one); the median is reported with the poles' errors against the truth. Needs: the
lamdyn binary (cargo build --release), the Python package (pip install ./python) to write the
UFF, numpy and sdypy-EMA.

Usage: python3 tools/ema/bench_long_vs_sdypy.py [REPEATS] [path/to/lamdyn] [four|beam|beam8|both|all]
(both: four and beam; all: the three)
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
WHICH = sys.argv[3] if len(sys.argv) > 3 else "both"
RECORDS = {"both": ["four", "beam"], "all": ["four", "beam", "beam8"]}.get(WHICH, [WHICH])
MODES = [(51.5, 0.003), (142.2, 0.002), (278.7, 0.004), (460.4, 0.01)]
BEAM_MODES = [(51.5, 0.004), (142.2, 0.002), (278.7, 0.003), (460.4, 0.006), (688.0, 0.005),
              (960.0, 0.008), (1290.0, 0.01)]
#: `beam8`'s two weakly excited modes (f Hz, zeta) and their residues' scale.
WEAK_MODES = [(323.0, 0.006), (581.0, 0.004)]
WEAK = 0.1
#: beta_r L of a free-free beam's bending modes.
BETA_L = [4.730, 7.853, 10.996, 14.137, 17.279, 20.420, 23.562]


def shape(r, o):
    x = (o + 0.5) / 24
    return np.sin((r + 1) * np.pi * x + 0.3 * r) + 0.2 * np.cos((r + 2) * x)


def lines():
    return np.arange(1, 50_002) * 0.02


def with_noise(h, fraction, rng):
    rms = np.sqrt(np.mean(np.abs(h) ** 2))
    sd = fraction * rms / np.sqrt(2)
    return h + sd * (rng.standard_normal(h.size) + 1j * rng.standard_normal(h.size))


def modal_sum(f, modes, residue):
    s = 2j * np.pi * f
    h = 0
    for r, (fr, z) in enumerate(modes):
        w = 2 * np.pi * fr
        p = complex(-z * w, w * np.sqrt(1 - z * z))
        a = residue(r) / (2j * p.imag)
        h = h + a / (s - p) + np.conj(a) / (s - np.conj(p))
    return h * s * s


def synthetic():
    f = lines()
    rng = np.random.default_rng(11)
    frf = np.zeros((9, f.size), complex)
    for o in range(9):
        h = modal_sum(f, MODES, lambda r: shape(r, 2 * o) * shape(r, 0))
        frf[o] = with_noise(h, 10 ** (-40 / 20), rng)
    return f, frf


def beam_shape(r, x):
    """Mode r of a free-free beam of unit length at x."""
    b = BETA_L[r]
    k = (np.cosh(b) - np.cos(b)) / (np.sinh(b) - np.sin(b))
    return np.cosh(b * x) + np.cos(b * x) - k * (np.sinh(b * x) + np.sin(b * x))


def beam(weak=0.0):
    f = lines()
    rng = np.random.default_rng(3)
    hammer, sensor = (np.arange(9) + 0.37) / 9.2, 0.03
    frf = np.zeros((9, f.size), complex)
    for o, x in enumerate(hammer):
        h = modal_sum(f, BEAM_MODES, lambda r: beam_shape(r, x) * beam_shape(r, sensor))
        if weak:
            h = h + modal_sum(
                f, WEAK_MODES, lambda r: weak * 1.3 * np.sin((r + 2) * np.pi * x + 0.4))
        # The rigid-body modes' mass line (translation and rotation, unit mass and length).
        h = h + (1 + 12 * (x - 0.5) * (sensor - 0.5))
        frf[o] = with_noise(h, 0.01, rng)
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


def rotated_runs(commands):
    """Each command REPEATS times, one after the other, each round starting with the next one:
    no program always runs right after the same other (a process started just after
    sdypy-EMA's may find the caches and free memory in another state). Returns the wall times
    and the outputs by name."""
    names = list(commands)
    times = {k: [] for k in names}
    outputs = {k: [] for k in names}
    for i in range(REPEATS):
        for k in names[i % len(names):] + names[:i % len(names)]:
            dt, out = timed(commands[k])
            times[k].append(dt)
            outputs[k].append(out)
    return times, outputs


def run(name, f, frf, modes):
    with tempfile.TemporaryDirectory() as tmp:
        uff = os.path.join(tmp, "long.uff")
        points = [f"{o + 1}+Z" for o in range(9)]
        lamdyn.write_uff(uff, f, frf[:, None, :], points, ["100+Z"], binary=True)
        roving = os.path.join(tmp, "roving.uff")
        lamdyn.write_uff(roving, f, frf[None, :, :], ["100+Z"], points, binary=True)
        fn, hn = os.path.join(tmp, "f.npy"), os.path.join(tmp, "frf.npy")
        np.save(fn, f)
        np.save(hn, frf)
        truth = [m[0] for m in modes]
        commands = {
            "nine": [LAMDYN, "ema", "--uff", uff, "--band-hz", "20,1000", "--json"],
            "roving": [LAMDYN, "ema", "--uff", roving, "--band-hz", "20,1000", "--json"],
            "sdypy": [sys.executable, "-c", SDYPY, fn, hn, json.dumps(truth)],
        }
        times, outputs = rotated_runs(commands)
        lam_t, rov_t, sd_t = times["nine"], times["roving"], times["sdypy"]
        lam, rov, sd = (json.loads(outputs[k][-1]) for k in ("nine", "roving", "sdypy"))
        steps = [json.loads(out)["details"]["seconds"] for out in outputs["roving"]]
    tl, tr, ts = (statistics.median(t) for t in (lam_t, rov_t, sd_t))
    print(f"{name}: 9 FRFs x {f.size} lines, band 20-1000 Hz, orders 2-60, {os.cpu_count()} cores, "
          f"median of {REPEATS}")
    print(f"whole process: lamdyn {tl:.3f} s (nine responses), {tr:.3f} s (roving hammer: one "
          f"response, nine references), sdypy-EMA {ts:.3f} s; ratio {ts / tl:.1f}x and {ts / tr:.1f}x")
    same = len(lam["rows"]) == len(rov["rows"]) and all(
        abs(a["freq_hz"] / b["freq_hz"] - 1) < 1e-9
        and abs(a["damping_ratio"] / b["damping_ratio"] - 1) < 1e-6
        for a, b in zip(lam["rows"], rov["rows"]))
    print(f"roving-hammer layout: the same poles as the nine responses' (1e-9 in f, 1e-6 in zeta): {same}")
    order = ["read", "diagram", "selection", "refinement", "check", "residues", "deviations", "modes"]
    print("lamdyn steps, roving hammer (median, s): " + ", ".join(
        f"{k} {statistics.median(s[k] for s in steps):.3f}" for k in order))
    print("| mode | true f [Hz] | lamdyn f err | sdypy f err | true zeta [%] | lamdyn zeta err | sdypy zeta err |")
    print("|---|---|---|---|---|---|---|")
    for k, (ft, zt) in enumerate(modes):
        lr = min(rov["rows"], key=lambda r: abs(r["freq_hz"] - ft))
        j = int(np.argmin([abs(x - ft) for x in sd["f"]]))
        print(f"| {k + 1} | {ft} | {lr['freq_hz'] / ft - 1:+.1e} | {sd['f'][j] / ft - 1:+.1e} | "
              f"{100 * zt:.2f} | {lr['damping_ratio'] / zt - 1:+.1e} | {sd['z'][j] / zt - 1:+.1e} |")


def main():
    for name in RECORDS:
        if name == "four":
            run("four modes, 40 dB", *synthetic(), MODES)
        elif name == "beam":
            run("beam stand-in, 1 % noise", *beam(), [m for m in BEAM_MODES if m[0] < 1000])
        else:
            modes = sorted([m for m in BEAM_MODES if m[0] < 1000] + WEAK_MODES)
            run("beam stand-in with two weak modes more, 1 % noise", *beam(WEAK), modes)
        print()


if __name__ == "__main__":
    main()

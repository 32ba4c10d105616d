#!/usr/bin/env python3
"""The measured plate sweep run by run: is each run the same plate?

For each of the four runs alone (crates/lamdyn-ema/tests/fixtures/plate-sweep, MIT) this prints
the six modes from three estimators that share nothing but the data:
- lamdyn: `lamdyn ema --time runI.csv --excitation sweep --quantity accelerance --band-hz 60,500`;
- sdypy-EMA (pip install sdypy-EMA; 0.31): its LSCF on the run's H = Y/X (numpy rfft of the whole
  record, mean removed: the run is one rectangular segment), orders 2-60, band 60-500 Hz, poles
  picked near the data README's 77, 126, 215, 263, 348, 450 Hz with select_closest_poles;
- a local fit: one complex pole pair plus a constant and a linear residual term, least squares
  (scipy) on the complex H over f +- 4 half-power bandwidths, started near the |H| peak;
and the noise floor of each run's H at the first mode: the force's and the acceleration's RMS
before the sweep starts and after the response has died out (the first and last 0.08 s), taken
through the 51 200-point transform against |X| there.

Usage: python3 tools/ema/plate_sweep_runs.py [path/to/lamdyn]  -> markdown tables (docs/ema.md)
"""
import json
import os
import subprocess
import sys
import warnings

import numpy as np
from scipy.optimize import least_squares

HERE = os.path.dirname(os.path.abspath(__file__))
DIR = os.path.join(HERE, "../../crates/lamdyn-ema/tests/fixtures/plate-sweep")
FS = 25600.0
#: The resonances and damping ratios the data's README gives (from the four runs' H1).
README_MODES = [(77.0, 0.018), (126.0, 0.015), (215.0, 0.022), (263.0, 0.027), (348.0, 0.030), (450.0, 0.031)]
#: Seconds at each end of a record with neither force nor response above the sensors' noise.
QUIET_S = 0.08


def run_path(i):
    return os.path.join(DIR, f"run{i}.csv")


def spectra(i):
    """Lines (Hz), force and acceleration transforms of run i (whole record, mean removed)."""
    r = np.loadtxt(run_path(i), delimiter=",", comments="#", skiprows=2)
    x, y = r[:, 1] - r[:, 1].mean(), r[:, 2] - r[:, 2].mean()
    return np.fft.rfftfreq(len(x), 1 / FS), np.fft.rfft(x), np.fft.rfft(y), (x, y)


def noise_of_h(spectra_of_run, f_hz):
    """Relative standard deviation of a run's H at f_hz from the sensors' noise (`spectra`'s
    output), and H there: a white noise of the quiet ends' RMS sigma gives |N(f)| = sigma sqrt(n)
    in an n-point transform."""
    f, X, Y, (x, y) = spectra_of_run
    q = int(QUIET_S * FS)
    n = len(x)
    sx, sy = (np.concatenate([s[:q], s[-q:]]).std() * np.sqrt(n) for s in (x, y))
    k = int(round(f_hz / (f[1] - f[0])))
    h = Y[k] / X[k]
    return np.hypot(sy / abs(Y[k]), sx / abs(X[k])), h


def local_pole(f, h, f0, zeta0):
    """One pole pair and a linear residual fitted to h near f0: (f_hz, zeta)."""
    m = (f > f0 * (1 - 4 * zeta0)) & (f < f0 * (1 + 4 * zeta0))
    w, hm = 2 * np.pi * f[m], h[m]

    def misfit(p):
        fr, z, ar, ai, br, bi, cr, ci = p
        wr = 2 * np.pi * fr
        lam = -z * wr + 1j * wr * np.sqrt(1 - z * z)
        r = ar + 1j * ai
        d = r / (1j * w - lam) + np.conj(r) / (1j * w - np.conj(lam)) + (br + 1j * bi) + (cr + 1j * ci) * (w / wr - 1) - hm
        return np.concatenate([d.real, d.imag])

    starts = [[fs, zeta0, 0, np.abs(hm).max() * zeta0 * 2 * np.pi * fs, 0, 0, 0, 0]
              for fs in np.linspace(f0 * (1 - zeta0), f0 * (1 + zeta0), 5)]
    best = min((least_squares(misfit, p0, x_scale="jac") for p0 in starts), key=lambda s: s.cost)
    return best.x[0], best.x[1]


def sdypy_poles(f, h):
    import sdypy.EMA as EMA

    keep = f <= 520
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = EMA.Model(frf=h[keep][None, :], freq=f[keep], lower=60, upper=500, pol_order_high=30,
                      frf_type="accelerance")
        m.get_poles(show_progress=False)
        m.select_closest_poles([f0 for f0, _ in README_MODES])
    return list(zip(m.nat_freq, m.nat_xi))


def lamdyn_poles(exe, runs):
    """lamdyn's modes of the given runs together. Exit 1 (a warning that makes the result doubtful,
    as run 3's regenerated FRF correlating below 0.9) still gives the modes."""
    args = [exe, "ema", "--channels", os.path.join(DIR, "channels.csv"), "--time", *map(run_path, runs),
            "--excitation", "sweep", "--quantity", "accelerance", "--band-hz", "60,500", "--json"]
    p = subprocess.run(args, capture_output=True, text=True, check=False)
    if p.returncode not in (0, 1):
        raise RuntimeError(f"lamdyn exited {p.returncode}: {p.stderr[-2000:]}")
    return [(r["freq_hz"], r["damping_ratio"]) for r in json.loads(p.stdout)["rows"]]


def nearest(poles, f0):
    return min(poles, key=lambda p: abs(p[0] - f0))


def per_run(exe):
    """{run: {"lamdyn": [...], "sdypy": [...], "local": [...], "noise": rel, "h": H, "force": |X|}}
    with one (f_hz, zeta) per README mode in each list, and the noise, H and |X| at the first
    mode's README frequency."""
    out = {}
    f1 = README_MODES[0][0]
    for i in (1, 2, 3, 4):
        spec = spectra(i)
        f, X, Y, _ = spec
        h = Y / X
        lam = lamdyn_poles(exe, [i])
        noise, h1 = noise_of_h(spec, f1)
        k = int(round(f1 / (f[1] - f[0])))
        out[i] = {
            "lamdyn": [nearest(lam, f0) for f0, _ in README_MODES],
            "sdypy": sdypy_poles(f, h),
            "local": [local_pole(f, h, f0, z0) for f0, z0 in README_MODES],
            "noise": noise,
            "h": h1,
            "force": abs(X[k]),
        }
    return out


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else "target/release/lamdyn"
    runs = per_run(exe)
    four = lamdyn_poles(exe, [1, 2, 3, 4])
    print("| mode | four runs (lamdyn) | run | lamdyn f [Hz] | sdypy f [Hz] | local fit f [Hz] | lamdyn vs four runs |")
    print("|---|---|---|---|---|---|---|")
    for m, (f0, _) in enumerate(README_MODES):
        f4 = nearest(four, f0)[0]
        for i, r in runs.items():
            a, b, c = (r[key][m][0] for key in ("lamdyn", "sdypy", "local"))
            print(f"| {m + 1} | {f4:.2f} | {i} | {a:.2f} | {b:.2f} | {c:.2f} | {100 * (a / f4 - 1):+.2f} % |")
    print()
    print("| run | force |X| at 77 Hz | noise of H at 77 Hz (rel.) | H at 77 Hz against run 1 |")
    print("|---|---|---|---|")
    for i, r in runs.items():
        print(f"| {i} | {r['force']:.0f} | {r['noise']:.1e} | {abs(r['h'] / runs[1]['h'] - 1):.2f} |")


if __name__ == "__main__":
    main()

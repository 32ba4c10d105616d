#!/usr/bin/env python3
"""Which pole of a stabilization diagram's column is nearest the truth on the damped virtual
plates of damped_bias.py (1 % noise): the column's top-order pole (lamdyn's `near_hz` pick), the
pole at the column's median frequency (lamdyn's automatic pick), the pole nearest the mean of the
column's frequencies over narrowing windows (sdypy-EMA 0.31's `select_closest_poles`), and
sdypy-EMA's own pole on the same FRFs. lamdyn's columns are its diagram's stable poles within the
`near_hz` window of each true frequency, from `ema()`'s `diagram`, without refinement.

Usage: python3 tools/ema/diagram_picks.py ZETA REFERENCES [SEEDS]   (REFERENCES: 1 or 3)
  -> per mode, RMS relative error over the seeds of f and zeta, in %, for each pick.
"""
import sys

import numpy as np

import damped_bias as bench

PICKS = ("top order", "median", "nearest mean", "sdypy")


def column_picks(column, target, window):
    """(f, zeta) of the median-frequency pole of `column` and of the pole nearest the mean
    frequency (windows narrowing from `window` around `target` to an eighth of it)."""
    by_f = sorted(column, key=lambda p: p["freq_hz"])
    centre = target
    for w in (window, window / 2, window / 4, window / 8):
        near = [p["freq_hz"] for p in column if abs(p["freq_hz"] - centre) < w]
        if near:
            centre = float(np.mean(near))
    mean_pick = min(column, key=lambda p: abs(p["freq_hz"] - centre))
    return [(p["freq_hz"], p["damping"]) for p in (by_f[len(by_f) // 2], mean_pick)]


def seed_errors(zeta, references, seed, targets, window):
    """Relative errors (picks, modes, [f, zeta]) of one noise seed; NaN where nothing was found."""
    f, h = bench.plate_frf(zeta, references, 0.01, np.random.default_rng(1000 + seed))
    r = bench.lamdyn_ema(f, h, targets, refine=False)
    stable = [p for p in r["diagram"] if p["stability"] != "New"]
    found = np.full((len(PICKS), len(targets), 2), np.nan)
    # The top-order pick is lamdyn's own (`near_hz`): the diagram pole it reports.
    found[0] = bench.nearest(r["diagram_freq_hz"], r["diagram_damping_ratio"], targets,
                             bench.windows(targets))
    for i, t in enumerate(targets):
        column = [p for p in stable if abs(p["freq_hz"] - t) <= window]
        if column:
            found[1:3, i] = column_picks(column, t, window)
    found[3] = bench.sdypy_poles(f, h, targets)
    return found / np.array([[t, zeta] for t in targets]) - 1


def main():
    zeta, references = float(sys.argv[1]), [0] if sys.argv[2] == "1" else [0, 5, 10]
    seeds = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    targets = [t[0] for t in bench.true_modes()]
    window = min(bench.windows(targets))
    e = np.array([seed_errors(zeta, references, s, targets, window) for s in range(seeds)])
    rms = 100 * np.sqrt(np.nanmean(e ** 2, axis=0))
    print(f"zeta {100 * zeta:g} %, {len(references)} reference(s), 1 % noise, {seeds} seeds: "
          "RMS error of f / zeta, %\n")
    print("| mode f [Hz] | " + " | ".join(PICKS) + " |")
    print("|---" * (1 + len(PICKS)) + "|")
    cell = lambda k, i: ("–" if np.isnan(rms[k, i, 0])  # noqa: E731
                         else f"{rms[k, i, 0]:.3f} / {rms[k, i, 1]:.2f}")
    for i, t in enumerate(targets):
        print(f"| {t:.1f} | " + " | ".join(cell(k, i) for k in range(len(PICKS))) + " |")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Which order of the stabilization diagram sdypy-EMA 0.31's `select_closest_poles` takes a mode's
pole from, and lamdyn's pole of that order beside it, with one LSCF over every curve in both
(`polymax=False`, sdypy's formulation), on the damped plate of damped_bias.py (1 % noise).

Usage: python3 tools/ema/sdypy_pick_order.py ZETA REFERENCES MODE_HZ [SEEDS]   (REFERENCES: 1 or 3)
  -> per seed: the order of sdypy's pick, its relative error in f, lamdyn's pole of that order,
     lamdyn's top-order pick (its `near_hz` pick) and the span of lamdyn's stable column (its
     lowest and highest order, and the range of its frequencies), in %.
"""
import sys

import numpy as np

import damped_bias as bench


def sdypy_pick(f, h, targets, mode_hz):
    """sdypy's pick nearest `mode_hz` (Hz) and the order of the diagram it is a pole of."""
    m = bench.sdypy_model(f, h, targets)
    picked = min(m.nat_freq, key=lambda x: abs(x - mode_hz))
    orders = [2 * (i + 1) for i, p in enumerate(m.all_poles)
              if np.any(np.abs(np.abs(np.asarray(p)) / (2 * np.pi) - picked) < 1e-9 * picked)]
    return picked, orders[0]


def main():
    zeta, references, mode_hz = float(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
    seeds = int(sys.argv[4]) if len(sys.argv) > 4 else 8
    refs = [0] if references == 1 else [0, 5, 10]
    targets = [t[0] for t in bench.true_modes()]
    truth = min(targets, key=lambda t: abs(t - mode_hz))
    win = bench.windows(targets)
    print(f"zeta {100 * zeta:g} %, {references} reference(s), 1 % noise, mode {truth:.3f} Hz: "
          "relative error of f, %\n")
    print("| seed | sdypy's order | sdypy | lamdyn, that order | lamdyn, top order "
          "| lamdyn's column: orders, f range |")
    print("|---|---|---|---|---|---|")
    for seed in range(1000, 1000 + seeds):
        f, h = bench.plate_frf(zeta, refs, 0.01, np.random.default_rng(seed))
        picked, order = sdypy_pick(f, h, targets, truth)
        r = bench.lamdyn_ema(f, h, targets, refine=False, polymax=False)
        column = [p for p in r["diagram"]
                  if p["stability"] != "New" and abs(p["freq_hz"] - truth) < min(win)]
        same = [p["freq_hz"] for p in column if p["order"] == order]
        span = (f"{min(p['order'] for p in column)}-{max(p['order'] for p in column)}, "
                f"{100 * (min(p['freq_hz'] for p in column) / truth - 1):+.4f} to "
                f"{100 * (max(p['freq_hz'] for p in column) / truth - 1):+.4f}")
        top = bench.nearest(r["freq_hz"], r["damping_ratio"], targets, win)[targets.index(truth), 0]
        err = lambda x: f"{100 * (x / truth - 1):+.4f}"  # noqa: E731
        at_order = err(same[0]) if same else "–"
        print(f"| {seed} | {order} | {err(picked)} | {at_order} | {err(top)} | {span} |")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The mode shapes lamdyn gives on the virtual damped plates of damped_bias.py (modal damping
0.1 %, 2 %, 8 % and 15 %, one and three references, noise-free or 1 % noise, the same seeds),
against the plate's true shapes, which are real.

Per case and mode, over the seeds where a pole was found near the mode (the tables' picks):
the lowest MAC between lamdyn's shape (reference 0) and the true shape, the lowest MPC, and
in how many seeds the pole was judged a smear (kept out of the chain). The true shapes are
sin(m pi x) sin(n pi y / 0.8) at the response points: any imaginary part of an identified
shape is error.

Usage: python3 tools/ema/damped_shapes.py [--seeds N] [--levels 0.001,0.02,...]
  -> markdown (docs/ema.md, method step 5).
"""
import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import damped_bias as db  # noqa: E402


def true_shapes():
    """Per mode in the band: its real shape at the response points."""
    return [np.array([np.sin(m * np.pi * x) * np.sin(n * np.pi * y / 0.8) for (x, y) in db.POINTS])
            for (_, m, n) in db.true_modes()]


def mac(a, b):
    """|a^H b|^2 / (|a|^2 |b|^2)."""
    return abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)


def case(zeta, references, snr_rel, seeds):
    """Per mode: (lowest MAC, lowest MPC, smears, seeds found)."""
    targets = [t[0] for t in db.true_modes()]
    win = db.windows(targets)
    truth = true_shapes()
    macs = [[] for _ in targets]
    mpcs = [[] for _ in targets]
    smears = [0] * len(targets)
    for s in range(seeds):
        f, h = db.plate_frf(zeta, references, snr_rel, np.random.default_rng(1000 + s))
        r = db.lamdyn_ema(f, h, targets, refine=True, poles="checked")
        for i, k in enumerate(db.nearest_index(r["freq_hz"], targets, win)):
            if k is None:
                continue
            shape = np.asarray(r["shapes"][k])
            macs[i].append(mac(shape, truth[i]))
            mpcs[i].append(r["mpc"][k])
            smears[i] += r["verdict"][k] == "smear"
    return [(min(m) if m else np.nan, min(p) if p else np.nan, n, len(m))
            for m, p, n in zip(macs, mpcs, smears)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--levels", default="0.001,0.02,0.08,0.15")
    args = ap.parse_args()
    targets = [t[0] for t in db.true_modes()]
    print("Lowest MAC with the true shape / lowest MPC / smears, over the seeds that found the "
          "mode (count in brackets):\n")
    print("| ζ | refs | noise | " + " | ".join(f"{t:.1f} Hz" for t in targets) + " |")
    print("|---|---|---|" + "---|" * len(targets))
    for zeta in (float(v) for v in args.levels.split(",")):
        for refs in ([0], [0, 5, 10]):
            for snr in (0.0, 0.01):
                seeds = 1 if snr == 0 else args.seeds
                rows = case(zeta, refs, snr, seeds)
                cells = [f"{m:.3f} / {p:.2f} / {n} ({c})" if c else "–" for m, p, n, c in rows]
                noise = "none" if snr == 0 else "1 %"
                print(f"| {100 * zeta:g} % | {len(refs)} | {noise} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()

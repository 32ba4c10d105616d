#!/usr/bin/env python3
"""How the band's upper edge moves lamdyn's poles on the damped virtual plate of damped_bias.py
(1 % noise): the diagram's, the refined and the checked pole, per mode, for each band given.

The modes just above the band (222.5 and 230.6 Hz) reach into it at 8 % damping, and the
refinement models what lies above the band with a real upper residual term (docs/ema.md,
"Damped poles"), so where the band ends decides how much of their flank the poles take up.
Every true mode inside a band is picked (`near_hz`), so a band reaching past 200 Hz also
identifies the modes above 200 Hz it holds; the table shows the nine modes of 20-200 Hz.

Usage: python3 tools/ema/refinement_band_edge.py ZETA REFERENCES SEEDS LO,HI [LO,HI ...]
  (REFERENCES: 1 or 3)
  -> per band and estimator, the RMS relative error over the seeds of f and zeta per mode, %.
"""
import sys

import numpy as np

import damped_bias as bench
import lamdyn

ESTIMATORS = (("diagram", False, "checked"), ("refined", True, "refined"),
              ("checked", True, "checked"))


def band_errors(f, h, band, targets, truth):
    """Relative errors (estimators, modes of `targets`, [f, zeta]) on one seed's FRFs over
    `band`, every true mode inside the band picked."""
    picked = [m[0] for m in bench.MODES if band[0] <= m[0] <= band[1]]
    win = bench.windows(targets)
    out = []
    for _, refine, poles in ESTIMATORS:
        try:
            r = bench.lamdyn_ema(f, h, picked, band, refine=refine, poles=poles)
            found = bench.nearest(r["freq_hz"], r["damping_ratio"], targets, win)
        except lamdyn.LamdynError:
            found = np.full((len(targets), 2), np.nan)
        out.append(found / truth - 1)
    return np.array(out)


def main():
    zeta, references, seeds = float(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    bands = [tuple(float(v) for v in b.split(",")) for b in sys.argv[4:]]
    refs = [0] if references == 1 else [0, 5, 10]
    targets = [t[0] for t in bench.true_modes()]
    truth = np.array([[t, zeta] for t in targets])
    errors = {b: [] for b in bands}
    for seed in range(seeds):
        f, h = bench.plate_frf(zeta, refs, 0.01, np.random.default_rng(1000 + seed))
        for b in bands:
            errors[b].append(band_errors(f, h, b, targets, truth))
    print(f"zeta {100 * zeta:g} %, {references} reference(s), 1 % noise, {seeds} seeds: "
          "RMS error of f / zeta, %\n")
    print("| band [Hz] | estimator | " + " | ".join(f"{t:.1f}" for t in targets) + " |")
    print("|---|---|" + "---|" * len(targets))
    for b in bands:
        rms = 100 * bench.rms(np.array(errors[b]))  # estimators x modes x [f, zeta]
        for k, (name, _, _) in enumerate(ESTIMATORS):
            cells = " | ".join("–" if np.isnan(x) else f"{x:.3f} / {y:.2f}" for x, y in rms[k])
            print(f"| {b[0]:g}–{b[1]:g} | {name} | {cells} |")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Seed by seed on one damped virtual plate of damped_bias.py: what lamdyn's diagram, its
refinement and its final pole make of the chosen modes, and why the final pole is the one it is.

For each seed (the FRFs of damped_bias.py's seed 1000 + s) and each chosen mode, lamdyn's pole
picked near it as the tables pick it (`damped_bias.lamdyn_ema`, the default checked poles), one
line: the relative errors, %, of f and zeta of the diagram's pole, the refined pole (as the
refinement left it, taken or not) and the final pole; the final pole's sd relative to the true
value; the refinement's outcome (`taken`, `not better`, `left its column`, `beside a lost pole`)
and the verdict. With --warnings the run's warnings that name a pole within 10 % of a chosen
mode follow each seed. docs/ema.md, "The losses left, looked into", quotes these lines.

Usage: python3 tools/ema/damped_seeds.py ZETA REFS [--seeds N] [--modes 102.5,105.6]
                                         [--noise 0.01] [--warnings]
  ZETA the modal damping ratio (0.08 for 8 %), REFS 1 or 3 references.
"""
import argparse
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import damped_bias as db  # noqa: E402

#: damped_bias.py's reference sets by their count.
REFERENCES = {len(refs): refs for refs in db.REFERENCE_SETS}


def pole_lines(r, k, target, zeta):
    """The fields of one mode's line: errors (f, zeta) of the diagram, refined and final pole, %,
    the final pole's sd relative to the truth, %, the outcome and the verdict."""
    def errors(f, z):
        return 100 * (f / target - 1), 100 * (z / zeta - 1)
    diagram = errors(r["diagram_freq_hz"][k], r["diagram_damping_ratio"][k])
    refined = errors(r["refined_freq_hz"][k], r["refined_damping_ratio"][k])
    final = errors(r["freq_hz"][k], r["damping_ratio"][k])
    sd = (100 * r["freq_sd_hz"][k] / target, 100 * r["damping_sd"][k] / zeta)
    return diagram, refined, final, sd, r["refinement"][k], r["verdict"][k]


def named_hz(warning):
    """The frequencies a warning names ("... at 105.470 Hz ..."), Hz."""
    return [float(x) for x in re.findall(r"(\d+(?:\.\d+)?) Hz", warning)]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("zeta", type=float)
    p.add_argument("refs", type=int, choices=sorted(REFERENCES))
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--modes", default="", help="true frequencies, Hz, to one decimal (all)")
    p.add_argument("--noise", type=float, default=0.01, help="relative to each curve's RMS")
    p.add_argument("--warnings", action="store_true")
    a = p.parse_args()
    targets = [t[0] for t in db.true_modes()]
    chosen = {float(m) for m in a.modes.split(",") if m} or {round(t, 1) for t in targets}
    win = db.windows(targets)
    print("seed  mode Hz | f %: diagram refined final | zeta %: diagram refined final | "
          "sd f / zeta % | refinement | verdict")
    for s in range(a.seeds):
        rng = np.random.default_rng(1000 + s)
        f, h = db.plate_frf(a.zeta, REFERENCES[a.refs], a.noise, rng)
        r = db.lamdyn_ema(f, h, targets, refine=True, poles="checked")
        for i, k in enumerate(db.nearest_index(r["freq_hz"], targets, win)):
            if round(targets[i], 1) not in chosen:
                continue
            if k is None:
                print(f"{s:4d} {targets[i]:8.1f} | no pole found")
                continue
            d, rf, fin, sd, outcome, verdict = pole_lines(r, k, targets[i], a.zeta)
            print(f"{s:4d} {targets[i]:8.1f} | {d[0]:+.3f} {rf[0]:+.3f} {fin[0]:+.3f} | "
                  f"{d[1]:+.2f} {rf[1]:+.2f} {fin[1]:+.2f} | {sd[0]:.3f} / {sd[1]:.3f} | "
                  f"{outcome} | {verdict}")
        if a.warnings:
            for w in r["warnings"]:
                if any(abs(f_hz / m - 1) <= 0.1 for f_hz in named_hz(w) for m in chosen):
                    print(f"     warning: {w}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""What a mode the diagram lacks does to its neighbours' poles, with one reference (docs/ema.md,
"One reference: the modes left out"), on damped_bias.py's plate (8 % damping, the driving point
as the only reference, 1 % noise).

The free-residue fit is rank_one_fit.py's model with one reference (each mode's residues over
the twelve responses free; the same block terms; scipy's Levenberg-Marquardt). Per seed:
- the diagram's poles (lamdyn, orders 2-60, picked near each true mode as damped_bias.py picks
  them): which modes it lacks;
- the fit from the diagram's poles of the modes it found, and from the true poles of those same
  modes: 105.6 Hz's zeta and the sum of squares of each (equal: one minimum, not two);
- the fit from all nine true poles, and the drop of the sum of squares that the modes the diagram
  lacks bring, over the residual variance of the nine-mode fit (against the 99 % point of chi^2
  with 26 degrees of freedom, a mode's pole and twelve complex residues: 45.6).

Usage: python3 tools/ema/missing_modes.py [--seeds N] [--zeta 0.08] [--noise 0.01]
"""
import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parent))
import damped_bias as db  # noqa: E402
import rank_one_fit as rf  # noqa: E402


def fitted(f, h, start):
    """The free-residue fit from `start` (rows f Hz, zeta): its poles and its sum of squares."""
    band = (f >= db.BAND_HZ[0]) & (f <= db.BAND_HZ[1])
    wn, z = 2 * np.pi * start[:, 0], start[:, 1]
    poles = -z * wn + 1j * wn * np.sqrt(1 - z * z)
    model = rf.RankOneModel(2 * np.pi * f[band], h[:, :, band], poles)
    sol = least_squares(model.residual, model.x0, method="lm", x_scale="jac")
    return model.unpack(sol.x)[0], float(np.sum(sol.fun ** 2)), sol.fun.size


def zeta_at(poles, freqs, target):
    """The damping ratio (%) of the pole fitted for the mode at `target` Hz."""
    k = int(np.argmin(np.abs(np.asarray(freqs) - target)))
    return -100 * poles[k].real / abs(poles[k])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--zeta", type=float, default=0.08)
    ap.add_argument("--noise", type=float, default=0.01)
    a = ap.parse_args()
    targets = np.array([t[0] for t in db.true_modes()])
    truth = np.array([[t, a.zeta] for t in targets])
    print("| seed | modes the diagram lacks, Hz | 105.6 Hz zeta, % (cost): from the diagram | "
          "from the truth, same modes | all nine modes | drop / variance |")
    print("|---|---|---|---|---|---|")
    for seed in range(a.seeds):
        f, h = db.plate_frf(a.zeta, [0], a.noise, np.random.default_rng(1000 + seed))
        diagram = db.lamdyn_poles(f, h, list(targets), refine=False)
        found = ~np.isnan(diagram[:, 0])
        p_d, c_d, _ = fitted(f, h, diagram[found])
        p_t, c_t, _ = fitted(f, h, truth[found])
        p_all, c_all, rows = fitted(f, h, truth)
        variance = c_all / rows
        print(f"| {1000 + seed} | {', '.join(f'{t:.1f}' for t in targets[~found])} | "
              f"{zeta_at(p_d, targets[found], 105.6):.3f} ({c_d:.6g}) | "
              f"{zeta_at(p_t, targets[found], 105.6):.3f} ({c_t:.6g}) | "
              f"{zeta_at(p_all, targets, 105.6):.3f} | {(c_d - c_all) / variance:.0f} |")


if __name__ == "__main__":
    main()

"""What biases the pole refinement on damped modes: its model of the modes outside the band.

The refinement (crates/lamdyn-ema/src/lsfd.rs) fits the poles by variable projection with a real
lower residual LR/(iw)^2 and a real upper residual UR beside them. This script repeats that fit
in numpy on the damped plate of tools/ema/damped_bias.py (nine modes in 20-200 Hz, eight above it
up to 400 Hz, accelerance) with three models of what lies outside the band:

  residuals      LR/(iw)^2 + UR, as lamdyn (reproduces lamdyn's refined poles);
  + (iw)^2       a second-order upper residual UR2 (iw)^2 beside them;
  + true poles   the eight true poles above the band as fixed partial fractions (their residues
                 free): what a perfect model of the outside would give, an upper bound;
  + free pole    the residuals and one more pole, free, started above the band (1.15 times its
                 upper edge, zeta 10 %) and not reported: a pseudo-mode for the modes above.

Each starts from the true poles moved by +0.05 % in frequency and +2 % in decay rate (or from
--start, e.g. a diagram's poles), and prints the RMS relative error of f and zeta per mode, %
(with --start, each true mode against the fitted pole nearest it, and the fitted poles).

    python3 tools/ema/refinement_out_of_band.py --zeta 0.02 --references 1
    python3 tools/ema/refinement_out_of_band.py --zeta 0.08 --noise 0.01 \
        --start 25.628:.078,55.613:.079,72.459:.078,102.437:.074,105.378:.068,151.913:.081,178.173:.081,180.193:.054
"""
import argparse
import os
import sys

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, os.path.dirname(__file__))
import damped_bias as db  # noqa: E402

MODELS = ("residuals", "+ (iw)^2", "+ true poles", "+ free pole")


def pair_columns(s, lam):
    """The two real-coefficient columns of the conjugate pair (lam, conj lam)."""
    a, b = 1 / (s - lam), 1 / (s - np.conj(lam))
    return [a + b, 1j * (a - b)]


def refine(f, curves, start, model, outside):
    """The poles fitted by variable projection on the accelerance `curves` (curves x lines)."""
    s = 2j * np.pi * f
    b = np.vstack([curves.T.real, curves.T.imag])

    def basis(poles):
        cols = [c for lam in poles for c in pair_columns(s, lam)]
        cols += [1 / s ** 2, np.ones_like(s)]
        if model == 1:
            cols.append(s ** 2)
        if model == 2:
            cols += [c for lam in outside for c in pair_columns(s, lam)]
        a = np.array(cols).T * (s ** 2)[:, None]
        a = np.vstack([a.real, a.imag])
        return a / np.linalg.norm(a, axis=0)

    def residual(u):
        a = basis(-np.exp(u[0::2]) + 1j * u[1::2])
        x, *_ = np.linalg.lstsq(a, b, rcond=None)
        return (b - a @ x).ravel()

    fitted = list(start)
    if model == 3:
        fitted.append(pole(1.15 * f[-1], 0.1))
    u0 = np.ravel([[np.log(-p.real), p.imag] for p in fitted])
    u = least_squares(residual, u0, x_scale="jac", xtol=1e-12, ftol=1e-14).x
    return (-np.exp(u[0::2]) + 1j * u[1::2])[:len(start)]


def pole(f_hz, zeta):
    w = 2 * np.pi * f_hz
    return -zeta * w + 1j * w * np.sqrt(1 - zeta ** 2)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--zeta", type=float, default=0.02)
    ap.add_argument("--references", type=int, choices=(1, 3), default=1)
    ap.add_argument("--noise", type=float, default=0.0, help="relative to each curve's RMS")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--start", help="the poles to start from, f_hz:zeta,... (default: the truth moved)")
    a = ap.parse_args()
    refs = [0] if a.references == 1 else [0, 5, 10]
    targets = np.array([t[0] for t in db.true_modes()])
    outside = [pole(t[0], a.zeta) for t in db.MODES if t[0] > db.BAND_HZ[1]]
    start = np.array([pole(t, a.zeta) for t in targets])
    start = start.real * 1.02 + 1j * start.imag * 1.0005
    if a.start:
        start = np.array([pole(*map(float, p.split(":"))) for p in a.start.split(",")])
    errors = {m: [] for m in range(len(MODELS))}
    for seed in range(a.seeds):
        f, h = db.plate_frf(a.zeta, refs, a.noise, np.random.default_rng(1000 + seed))
        band = (f >= db.BAND_HZ[0]) & (f <= db.BAND_HZ[1])
        curves = h.reshape(-1, h.shape[2])[:, band]
        for m in errors:
            p = refine(f[band], curves, start, m, outside)
            if a.start:
                fitted = np.abs(p) / (2 * np.pi)
                print(f"{MODELS[m]}: f {np.round(fitted, 2)} Hz, zeta {np.round(-100 * p.real / np.abs(p), 2)} %")
                p = p[[int(np.argmin(np.abs(fitted - t))) for t in targets]]
            errors[m].append(np.c_[np.abs(p) / (2 * np.pi) / targets - 1, -p.real / np.abs(p) / a.zeta - 1])
    print(f"zeta {100 * a.zeta:g} %, {a.references} reference(s), noise {100 * a.noise:g} %, "
          f"{a.seeds} seed(s): RMS error of f / zeta, %\n")
    print("| model | " + " | ".join(f"{t:.1f} Hz" for t in targets) + " |")
    print("|---" * (1 + len(targets)) + "|")
    for m, name in enumerate(MODELS):
        e = 100 * np.sqrt(np.mean(np.array(errors[m]) ** 2, axis=0))
        print(f"| {name} | " + " | ".join(f"{e[i, 0]:.3f} / {e[i, 1]:.2f}" for i in range(len(targets))) + " |")


if __name__ == "__main__":
    main()

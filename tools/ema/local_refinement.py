#!/usr/bin/env python3
"""A prototype, not in lamdyn: each pole refined alone in the local model of its shape
(crates/lamdyn-ema/src/local_residues.rs: within +-k zeta f of the pole, the band fit's terms
for the pole and for the poles whose half-power band reaches the window, those held where
lamdyn put them, and a complex quadratic), by least squares on the pole's decay rate and
damped frequency with every coefficient eliminated. Started at lamdyn's checked pole, on the
virtual damped plates of damped_bias.py.

Usage: python3 tools/ema/local_refinement.py ZETA REFS SEEDS [K]
  (REFS as 0 or 0,5,10; K the window in half-power half-widths, default 2)
  -> RMS relative error of f / zeta per mode, %, of lamdyn's checked pole and of the local one.

Measured 2026-12-02 (docs/ema.md, "Damped poles"): at 8 % with one reference, ten seeds, the
local pole is better in zeta and worse in f at most modes, whatever K.
"""
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parent))
import damped_bias as db  # noqa: E402


def natural(p):
    """(f in Hz, zeta) of pole p (rad/s)."""
    return abs(p) / (2 * np.pi), -p.real / abs(p)


def local_pole(f, curves, poles, k, half_widths):
    """Pole k of `poles` refined alone in its local model on `curves` (rows, accelerance)."""
    f0, z0 = natural(poles[k])
    hw = max(half_widths * z0 * f0, 20 * (f[1] - f[0]))
    sel = (f >= db.BAND_HZ[0]) & (f <= db.BAND_HZ[1]) & (np.abs(f - f0) <= hw)
    s = 2j * np.pi * f[sel]
    near = [q for j, q in enumerate(poles)
            if j != k and abs(natural(q)[0] - f0) <= hw + 2 * natural(q)[1] * natural(q)[0]]
    x = (f[sel] - f0) / hw
    quad = np.array([x ** d for d in range(3)]).T.astype(complex)
    quad = np.vstack([np.hstack([quad.real, -quad.imag]), np.hstack([quad.imag, quad.real])])
    data = curves[:, sel]
    b = np.vstack([data.real.T, data.imag.T])

    def residual(u):
        p = -np.exp(u[0]) + 1j * u[1]
        cols = []
        for q in [p] + near:
            a1, a2 = 1 / (s - q), 1 / (s - np.conj(q))
            cols += [s * s * (a1 + a2), s * s * 1j * (a1 - a2)]
        a = np.array(cols).T
        q_, _ = np.linalg.qr(np.hstack([np.vstack([a.real, a.imag]), quad]))
        return (b - q_ @ (q_.T @ b)).ravel()

    p0 = poles[k]
    u = least_squares(residual, [np.log(-p0.real), p0.imag],
                      x_scale=[0.1, abs(p0.imag) * 1e-3]).x
    return -np.exp(u[0]) + 1j * u[1]


def main():
    zeta, refs = float(sys.argv[1]), [int(v) for v in sys.argv[2].split(",")]
    seeds, half_widths = int(sys.argv[3]), float(sys.argv[4]) if len(sys.argv) > 4 else 2.0
    targets = [t[0] for t in db.true_modes()]
    win = db.windows(targets)
    errors = {"checked": [], "local": []}
    for seed in range(seeds):
        f, h = db.plate_frf(zeta, refs, 0.01, np.random.default_rng(1000 + seed))
        r = db.lamdyn_ema(f, h, targets, refine=True, poles="checked")
        poles = list(r["poles"])
        checked, local = (np.full((len(targets), 2), np.nan) for _ in range(2))
        for i, k in enumerate(db.nearest_index(r["freq_hz"], targets, win)):
            if k is None:
                continue
            fl, zl = natural(local_pole(f, h.reshape(-1, h.shape[-1]), poles, k, half_widths))
            checked[i] = r["freq_hz"][k] / targets[i] - 1, r["damping_ratio"][k] / zeta - 1
            local[i] = fl / targets[i] - 1, zl / zeta - 1
        errors["checked"].append(checked)
        errors["local"].append(local)
    for name, e in errors.items():
        e = np.array(e)
        found = np.isfinite(e[..., 0]).any(axis=0)
        rms = np.full((len(targets), 2), np.nan)
        rms[found] = 100 * np.sqrt(np.nanmean(e[:, found] ** 2, axis=0))
        print(f"{name:8s}", " ".join(f"{t:.1f}: {a:.3f} / {b:.2f}" for t, (a, b) in zip(targets, rms)))


if __name__ == "__main__":
    main()

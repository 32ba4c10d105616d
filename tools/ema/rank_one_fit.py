#!/usr/bin/env python3
"""A prototype (numpy + scipy, not in lamdyn) of the joint pole fit with rank-one residues, on
damped_bias.py's plate with several references: beside lamdyn's diagram pole, lamdyn's final
(checked) pole and sdypy-EMA's, on the same FRFs.

lamdyn's refinement gives each curve its own residue per mode (free residues). The modal model's
residues of mode r over responses o and references j are psi_or L_rj: one shape, one
participation vector. The prototype fits that model to the band's lines (20-200 Hz): the poles
and the participation factors L (L_r at one reference held at 1) are the nonlinear unknowns
(scipy's Levenberg-Marquardt, finite-difference Jacobian), the shapes psi are eliminated by
least squares per response (variable projection: every response's curves share one basis,
their rows stacked over the references), beside per curve an upper and a lower residual term and
the four pseudo-modes above the band of lamdyn's joint fit (1.1, 1.3, 1.7, 2.3 times 200 Hz,
zeta 10 %, residues free). It starts from lamdyn's diagram poles (picked as damped_bias.py picks
them) and from L of each mode's free residues at those poles (their first singular vector). A
mode the diagram did not find is left out of the fit (no put-back rule as lamdyn's).

With --lamdyn the rank-one fit is lamdyn's own (`lamdyn ema --poles rank-one`, module
`rank_one`: the same model, an exact gradient, the poles that left their columns put back).

Usage: python3 tools/ema/rank_one_fit.py ZETA [--seeds N] [--noise 0.01] [--no-sdypy] [--lamdyn]
  -> per mode, RMS error of f / zeta over the seeds, %, of the diagram's pole, lamdyn's final
     pole, sdypy-EMA's and the rank-one fit's (over every seed, and over the seeds where the
     diagram found every mode) (docs/ema.md, "What the free residues cost at a close pair").
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parent))
import damped_bias as db  # noqa: E402

REFERENCES = [0, 5, 10]
PSEUDO_RATIOS = (1.1, 1.3, 1.7, 2.3)
PSEUDO_DAMPING = 0.1


def pair(g, gb, c):
    """The two real-coefficient columns of a complex coefficient c on g / its conjugate gb."""
    return [c * g + np.conj(c) * gb, 1j * (c * g - np.conj(c) * gb)]


def block_columns(w):
    """Each reference's own columns, curve by curve: the pseudo-modes' (free residues) and the
    residual terms (a constant and -w^2, accelerance's lower and upper residuals)."""
    s, q = 1j * w, -w * w
    cols = []
    for r in PSEUDO_RATIOS:
        wp = 2 * np.pi * r * db.BAND_HZ[1]
        p = complex(-PSEUDO_DAMPING * wp, wp * np.sqrt(1 - PSEUDO_DAMPING ** 2))
        cols += pair(q / (s - p), q / (s - np.conj(p)), 1.0)
    return cols + [np.ones_like(w) + 0j, q + 0j]


def basis(w, poles, participation, refs):
    """The real basis shared by every response: rows (reference, line, re/im), per mode two
    columns psi's re and im with L_rj on reference j's rows, then each reference's block."""
    s, q, nk = 1j * w, -w * w, len(w)
    cols = []
    for p, L in zip(poles, participation):
        g, gb = q / (s - p), q / (s - np.conj(p))
        per_ref = [pair(g, gb, L[j]) for j in range(refs)]
        cols += [np.concatenate([c[m] for c in per_ref]) for m in (0, 1)]
    for c in block_columns(w):
        for j in range(refs):
            z = np.zeros(refs * nk, complex)
            z[j * nk:(j + 1) * nk] = c
            cols.append(z)
    a = np.array(cols).T
    return np.vstack([a.real, a.imag])


def stacked(h):
    """The curves (responses x references x lines) as the basis's rows, one column per
    response."""
    no, nj, nk = h.shape
    b = h.transpose(1, 2, 0).reshape(nj * nk, no)
    return np.vstack([b.real, b.imag])


def start_participation(w, h, poles):
    """Each mode's L from its free residues at `poles` (first right singular vector), scaled to
    1 at the reference where it is largest; and that reference."""
    no, nj, nk = h.shape
    s, q = 1j * w, -w * w
    cols = []
    for p in poles:
        cols += pair(q / (s - p), q / (s - np.conj(p)), 1.0)
    a = np.array(cols + block_columns(w)).T
    c = h.reshape(no * nj, nk).T
    x, *_ = np.linalg.lstsq(np.vstack([a.real, a.imag]), np.vstack([c.real, c.imag]),
                            rcond=None)
    participation, pivots = [], []
    for r in range(len(poles)):
        residues = (x[2 * r] + 1j * x[2 * r + 1]).reshape(no, nj)
        v = np.linalg.svd(residues)[2][0]
        k = int(np.argmax(np.abs(v)))
        participation.append(v / v[k])
        pivots.append(k)
    return np.array(participation), pivots


class RankOneModel:
    """The fit's unknowns: ln(-Re l), Im l of each pole, then re, im of L_rj for every j but
    the mode's pivot."""

    def __init__(self, w, h, poles):
        self.w, self.b = w, stacked(h)
        self.refs = h.shape[1]
        participation, self.pivots = start_participation(w, h, poles)
        free = [participation[r, j] for r in range(len(poles)) for j in self.free_refs(r)]
        self.x0 = np.concatenate([np.log(-poles.real), poles.imag,
                                  np.array([[c.real, c.imag] for c in free]).ravel()])
        self.n = len(poles)

    def free_refs(self, r):
        return [j for j in range(self.refs) if j != self.pivots[r]]

    def unpack(self, x):
        poles = -np.exp(x[:self.n]) + 1j * x[self.n:2 * self.n]
        participation = np.ones((self.n, self.refs), complex)
        rest = x[2 * self.n:].reshape(-1, 2)
        k = 0
        for r in range(self.n):
            for j in self.free_refs(r):
                participation[r, j] = rest[k, 0] + 1j * rest[k, 1]
                k += 1
        return poles, participation

    def residual(self, x):
        a = basis(self.w, *self.unpack(x), self.refs)
        coef, *_ = np.linalg.lstsq(a, self.b, rcond=None)
        return (self.b - a @ coef).ravel()

    def fit(self):
        sol = least_squares(self.residual, self.x0, method="lm", x_scale="jac")
        return self.unpack(sol.x)[0]


def rank_one_poles(f, h, diagram):
    """The rank-one fit's (f Hz, zeta) per target from the diagram's (NaN rows left out)."""
    band = (f >= db.BAND_HZ[0]) & (f <= db.BAND_HZ[1])
    found = ~np.isnan(diagram[:, 0])
    wn, z = 2 * np.pi * diagram[found, 0], diagram[found, 1]
    poles = RankOneModel(2 * np.pi * f[band], h[:, :, band],
                         -z * wn + 1j * wn * np.sqrt(1 - z * z)).fit()
    out = np.full_like(diagram, np.nan)
    out[found, 0] = np.abs(poles) / (2 * np.pi)
    out[found, 1] = -poles.real / np.abs(poles)
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("zeta", type=float)
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--noise", type=float, default=0.01)
    p.add_argument("--no-sdypy", action="store_true")
    p.add_argument("--lamdyn", action="store_true", help="lamdyn's --poles rank-one")
    a = p.parse_args()
    targets = [t[0] for t in db.true_modes()]
    truth = np.array([[t, a.zeta] for t in targets])
    errors = {"diagram": [], "final": []}
    if not a.no_sdypy:
        errors["sdypy"] = []
    errors["rank-one"] = []
    complete, seconds = [], []
    for seed in range(a.seeds):
        f, h = db.plate_frf(a.zeta, REFERENCES, a.noise, np.random.default_rng(1000 + seed))
        diagram = db.lamdyn_poles(f, h, targets, refine=False)
        errors["diagram"].append(diagram / truth - 1)
        errors["final"].append(db.lamdyn_poles(f, h, targets, refine=True) / truth - 1)
        if not a.no_sdypy:
            errors["sdypy"].append(db.sdypy_poles(f, h, targets) / truth - 1)
        t0 = time.perf_counter()
        if a.lamdyn:
            fitted = db.lamdyn_poles(f, h, targets, refine=True, estimator="rank-one")
        else:
            fitted = rank_one_poles(f, h, diagram)
        errors["rank-one"].append(fitted / truth - 1)
        seconds.append(time.perf_counter() - t0)
        complete.append(not np.isnan(diagram[:, 0]).any())
    complete = np.array(complete)
    print(f"zeta {100 * a.zeta:g} %, three references, noise {100 * a.noise:g} %, "
          f"{a.seeds} seeds ({complete.sum()} with every mode in the diagram); the rank-one "
          f"fit {np.median(seconds):.1f} s per seed (median): RMS error f / zeta, %")
    names = list(errors) + ["rank-one, complete seeds"]
    print("| mode | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for i, t in enumerate(targets):
        cells = []
        for name in names:
            e = np.array(errors[name.split(",")[0]])[:, i, :]
            if name.endswith("seeds"):
                e = e[complete]
            if not len(e):
                cells.append("–")
                continue
            r = 100 * np.sqrt(np.nanmean(e ** 2, axis=0))
            cells.append(f"{r[0]:.4f} / {r[1]:.3f}")
        print(f"| {t:.1f} Hz | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()

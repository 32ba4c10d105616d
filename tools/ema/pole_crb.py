#!/usr/bin/env python3
"""The Cramer-Rao bound of each in-band mode's f and zeta on damped_bias.py's plate: the least
standard deviation any unbiased estimator can reach with the FRFs' noise (complex Gaussian, 1 %
of each curve's RMS over the band, white over the lines), for two models of the residues:

- free: each curve's residue of each mode its own complex unknown (lamdyn's refinement, LSFD);
- rank-one: the residues of mode r over responses o and references j are psi_or L_rj (the modal
  model; with one reference the two are the same).

Every one of the seventeen modes up to 400 Hz enters with its pole and residues unknown (the
modes above the band are what a fit does not know either); the lines are the band's
(20-200 Hz, 0.1 Hz). The bound is the inverse of the Fisher information 2 Re(D^H D) / sigma^2,
D the model's derivatives with respect to the real parameters, mapped to f = |lambda| / 2 pi and
zeta = -Re lambda / |lambda| by their gradients.

Usage: python3 tools/ema/pole_crb.py ZETA REFS [--noise 0.01]
  -> per mode: the bound's sd of f and zeta relative to the truth, %, for both models
     (docs/ema.md, "What the free residues cost at a close pair").
"""
import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import damped_bias as db  # noqa: E402

REFERENCES = {len(refs): refs for refs in db.REFERENCE_SETS}


def plate(zeta, refs):
    """Lines (rad/s) in the band, each mode's pole and residue matrix (responses x references)
    of the accelerance model -w^2 sum_r [A_r/(iw - l_r) + A_r*/(iw - l_r*)], and the true
    curves (responses x references x lines)."""
    f = np.arange(1, int(db.F_MAX_HZ / db.DF_HZ) + 1) * db.DF_HZ
    w = 2 * np.pi * f[(f >= db.BAND_HZ[0]) & (f <= db.BAND_HZ[1])]
    phi = np.array([[np.sin(m * np.pi * x) * np.sin(n * np.pi * y / 0.8) for (x, y) in db.POINTS]
                    for (_, m, n) in db.MODES])
    poles, residues = [], []
    for r, (fr, _, _) in enumerate(db.MODES):
        wr = 2 * np.pi * fr
        lam = complex(-zeta * wr, wr * np.sqrt(1 - zeta * zeta))
        poles.append(lam)
        residues.append(np.outer(phi[r], phi[r, refs]) / (2j * lam.imag))
    s = 1j * w
    h = sum(-w * w * (a[:, :, None] / (s - p) + np.conj(a)[:, :, None] / (s - np.conj(p)))
            for p, a in zip(poles, residues))
    return w, poles, residues, h


def derivative_columns(w, pole, residue, rank_one):
    """The model's derivatives (responses x references x lines each) with respect to the mode's
    real parameters: Re and Im of the pole, then its residues' (free: each curve's re, im;
    rank-one: psi_o's re, im, then L_j's for j >= 1, L_0 = its true value held)."""
    s, g = 1j * w, -w * w
    t1, t2 = 1 / (s - pole), 1 / (s - np.conj(pole))
    no, nj = residue.shape

    def term(a):
        """The curves of residues `a` (responses x references) at this pole."""
        return g * (a[:, :, None] * t1 + np.conj(a)[:, :, None] * t2)

    cols = [g * (residue[:, :, None] * t1 ** 2 + np.conj(residue)[:, :, None] * t2 ** 2),
            g * (1j * residue[:, :, None] * t1 ** 2 - 1j * np.conj(residue)[:, :, None] * t2 ** 2)]
    unit = [1.0, 1j]
    if not rank_one:
        for o in range(no):
            for j in range(nj):
                for u in unit:
                    a = np.zeros((no, nj), complex)
                    a[o, j] = u
                    cols.append(term(a))
        return cols
    k = int(np.argmax(np.abs(residue).sum(axis=0)))
    participation = residue[k] / residue[k, 0]
    psi = residue[:, 0]
    for o in range(no):
        for u in unit:
            a = np.zeros((no, nj), complex)
            a[o] = u * participation
            cols.append(term(a))
    for j in range(1, nj):
        for u in unit:
            a = np.zeros((no, nj), complex)
            a[:, j] = u * psi
            cols.append(term(a))
    return cols


def bound(zeta, refs, noise, rank_one):
    """(f Hz, sd f %, sd zeta %) of each in-band mode."""
    w, poles, residues, h = plate(zeta, refs)
    sigma = noise * np.sqrt(np.mean(np.abs(h) ** 2, axis=2))[:, :, None]
    cols, first = [], []
    for p, a in zip(poles, residues):
        first.append(len(cols))
        cols += derivative_columns(w, p, a, rank_one)
    d = np.array([(c / sigma).ravel() for c in cols]).T
    cov = np.linalg.inv(2 * np.real(d.conj().T @ d))
    out = []
    for (fr, _, _), p, i in zip(db.MODES, poles, first):
        if not db.BAND_HZ[0] <= fr <= db.BAND_HZ[1]:
            continue
        mag = abs(p)
        grad_f = np.array([p.real, p.imag]) / mag / (2 * np.pi)
        grad_z = np.array([-1 / mag + p.real ** 2 / mag ** 3, p.real * p.imag / mag ** 3])
        c = cov[i:i + 2, i:i + 2]
        var_f, var_z = grad_f @ c @ grad_f, grad_z @ c @ grad_z
        out.append((fr, 100 * np.sqrt(var_f) / (mag / (2 * np.pi)) if var_f > 0 else np.nan,
                    100 * np.sqrt(var_z) / (-p.real / mag) if var_z > 0 else np.nan))
    return out


def cell(sd_f, sd_zeta):
    """A table cell; a variance the inverse's rounding made negative (the information matrix
    nearly singular: the model cannot tell the parameters apart) as "singular"."""
    if not np.isfinite(sd_f) or not np.isfinite(sd_zeta):
        return "singular"
    return f"{sd_f:.4f} / {sd_zeta:.3f}"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("zeta", type=float)
    p.add_argument("refs", type=int, choices=sorted(REFERENCES))
    p.add_argument("--noise", type=float, default=0.01)
    a = p.parse_args()
    rows = {m: bound(a.zeta, REFERENCES[a.refs], a.noise, m) for m in (False, True)}
    print(f"zeta {100 * a.zeta:g} %, {a.refs} reference(s), noise {100 * a.noise:g} %: "
          "Cramer-Rao sd of f / zeta, % of the truth")
    print("| residues | " + " | ".join(f"{f:.1f} Hz" for f, _, _ in rows[False]) + " |")
    print("|---" * (len(rows[False]) + 1) + "|")
    for m, name in ((False, "free"), (True, "rank-one")):
        print(f"| {name} | " + " | ".join(cell(sf, sz) for _, sf, sz in rows[m]) + " |")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""A maximum-likelihood (output-error) step on the LSCF common-denominator model, measured on
damped_bias.py's virtual plate: a candidate for issue 45's unbiased damped poles, kept here with
its measurements (docs/ema.md, "Damped poles": tried) until it is the estimator or is dropped.

Independent of lamdyn: the LSCF (real coefficients, monic denominator of order n in
z = e^{iωΔt}, Δt = 1/(2 f_max of the band), the numerators eliminated: the reduced normal
equations), then Levenberg-Marquardt on the denominator's n free coefficients for the output
error Σ_o Σ_k |B_o(z_k)/A(z_k) − H_o(k)|², the numerators eliminated by variable projection
(Golub & Pereyra 1973; Kaufman's Jacobian). White noise of equal variance on every line makes
that the maximum-likelihood estimate of the order-n model. Each true mode takes the root
nearest its frequency (so the table compares the estimators, not a selection).

Usage: python3 tools/ema/ml_denominator.py ZETA REFS NOISE SEEDS [ORDER]
  e.g. `python3 tools/ema/ml_denominator.py 0.02 1 0.01 20` -> per mode the RMS error of f and
  zeta (%) over the seeds: LSCF at the order, its generalised total-least-squares variant
  (GTLS: the same normal equations, another constraint), and the ML step from the LSCF.
"""
import os
import sys

import numpy as np
import scipy.linalg

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import damped_bias as db  # noqa: E402


def lscf(f, h, band, order):
    """The LSCF denominator (coefficients a_0..a_n, a_n = 1) on the band's lines, the lines' z,
    the band's curves and Δt."""
    m = (f >= band[0]) & (f <= band[1])
    f, h = f[m], h[:, m]
    dt = 1 / (2 * band[1])
    z = np.exp(1j * 2 * np.pi * f * dt)
    phi = z[:, None] ** np.arange(order + 1)[None, :]
    r = np.real(phi.conj().T @ phi)
    r_inv = np.linalg.inv(r)
    normal = np.zeros((order + 1, order + 1))
    for curve in h:
        s = -np.real(phi.conj().T @ (curve[:, None] * phi))
        t = np.real(phi.conj().T @ ((np.abs(curve) ** 2)[:, None] * phi))
        normal += t - s.T @ r_inv @ s
    a = np.append(np.linalg.solve(normal[:-1, :-1], -normal[:-1, -1]), 1.0)
    return a, z, h, dt, (normal, r)


def gtls(normal, r):
    """The generalised total-least-squares denominator: the a minimising aᵀ M a / aᵀ R a (M the
    reduced normal matrix, R = Re ΦᴴΦ, the noise's metric for white noise of equal variance on
    every line; Verboven 2002, sec. 5.3), scaled to a_n = 1. Where the noise is that white,
    the LS estimate's noise bias (E M = M_true + σ² R, less the numerators' share) is removed."""
    _, vectors = scipy.linalg.eigh(normal, r)
    return vectors[:, 0] / vectors[-1, 0]


def poles(a, dt):
    """The stable poles with positive frequency of denominator a, rad/s."""
    lam = np.log(np.roots(a[::-1]).astype(complex)) / dt
    return lam[(lam.imag > 0) & (lam.real < 0)]


def projected_residual(a, phi, data):
    """The output error with the numerators eliminated: data (2L x curves, real and imaginary
    rows) less its projection on the columns z^j / A; the projector's Q and A."""
    den = phi @ a
    w = phi / den[:, None]
    q, _ = np.linalg.qr(np.vstack([w.real, w.imag]))
    return data - q @ (q.T @ data), q, den


def output_error_step(a0, z, h, iterations=30):
    """Levenberg-Marquardt on a_0..a_{n-1} (a_n = 1) for the output error (module docs)."""
    n = len(a0) - 1
    lines = len(z)
    phi = z[:, None] ** np.arange(n + 1)[None, :]
    data = np.vstack([h.T.real, h.T.imag])
    a, mu = a0.copy(), 1e-3
    r, q, den = projected_residual(a, phi, data)
    cost = np.sum(r ** 2)
    for _ in range(iterations):
        model = data - r
        model = model[:lines] + 1j * model[lines:]
        cols = []
        for j in range(n):
            d = (phi[:, j] / den)[:, None] * model
            d = np.vstack([d.real, d.imag])
            cols.append((d - q @ (q.T @ d)).T.reshape(-1))
        jac = np.array(cols).T
        jtj, g = jac.T @ jac, jac.T @ r.T.reshape(-1)
        while True:
            step = np.linalg.solve(jtj + mu * np.diag(np.diag(jtj)), -g)
            trial = a.copy()
            trial[:n] += step
            r_t, q_t, den_t = projected_residual(trial, phi, data)
            c_t = np.sum(r_t ** 2)
            if c_t < cost:
                gain = (cost - c_t) / cost
                a, r, q, den, cost, mu = trial, r_t, q_t, den_t, c_t, max(mu / 3, 1e-9)
                break
            mu *= 4
            if mu > 1e8:
                return a
        if gain < 1e-9:
            break
    return a


def nearest(lam, targets):
    f, zeta = np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam)
    return np.array([(f[k], zeta[k]) for k in (np.argmin(np.abs(f - t)) for t in targets)])


def main():
    zeta, refs, noise, seeds = float(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
    order = int(sys.argv[5]) if len(sys.argv) > 5 else 60
    references = [0] if refs == 1 else [0, 5, 10]
    targets = [t[0] for t in db.true_modes()]
    truth = np.array([[t, zeta] for t in targets])
    errors = {"lscf": [], "gtls": [], "ml": []}
    for seed in range(seeds):
        f, h = db.plate_frf(zeta, references, noise, np.random.default_rng(1000 + seed))
        curves = h.reshape(-1, h.shape[2])
        curves = curves / np.max(np.abs(curves))
        a, z, band_curves, dt, normal = lscf(f, curves, db.BAND_HZ, order)
        errors["lscf"].append(nearest(poles(a, dt), targets) / truth - 1)
        errors["gtls"].append(nearest(poles(gtls(*normal), dt), targets) / truth - 1)
        errors["ml"].append(nearest(poles(output_error_step(a, z, band_curves), dt), targets) / truth - 1)
    rms = {k: 100 * np.sqrt(np.mean(np.array(v) ** 2, axis=0)) for k, v in errors.items()}
    print(f"zeta {100 * zeta:g} %, {refs} reference(s), noise {100 * noise:g} %, {seeds} seed(s), order {order}")
    print("| mode f [Hz] | LSCF f / zeta RMS error [%] | GTLS f / zeta RMS error [%] "
          "| ML step f / zeta RMS error [%] |")
    print("|---|---|---|---|")
    for i, t in enumerate(targets):
        print(f"| {t:.1f} | " + " | ".join(f"{rms[k][i, 0]:.4f} / {rms[k][i, 1]:.3f}" for k in errors) + " |")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""A prototype: each pole refitted on the lines around it with the rest of the band's model held,
beside a local background. Measured against lamdyn's diagram and checked pole (and sdypy-EMA
0.31 with --sdypy) on the damped plate of damped_bias.py. lamdyn does this since 2026-12-03 for
the poles that stand alone, with the pseudo-modes of --pseudo-outside and a real two-term
background (crates/lamdyn-ema/src/local_refit.rs); the prototype also refits groups of
overlapping poles and compares the outside models.

The prototype, per seed:
1. lamdyn's final (checked) poles (every selected mode, `damped_bias.lamdyn_ema`);
2. one LSFD over the whole band 20-200 Hz with those poles (each pole pair's residue per curve,
   complex) and two residual terms per curve (omega^2 and a constant, complex); with
   --oracle-outside the plate's true modes above the band too (what the LSCF's outside roots
   stand for in lamdyn, given exactly), with --pseudo-outside four pseudo-modes above the band
   instead (at 1.1, 1.3, 1.7 and 2.3 times its upper edge, zeta 10 %, residues free: no
   knowledge of the part);
3. the poles grouped where their half-power bands (f +- zeta f, times GROUP) overlap; for each
   group, the lines within K half-power half-widths of its poles (+ 20 lines), the model of every
   other pole and the residual terms (step 2's residues) subtracted from the data, and the
   group's poles refitted there by variable projection (scipy least_squares, 'lm'): the group's
   residues and a complex constant and slope per curve free.

It asks whether the refinement's bias with one reference (docs/ema.md, "Where the noise that
biases the refined pole comes from": the far lines' noise reaching the mode through the joint
fit's poorly determined parameters) goes when those parameters are held and only a smooth local
background is left free. Its numbers are in docs/ema.md beside that paragraph.

Usage: python3 tools/ema/local_refit.py ZETA REFERENCES [SEEDS] [K] [GROUP] [--sdypy]
                                        [--noise-free] [--oracle-outside | --pseudo-outside]
  (REFERENCES: 1 or 3; SEEDS 20, K 5, GROUP 1 by default)
  -> per mode, RMS of the relative error of f / zeta in % over the seeds for lamdyn's diagram
     and checked pole, the prototype ("local") and with --sdypy sdypy-EMA's; then the modes and
     quantities where the prototype's RMS error is larger than each other estimator's.
"""
import sys
import warnings

import numpy as np
from scipy.optimize import least_squares

import damped_bias as bench


def pole_columns(w, pole):
    """The accelerance basis of one pole pair (lambda, conj lambda) with a real and an
    imaginary residue part: two complex columns on the lines w (rad/s)."""
    a, c = 1 / (1j * w - pole), 1 / (1j * w - np.conj(pole))
    return [-w * w * (a + c), -w * w * 1j * (a - c)]


def residual_columns(w):
    """The band's residual terms, complex per curve: omega^2 (modes above) and 1 (below)."""
    return [w * w, 1j * w * w, np.ones_like(w), 1j * np.ones_like(w)]


def solve(columns, curves):
    """Real least squares of every curve (rows of `curves`) on the complex `columns`, real and
    imaginary parts stacked: (coefficients, columns x curves; residual, 2 lines x curves)."""
    a = np.array(columns).T
    ar = np.vstack([a.real, a.imag])
    br = np.vstack([curves.T.real, curves.T.imag])
    scale = np.linalg.norm(ar, axis=0)
    x, *_ = np.linalg.lstsq(ar / scale, br, rcond=None)
    return x / scale[:, None], br - (ar / scale) @ x


def band_model(f, curves, poles):
    """Step 2: the LSFD coefficients of `poles` (and OUTSIDE's) and the residual terms over the
    band."""
    poles = np.concatenate([poles, OUTSIDE])
    band = (f >= bench.BAND_HZ[0]) & (f <= bench.BAND_HZ[1])
    w = 2 * np.pi * f[band]
    columns = [c for p in poles for c in pole_columns(w, p)] + residual_columns(w)
    return solve(columns, curves[:, band])[0]


def model_without(w, poles, coefficients, group):
    """The band model (step 2) on the lines w without the poles of `group`, per curve."""
    poles = np.concatenate([poles, OUTSIDE])
    a = np.array([c for p in poles for c in pole_columns(w, p)] + residual_columns(w)).T
    keep = np.ones(a.shape[1], bool)
    for g in group:
        keep[2 * g:2 * g + 2] = False
    return (a[:, keep] @ coefficients[keep]).T


#: Poles held in the band model beside the identified ones: none, with --oracle-outside the
#: plate's true modes above the band (an oracle: what the LSCF's outside roots stand for), with
#: --pseudo-outside pseudo-modes above the band at these multiples of its upper edge and ζ.
OUTSIDE = np.zeros(0, complex)
PSEUDO_RATIOS, PSEUDO_ZETA = (1.1, 1.3, 1.7, 2.3), 0.1


def groups(poles, reach):
    """Indices of the poles grouped where their bands f +- reach zeta f overlap."""
    f = np.abs(poles) / (2 * np.pi)
    z = -poles.real / np.abs(poles)
    order = np.argsort(f)
    out, current = [], [order[0]]
    for a in order[1:]:
        if f[a] * (1 - reach * z[a]) <= max(f[c] * (1 + reach * z[c]) for c in current):
            current.append(a)
        else:
            out.append(current)
            current = [a]
    return out + [current]


def refit_group(f, curves, poles, coefficients, group, k):
    """Step 3 for one group: its poles refitted on their lines, the rest held."""
    fg = np.abs(poles[group]) / (2 * np.pi)
    zg = -poles[group].real / np.abs(poles[group])
    margin = 20 * (f[1] - f[0])
    lo = max(np.min(fg * (1 - k * zg)) - margin, bench.BAND_HZ[0])
    hi = min(np.max(fg * (1 + k * zg)) + margin, bench.BAND_HZ[1])
    lines = (f >= lo) & (f <= hi)
    if lines.sum() < 2 * len(group) + 2:
        raise ValueError("fewer lines than unknowns")
    w = 2 * np.pi * f[lines]
    data = curves[:, lines] - model_without(w, poles, coefficients, group)
    w0 = w.mean()
    background = [np.ones_like(w), 1j * np.ones_like(w), (w - w0) / w0, 1j * (w - w0) / w0]

    def to_poles(u):
        return np.array([-np.exp(u[2 * i]) + 1j * u[2 * i + 1] for i in range(len(group))])

    def residual(u):
        columns = [c for p in to_poles(u) for c in pole_columns(w, p)] + background
        return solve(columns, data)[1].ravel()

    u0 = np.concatenate([[np.log(-poles[g].real), poles[g].imag] for g in group])
    scale = np.concatenate([[1e-2, 1e-4 * abs(poles[g].imag)] for g in group])
    return to_poles(least_squares(residual, u0, x_scale=scale, method="lm").x)


def local_poles(f, curves, poles, k, reach):
    """Steps 2 and 3: every pole refitted in its group; a group whose fit fails keeps NaN."""
    coefficients = band_model(f, curves, poles)
    out = np.full(len(poles), np.nan + 0j)
    for group in groups(poles, reach):
        try:
            out[group] = refit_group(f, curves, poles, coefficients, group, k)
        except (ValueError, np.linalg.LinAlgError):
            pass
    return out


def poles_of(freq_hz, zeta):
    """lambda = -zeta w + i w sqrt(1 - zeta^2) of each (f, zeta)."""
    w, z = 2 * np.pi * np.asarray(freq_hz), np.asarray(zeta)
    return -z * w + 1j * w * np.sqrt(1 - z * z)


def seed_poles(zeta, refs, snr, seed, k, reach, with_sdypy):
    """(f, zeta) per estimator and mode for one seed, NaN where none was found."""
    targets = [t[0] for t in bench.true_modes()]
    f, h = bench.plate_frf(zeta, refs, snr, np.random.default_rng(seed))
    names = ["diagram", "checked", "local"] + (["sdypy"] if with_sdypy else [])
    out = {n: np.full((len(targets), 2), np.nan) for n in names}
    try:
        r = bench.lamdyn_ema(f, h, targets)
    except Exception:  # noqa: BLE001 - a failed identification finds nothing
        r = None
    if r is not None:
        curves = h.reshape(-1, h.shape[2])
        local = local_poles(f, curves, np.asarray(r["poles"]),
                            k, reach)
        picks = bench.nearest_index(r.freq_hz, targets, bench.windows(targets))
        for i, j in enumerate(picks):
            if j is not None:
                out["diagram"][i] = r.diagram_freq_hz[j], r.diagram_damping_ratio[j]
                out["checked"][i] = r.freq_hz[j], r.damping_ratio[j]
                out["local"][i] = abs(local[j]) / (2 * np.pi), -local[j].real / abs(local[j])
    if with_sdypy:
        out["sdypy"] = bench.sdypy_poles(f, h, targets)
    return out


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    zeta, references = float(args[0]), int(args[1])
    seeds = int(args[2]) if len(args) > 2 else 20
    k = float(args[3]) if len(args) > 3 else 5.0
    reach = float(args[4]) if len(args) > 4 else 1.0
    snr = 0.0 if "--noise-free" in sys.argv else 0.01
    seeds = 1 if snr == 0 else seeds
    refs = [0] if references == 1 else [0, 5, 10]
    global OUTSIDE
    if "--oracle-outside" in sys.argv:
        above = [t[0] for t in bench.MODES if t[0] > bench.BAND_HZ[1]]
        OUTSIDE = poles_of(above, np.full(len(above), zeta))
    elif "--pseudo-outside" in sys.argv:
        above = [r * bench.BAND_HZ[1] for r in PSEUDO_RATIOS]
        OUTSIDE = poles_of(above, np.full(len(above), PSEUDO_ZETA))
    targets = [t[0] for t in bench.true_modes()]
    truth = np.array([[t, zeta] for t in targets])
    errors = {}
    for seed in range(1000, 1000 + seeds):
        for name, p in seed_poles(zeta, refs, snr, seed, k, reach, "--sdypy" in sys.argv).items():
            errors.setdefault(name, []).append(100 * (p / truth - 1))
    errors = {n: np.array(e) for n, e in errors.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rms = {n: np.sqrt(np.nanmean(e ** 2, axis=0)) for n, e in errors.items()}
    print(f"zeta {100 * zeta:g} %, {references} reference(s), "
          f"{'noise-free' if snr == 0 else f'1 % noise, {seeds} seeds'}, K {k:g}, GROUP "
          f"{reach:g}: RMS error of f / zeta, %\n")
    print("| mode, Hz | " + " | ".join(rms) + " |")
    print("|---|" + "---|" * len(rms))
    for i, t in enumerate(targets):
        print(f"| {t:.1f} | " + " | ".join(f"{r[i, 0]:.4f} / {r[i, 1]:.2f}" for r in rms.values())
              + " |")
    worse = [f"{t:.1f} Hz {q} vs {n}: {rms['local'][i, c]:.4f} against {rms[n][i, c]:.4f}"
             for n in rms if n != "local" for i, t in enumerate(targets)
             for c, q in enumerate(("f", "zeta")) if rms["local"][i, c] > rms[n][i, c]]
    print("\nWhere the prototype's RMS error is larger:\n" + "\n".join(worse or ["nowhere"]))


if __name__ == "__main__":
    main()

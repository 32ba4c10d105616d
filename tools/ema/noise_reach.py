#!/usr/bin/env python3
"""Where the noise that biases a pole comes from: the damped plate of damped_bias.py with its
noise on every line, only on the lines near one mode, or only on the others; lamdyn's diagram,
refined and checked pole of that mode and sdypy-EMA 0.31's, bias / standard deviation / RMS of
the relative error of f and zeta over the seeds.

The noise of each seed is drawn once on every line (damped_bias.plate_frf with 1 % noise) and
then masked, so the three rows of one seed share their noise where they have it.

Usage: python3 tools/ema/noise_reach.py ZETA REFERENCES MODE_HZ [SEEDS] [HALF_WIDTH_HZ]
         [--no-sdypy]
  (REFERENCES: 1 or 3; "near" is within HALF_WIDTH_HZ of the mode, by default 20 Hz)
  -> a markdown table: per noise mask and estimator, bias / sd / RMS of f and zeta, in %.
"""
import sys

import numpy as np

import damped_bias as bench

ESTIMATORS = ("diagram", "refined", "checked", "sdypy")


def clean_and_noise(zeta, refs, seed):
    """The lines, the plate's noise-free FRFs and the 1 % noise of `seed` on them."""
    f, clean = bench.plate_frf(zeta, refs, 0.0, np.random.default_rng(seed))
    _, noisy = bench.plate_frf(zeta, refs, 0.01, np.random.default_rng(seed))
    return f, clean, noisy - clean


def poles_of(f, h, targets, truth, with_sdypy):
    """(f, zeta) of each estimator's pole nearest `truth`, NaN where none was found or the
    identification failed."""
    win = bench.windows(targets)
    i = targets.index(truth)
    out = dict.fromkeys(ESTIMATORS, (np.nan, np.nan))
    try:
        r = bench.lamdyn_ema(f, h, targets)
    except Exception:  # noqa: BLE001 - a failed identification finds nothing
        r = None
    k = bench.nearest_index(r.freq_hz, targets, win)[i] if r is not None else None
    if k is not None:
        out["diagram"] = r.diagram_freq_hz[k], r.diagram_damping_ratio[k]
        out["refined"] = r.refined_freq_hz[k], r.refined_damping_ratio[k]
        out["checked"] = r.freq_hz[k], r.damping_ratio[k]
    if with_sdypy:
        out["sdypy"] = tuple(bench.sdypy_poles(f, h, targets)[i])
    return out


def summary(errors):
    """'bias / sd / RMS' of relative errors in %, over the seeds that found the mode."""
    e = np.asarray(errors)
    e = e[np.isfinite(e)]
    if len(e) < 2:
        return "–"
    return f"{e.mean():+.4f} / {e.std(ddof=1):.4f} / {np.sqrt(np.mean(e ** 2)):.4f}"


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    with_sdypy = "--no-sdypy" not in sys.argv
    zeta, references, mode_hz = float(args[0]), int(args[1]), float(args[2])
    seeds = int(args[3]) if len(args) > 3 else 20
    half = float(args[4]) if len(args) > 4 else 20.0
    refs = [0] if references == 1 else [0, 5, 10]
    targets = [t[0] for t in bench.true_modes()]
    truth = min(targets, key=lambda t: abs(t - mode_hz))
    masks = {
        "every line": lambda f: np.ones_like(f),
        f"within {half:g} Hz only": lambda f: (np.abs(f - truth) <= half).astype(float),
        f"beyond {half:g} Hz only": lambda f: (np.abs(f - truth) > half).astype(float),
    }
    print(f"zeta {100 * zeta:g} %, {references} reference(s), 1 % noise, mode {truth:.3f} Hz, "
          f"{seeds} seeds: bias / sd / RMS of the relative error, %\n")
    print("| noise | estimator | f | zeta |")
    print("|---|---|---|---|")
    errors = {name: {e: ([], []) for e in ESTIMATORS} for name in masks}
    for seed in range(1000, 1000 + seeds):
        f, clean, noise = clean_and_noise(zeta, refs, seed)
        for name, mask in masks.items():
            found = poles_of(f, clean + noise * mask(f), targets, truth, with_sdypy)
            for e, (fe, ze) in found.items():
                errors[name][e][0].append(100 * (fe / truth - 1))
                errors[name][e][1].append(100 * (ze / zeta - 1))
    for name in masks:
        for e in ESTIMATORS if with_sdypy else ESTIMATORS[:3]:
            f_err, z_err = errors[name][e]
            print(f"| {name} | {e} | {summary(f_err)} | {summary(z_err)} |")


if __name__ == "__main__":
    main()

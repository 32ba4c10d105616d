#!/usr/bin/env python3
"""Coverage of lamdyn's per-pole 95 % intervals, f +- 1.96 sd(f) and zeta +- 1.96 sd(zeta), on
the virtual damped plates of damped_bias.py (modal damping 0.1 %, 2 %, 8 % and 15 %, one and
three references, 1 % noise, the same seeds), with lamdyn's default poles (the rank-one fit, with
one reference checked in the LSCF model's context; `--poles` another) picked near each true
mode as the tables there pick them. Issue 45, item 2, asks for 90 % at least.

A pole whose verdict is "smear" is counted apart: the chain leaves it out by default, and its
deviation does not describe one mode. Each pole is also classed by where it came from
(`lamdyn.ema`'s `refinement`): "refined" (the check took the refined pole), "diagram" (the
check kept the diagram's pole) and "put back" (the diagram's pole, put back because the
refinement left its column or moved a pole beside one that left).

Usage: python3 tools/ema/damped_coverage.py [--seeds N] [--levels 0.001,0.02,...]
                                            [--mass-line X] [--poles ESTIMATOR]
  -> markdown (docs/ema.md, "Standard deviations of each pole"): per case, the poles counted,
     the coverage of f and zeta over the poles that are not smears, and by class, and the
     widest sd of any pole found (smears too) relative to the true f and zeta; then per mode
     where a coverage is below 90 %: its class counts, observed RMS error over the RMS of the
     predicted sd, and the mean error over it (a bias where near the first).
"""
import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import damped_bias as db  # noqa: E402

#: Classes of the pole each mode reports (module docs).
CLASSES = ("refined", "diagram", "put back")
#: The class of each `lamdyn.ema` refinement outcome.
CLASS_OF = {"taken": "refined", "not better": "diagram", "none": "diagram",
            "left its column": "put back", "beside a lost pole": "put back"}


def intervals(zeta, references, seeds, snr_rel=0.01, mass_line=0.0, poles=None):
    """Per (seed, mode): the pole's (estimator `poles`, None: lamdyn's default) error (f in Hz,
    zeta), its sd, its verdict and its class (`CLASSES`); NaN, "" where no pole was found near the mode."""
    targets = [t[0] for t in db.true_modes()]
    win = db.windows(targets)
    shape = (seeds, len(targets))
    err, sd = np.full(shape + (2,), np.nan), np.full(shape + (2,), np.nan)
    verdict, kind = np.full(shape, "", object), np.full(shape, "", object)
    for s in range(seeds):
        f, h = db.plate_frf(zeta, references, snr_rel, np.random.default_rng(1000 + s),
                            mass_line=mass_line)
        options = {} if poles is None else {"poles": poles}
        r = db.lamdyn_ema(f, h, targets, refine=True, **options)
        found = r["freq_hz"]
        for i, k in enumerate(db.nearest_index(found, targets, win)):
            if k is None:
                continue
            err[s, i] = found[k] - targets[i], r["damping_ratio"][k] - zeta
            sd[s, i] = r["freq_sd_hz"][k], r["damping_sd"][k]
            verdict[s, i] = r["verdict"][k]
            kind[s, i] = CLASS_OF[r["refinement"][k]]
    return targets, err, sd, verdict, kind


def cases_counted(err, sd, verdict):
    """Which (seed, mode) cases count: a pole found, with an sd, and not a smear."""
    return np.isfinite(err[..., 0]) & np.isfinite(sd).all(axis=-1) & (verdict != "smear")


def covered(err, sd):
    """Whether the truth lies in each 95 % interval (|error| <= 1.96 sd), per quantity."""
    return np.abs(err) <= 1.96 * sd


def fraction(hit, mask):
    """`hit`'s share over `mask` per quantity as text "f / zeta", or "–" over none."""
    n = int(mask.sum())
    if n == 0:
        return "–"
    return f"{hit[mask, 0].mean():.3f} / {hit[mask, 1].mean():.3f}"


def case_lines(zeta, refs, seeds, mass_line=0.0, poles=None):
    """One row of the coverage table, and the lines on its modes below 90 %."""
    targets, err, sd, verdict, kind = intervals(zeta, refs, seeds, mass_line=mass_line,
                                                poles=poles)
    counted = cases_counted(err, sd, verdict)
    hit = covered(err, sd)
    smears = int((verdict == "smear").sum())
    cells = [fraction(hit, counted & (kind == c)) + f" ({int((counted & (kind == c)).sum())})"
             for c in CLASSES]
    found = np.isfinite(sd).all(axis=-1)
    rel = sd / np.array([targets, [zeta] * len(targets)]).T
    widest = np.max(rel[found], axis=0) if found.any() else [np.nan, np.nan]
    row = (f"| {100 * zeta:g} % | {len(refs)} | {int(counted.sum())} | {smears} | "
           f"{fraction(hit, counted)} | " + " | ".join(cells)
           + f" | {100 * widest[0]:.3g} / {100 * widest[1]:.3g} |")
    notes = []
    for i, t in enumerate(targets):
        m = counted[:, i]
        if not m.any() or hit[m, i].mean(axis=0).min() >= 0.9:
            continue
        e, s = err[m, i], sd[m, i]
        rms_sd = np.sqrt(np.mean(s ** 2, axis=0))
        ratio, bias = np.sqrt(np.mean(e ** 2, axis=0)) / rms_sd, e.mean(axis=0) / rms_sd
        classes = ", ".join(f"{c} {int((kind[m, i] == c).sum())}" for c in CLASSES)
        notes.append(f"- ζ {100 * zeta:g} %, {len(refs)} reference(s), {t:.1f} Hz: coverage "
                     f"{fraction(hit[:, i], m)} over {int(m.sum())} poles ({classes}); RMS error "
                     f"/ sd {ratio[0]:.2f} / {ratio[1]:.2f}, mean error / sd "
                     f"{bias[0]:+.2f} / {bias[1]:+.2f}")
    return row, notes


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--levels", default="0.001,0.02,0.08,0.15")
    ap.add_argument("--mass-line", type=float, default=0.0,
                    help="a free plate: its rigid-body mass line, this many times the elastic "
                         "modes' RMS (damped_bias.plate_frf)")
    ap.add_argument("--poles", default=None,
                    help="lamdyn's pole estimator (`lamdyn ema --poles`; lamdyn's default)")
    a = ap.parse_args()
    rows, notes = [], []
    for zeta in map(float, a.levels.split(",")):
        for refs in db.REFERENCE_SETS:
            row, more = case_lines(zeta, refs, a.seeds, a.mass_line, a.poles)
            rows.append(row)
            notes.extend(more)
    free = f", free plate (mass line {a.mass_line:g} times the modes' RMS)" if a.mass_line else ""
    print(f"Coverage of the 95 % intervals, f / ζ, over {a.seeds} seeds at 1 % noise{free} "
          "(poles counted in brackets):\n")
    print("| ζ | refs | poles | smears (apart) | all | " + " | ".join(CLASSES)
          + " | widest sd(f)/f / sd(ζ)/ζ, % |")
    print("|---" * (6 + len(CLASSES)) + "|")
    print("\n".join(rows))
    print("\nModes below 90 %:\n" + ("\n".join(notes) if notes else "none."))


if __name__ == "__main__":
    main()

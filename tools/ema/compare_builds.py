"""Two builds of lamdyn on the damped virtual tests, mode by mode: where one estimator's RMS
error differs significantly between two runs of `damped_bias.py --save` (the paired bootstrap
over the seeds, which are the same FRFs in both runs).

Run damped_bias.py with one build (`--save before.npz`), install the other, run it again
(`--save after.npz`), then `python3 tools/ema/compare_builds.py before.npz after.npz`. Prints,
per case, the modes and quantities where after / before's 95 % interval lies wholly above or
below 1 (and, with `--all`, every mode whose RMS changed within the seeds' scatter), then how
many were better and how many worse. Changes below 0.1 % of the RMS are left out (rounding).
"""
import argparse

import numpy as np

from damped_bias import rms, rms_ratio_interval, true_modes

#: Changes of an RMS error below this fraction are rounding (FRFs computed in another order
#: differ in the last bits, and so do the poles), not the build's: never listed or counted.
MIN_CHANGE = 1e-3


def changes(before, after, estimator, show_all, rng):
    """Lines for the cases of both files; (better, worse) counts of significant changes."""
    lines, better, worse = [], 0, 0
    targets = [t[0] for t in true_modes()]
    for key in sorted(k for k in before.files if k.endswith("/" + estimator)):
        if key not in after.files:
            continue
        a, b = before[key], after[key]
        case = key.split("/")[0]
        for i, t in enumerate(targets):
            for q, name in ((0, "f"), (1, "zeta")):
                r = rms_ratio_interval(b[:, i, q], a[:, i, q], rng)
                if r is None or r[1] is None:
                    continue
                ratio, lo, hi = r
                if abs(ratio - 1.0) < MIN_CHANGE:
                    continue
                significant = lo > 1.0 or hi < 1.0
                if not significant and not show_all:
                    continue
                rms_a, rms_b = 100 * rms(a[:, i, q]), 100 * rms(b[:, i, q])
                mark = ""
                if significant:
                    better, worse = (better + 1, worse) if ratio < 1 else (better, worse + 1)
                    mark = ", significant"
                lines.append(f"- {case}, {t:.1f} Hz, {name}: RMS {rms_a:.3f} -> {rms_b:.3f} % "
                             f"(after / before {ratio:.2f}, 95 % interval {lo:.2f}-{hi:.2f}"
                             f"{mark})")
    return lines, better, worse


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--estimator", default="checked",
                    help="diagram, refined, checked or single (default checked)")
    ap.add_argument("--all", action="store_true", help="also changes within the seeds' scatter")
    a = ap.parse_args()
    lines, better, worse = changes(np.load(a.before), np.load(a.after), a.estimator, a.all,
                                   np.random.default_rng(0))
    print("\n".join(lines) if lines else "No mode changed.")
    print(f"\n{a.estimator}: significantly better at {better}, worse at {worse} "
          "(mode, quantity, case)")


if __name__ == "__main__":
    main()

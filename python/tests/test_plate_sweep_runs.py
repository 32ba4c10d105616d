"""The measured plate sweep run by run (crates/lamdyn-ema/tests/fixtures/plate-sweep, MIT): each
run alone against two independent estimators of the same run (sdypy-EMA's LSCF and a local
one-pole fit, tools/ema/plate_sweep_runs.py), and the evidence that the four runs are not four
records of one linear plate, so that no estimator can put each run's first mode within 0.5 % of
the four runs' value (docs/ema.md, "Measured plate, swept sine")."""

import sys

import numpy as np
import pytest

pytest.importorskip("sdypy.EMA")
pytest.importorskip("scipy")


@pytest.fixture(scope="module")
def runs(repo, lamdyn_exe):
    sys.path.insert(0, str(repo / "tools" / "ema"))
    import plate_sweep_runs

    return plate_sweep_runs, plate_sweep_runs.per_run(str(lamdyn_exe))


def test_each_run_gives_the_independent_estimators_modes(runs):
    tool, per_run = runs
    for i, r in per_run.items():
        for m, (f0, _) in enumerate(tool.README_MODES):
            f = r["lamdyn"][m][0]
            others = [r["sdypy"][m][0], r["local"][m][0]]
            # Within 0.5 % (the figure) of the nearer independent estimate of the same
            # run (measured: 0.20 % at most; the two independent ones differ by up to 2 % at
            # run 3's 215 Hz mode, where the local fit meets the run's distortion).
            nearest = min(abs(f / o - 1) for o in others)
            assert nearest < 0.005, f"run {i} mode {m + 1}: lamdyn {f:.2f} Hz, others {others}"


def test_the_runs_first_mode_moves_with_the_force_far_beyond_the_noise(runs):
    _, per_run = runs
    f1 = {i: r["sdypy"][0][0] for i, r in per_run.items()}
    # sdypy's own first mode spans 75.56-77.71 Hz over the runs (2.8 %): from any one value the
    # others lie 1-2.8 % away, so "each run within 0.5 % of the four runs' estimate" cannot hold.
    assert max(f1.values()) / min(f1.values()) - 1 > 0.02
    # It rises with the force at the resonance (a hardening plate): the run with the largest
    # force (run 3, |X| 2661 against 1333-1552) has the highest mode, the weakest (run 4) the
    # lowest.
    force = {i: r["force"] for i, r in per_run.items()}
    assert max(f1, key=f1.get) == max(force, key=force.get)
    assert min(f1, key=f1.get) == min(force, key=force.get)
    # Noise does not explain it: run 3's H at 77 Hz differs from run 1's by 77 %, against a
    # noise floor of 0.1-0.2 % of H (the sensors' RMS at the records' quiet ends).
    one, three = per_run[1], per_run[3]
    assert abs(three["h"] / one["h"] - 1) > 100 * np.hypot(one["noise"], three["noise"])

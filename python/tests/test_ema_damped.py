"""Poles of damped, overlapping modes: the diagram's pole, the refined pole and the default pole
(the rank-one fit; with one reference checked in the LSCF model's context) on virtual plates with
modal damping 0.1 %, 2 %, 8 % and 15 %, one and three references, beside sdypy-EMA 0.31 on the same FRFs (tools/ema/damped_bias.py prints the whole
table of docs/ema.md, "Damped poles"; this test runs a few seeds of it).

What must hold (issue 45, item 1): the final pole is never worse than the diagram's on noise-free
FRFs, and on noisy ones better or equal, and as good as sdypy-EMA's. Measured: on noise-free
FRFs the checked pole is the diagram's in every case, and so is the default with one reference
(the rank-one fit, each pole checked in the LSCF model's context: unchecked it moves poles near
the band's upper edge by up to 0.19 % at 15 %); with three references the rank-one fit lies
within 5e-5 of f and 1e-4 of zeta of it (the pseudo-modes above the band model the modes there
closely, not exactly: docs/ema.md).
"""

import sys

import numpy as np
import pytest

import lamdyn


@pytest.fixture(scope="module")
def bench(repo):
    sys.path.insert(0, str(repo / "tools" / "ema"))
    import damped_bias

    return damped_bias


def rms(e):
    """RMS relative error over the seeds that found each mode (NaN where none did): modes x
    [f, zeta]."""
    found = np.isfinite(e).sum(axis=0)
    return np.sqrt(np.where(found > 0, np.nansum(e ** 2, axis=0) / np.maximum(found, 1), np.nan))


def one_mode_rms(bench, zeta, references, mode_hz, seeds=8):
    """RMS relative errors [f, zeta] of the diagram's, the default and sdypy-EMA's pole at the
    true mode `mode_hz` over the first `seeds` seeds of damped_bias.py's plate (1 % noise),
    printed in %."""
    targets, errors = bench.run(zeta, references, 0.01, seeds, with_sdypy=True)
    k = int(np.argmin(np.abs(np.array(targets) - mode_hz)))
    assert targets[k] == pytest.approx(mode_hz)
    d, c, s = (rms(errors[e])[k] for e in ("diagram", "default", "sdypy"))
    print(f"{mode_hz:.1f} Hz, RMS f / zeta %: diagram {100 * d[0]:.4f} / {100 * d[1]:.3f}, "
          f"default {100 * c[0]:.4f} / {100 * c[1]:.3f}, sdypy {100 * s[0]:.4f} / {100 * s[1]:.3f}")
    return d, c, s


@pytest.mark.parametrize("zeta", [0.001, 0.02, 0.08, 0.15])
@pytest.mark.parametrize("references", [[0], [0, 5, 10]])
def test_noise_free_poles_stay_where_the_diagram_has_them(bench, zeta, references):
    targets, errors = bench.run(zeta, references, 0.0, 1, with_sdypy=False)
    diagram, final = np.abs(errors["diagram"][0]), np.abs(errors["default"][0])
    assert np.all(np.isfinite(final[:, 0])), f"modes missing: {targets}"
    # The diagram is exact to 1e-6 at <= 2 % damping and within 0.1 % in zeta at 15 %. With
    # the refinement holding the LSCF model's roots outside the band, the check keeps the
    # diagram's pole at every mode of these FRFs (measured: equal to the table's digits); the
    # residual terms' refinement let one through before (180.6 Hz, 2 %, one reference, zeta
    # +0.35 %), so 1e-4 in zeta (0.01 %) fails on what was fixed, and a refinement let through
    # unchecked is 0.07-6.4 % off.
    assert np.all(final[:, 0] <= diagram[:, 0] + 5e-5)
    assert np.all(final[:, 1] <= diagram[:, 1] + 1e-4)


@pytest.mark.parametrize("zeta", [0.001, 0.02])
@pytest.mark.parametrize("references", [[0], [0, 5, 10]])
def test_noisy_poles_are_better_than_the_diagrams_and_sdypys(bench, zeta, references):
    targets, errors = bench.run(zeta, references, 0.01, 4, with_sdypy=True)
    d, c, s = rms(errors["diagram"]), rms(errors["default"]), rms(errors["sdypy"])
    for k, f in enumerate(targets):
        print(f"{f:6.1f} Hz  zeta err diagram {100 * d[k, 1]:6.2f} %  default {100 * c[k, 1]:6.2f} %"
              f"  sdypy {100 * s[k, 1]:6.2f} %   f err {100 * d[k, 0]:.4f} / {100 * c[k, 0]:.4f} / {100 * s[k, 0]:.4f} %")
    # The check takes the diagram's pole or a refined one that fits significantly better; over
    # 20 seeds no mode is worse than the diagram's in f or zeta at these damping levels
    # (measured; the trades are at 8 %). So: no mode worse in both beyond the scatter of four
    # seeds (the RMS of four draws scatters by about 35 %), and the worst mode no worse than
    # the diagram's worst.
    worse = lambda q, tol: c[:, q] > 1.35 * d[:, q] + tol  # noqa: E731
    assert not np.any(worse(0, 1e-5) & worse(1, 1e-3))
    assert np.max(c[:, 1]) <= 1.05 * np.max(d[:, 1]) + 1e-3
    assert np.max(c[:, 0]) <= 1.05 * np.max(d[:, 0]) + 1e-5
    # Against sdypy-EMA wherever its select_closest_poles found the mode: never worse in both
    # (20 seeds at 2 %, one reference, 25.6 Hz: f 0.0051 against sdypy's 0.0064 %, zeta 0.20
    # against 1.33 %; the residual terms' refinement was worse in f there, 0.0125 %).
    found = np.isfinite(s[:, 1])
    assert found.sum() >= 3
    beaten = lambda q, tol: c[found, q] > 1.35 * s[found, q] + tol  # noqa: E731
    assert not np.any(beaten(0, 1e-5) & beaten(1, 1e-3))
    if zeta < 0.01:
        # Light damping: the LSCF's noise bias (zeta several % off) is what the refinement is for.
        assert np.max(c[:, 1]) < 0.25 * np.max(d[:, 1])


def test_an_isolated_damped_mode_loses_the_far_lines_bias(bench):
    """8 % damping, one reference, 1 % noise, the isolated 25.6 Hz mode. The joint refinement's
    pole is unbiased on the noise of its own lines but not on the rest of the band's (docs/ema.md,
    "Where the noise that biases the refined pole comes from"); over 20 seeds it was 0.041 %
    high in f, and the check took it: 0.045 % RMS, 1.87 times sdypy-EMA's. Refitted on its own
    lines with the rest of the band's model held (`local_refit.rs`, 2026-12-03): 0.019 % against
    sdypy's 0.024 %, zeta 0.20 against 1.86 %. Over these eight seeds: f 0.018 against sdypy's
    0.027 and the diagram's 0.028 %, zeta 0.19 against 2.0 and 2.1 %."""
    d, c, s = one_mode_rms(bench, 0.08, [0], 25.625)
    assert c[0] <= s[0] and c[0] <= d[0]
    assert c[1] < 0.25 * min(s[1], d[1])


def test_a_damped_mode_the_check_cannot_tell_takes_its_local_refit(bench):
    """8 % damping, three references, 1 % noise, the isolated 25.6 Hz mode. Its local refit
    (`local_refit.rs`) is less biased than the diagram's pole, but the move is within the
    noise, so the context model found it no better and the check kept the diagram's: over 20
    seeds f 0.0090 % RMS, 1.64 times sdypy-EMA's 0.0055 %. A pole refitted alone is now taken
    unless the context model finds it significantly worse (`context.rs`, "Poles refitted
    alone"): 0.0050 % (2026-12-03). Over these eight seeds: f 0.0044 against sdypy's 0.0050 and
    the diagram's 0.0084 %, zeta 0.051 against 0.26 and 0.10 %."""
    d, c, s = one_mode_rms(bench, 0.08, [0, 5, 10], 25.625)
    assert c[0] <= s[0] and c[0] < 0.7 * d[0]
    assert c[1] < 0.7 * min(s[1], d[1])


def test_a_damped_neighbour_apart_from_its_pair_takes_its_local_refit(bench):
    """15 % damping, three references, 1 % noise, 55.6 Hz: its half-power band overlaps that of
    72.5 Hz (17 Hz apart, half-widths 8.3 and 10.9 Hz), so the local step left it at its joint
    estimate, which the check found no better than the diagram's pole (over 20 seeds f 0.035 %
    RMS, 1.5 times sdypy-EMA's 0.024 %). The local step now leaves out only a pole within the
    larger of two half-power half-widths of another (`local_refit.rs`, 2026-12-03): 0.017 %,
    zeta 0.16 against sdypy's 2.3 %. Over these eight seeds: f 0.014 against sdypy's 0.025 and
    the diagram's 0.035 %, zeta 0.21 against 2.3 and 0.55 % (the build before: 0.034 / 0.50)."""
    d, c, s = one_mode_rms(bench, 0.15, [0, 5, 10], 55.625)
    assert c[0] <= s[0] and c[0] < 0.7 * d[0]
    assert c[1] < 0.5 * min(s[1], d[1])


def test_a_pole_over_a_pair_takes_the_estimate_the_context_can_judge(bench):
    """8 % damping, one reference, 1 % noise: the diagram has one pole over 150.6 / 152.5 Hz
    (1.2 % apart), a smear. The rank-one fit resolves the pair (a second mode under the pole),
    but the LSCF model's context has one pole there, so the check kept the diagram's: over 20
    seeds zeta 1.477 % RMS, 1.02 times sdypy-EMA's 1.443 %. Where the check keeps the diagram's
    pole, the joint refinement's single pole is now checked in its place (docs/ema.md, "Where
    the fit and the context disagree", 2026-12-04): f 0.370 % against sdypy's 0.384 and the
    diagram's 0.378 %, zeta 0.317 %. Over these eight seeds: f 0.370 against 0.383 and 0.378 %,
    zeta 0.36 against 1.48 and 1.50 %."""
    d, c, s = one_mode_rms(bench, 0.08, [0], 152.5)
    assert c[0] <= s[0] and c[0] <= d[0]
    assert c[1] < 0.5 * min(s[1], d[1])


def test_a_fallback_pole_carries_the_refused_estimate_in_its_deviation(coverage_tool):
    """8 % damping, one reference at point 5, 1 % noise: at 150.6 Hz the check refuses the
    rank-one fit's pole and takes the checked estimator's refined pole in every seed (docs/ema.md,
    "Where the fit and the context disagree"). That pole's own sd described its scatter only:
    the truth lay within 1.96 sd(zeta) in 3 of 20 seeds (|error| / sd 2.6 RMS), the diagram's
    pole before in 20 of 20. The truth may lie by either estimate, so the sd is widened by the
    refused pole's difference as far as the column reaches, as where the diagram's pole is kept:
    20 of 20 (measured 2026-12-04)."""
    targets, err, sd, verdict, kind = coverage_tool.intervals(0.08, [5], 20)
    k = int(np.argmin(np.abs(np.array(targets) - 150.625)))
    counted = coverage_tool.cases_counted(err, sd, verdict)[:, k]
    assert counted.sum() >= 15, counted.sum()
    hit = coverage_tool.covered(err, sd)[counted, k]
    print("150.6 Hz, reference at point 5: f / zeta covered", hit.sum(axis=0), "of", counted.sum())
    assert hit[:, 1].mean() >= 0.9 and hit[:, 0].mean() >= 0.9


def test_a_pole_over_a_weak_neighbour_is_widened_by_the_residual(coverage_tool):
    """8 % damping, one reference at point 5 (near the node lines of 102.5 and 105.6 Hz), 1 %
    noise: the diagram has one pole for the two, and the rank-one fit's pole lies 0.4-0.5 % high
    of 102.5 Hz in every seed, 3-4 times its noise sd (0.14 Hz): the truth lay within 1.96 sd(f)
    in 0 of 20 seeds. The fit's residual holds a second-order term at the pole beyond noise (the
    weak 105.6 Hz mode's shape, orthogonal to the pole's residues), whose size widens the sd
    (module `residual_spread`): 20 of 20 (measured 2026-12-04)."""
    targets, err, sd, verdict, kind = coverage_tool.intervals(0.08, [5], 20)
    k = int(np.argmin(np.abs(np.array(targets) - 102.5)))
    counted = coverage_tool.cases_counted(err, sd, verdict)[:, k]
    assert counted.sum() >= 15, counted.sum()
    hit = coverage_tool.covered(err, sd)[counted, k]
    ratio = np.abs(err[counted, k, 0]) / sd[counted, k, 0]
    print("102.5 Hz, reference at point 5: f / zeta covered", hit.sum(axis=0), "of", counted.sum(),
          "|error| / sd(f) max", ratio.max())
    assert hit[:, 0].mean() >= 0.9 and hit[:, 1].mean() >= 0.9


def test_a_pole_put_back_beside_a_held_mode_widens_to_it(coverage_tool):
    """8 % damping, one reference at point 1, 1 % noise: at 180.6 Hz the diagram's column is
    one order wide (180.2 Hz, zeta 1.35 %), the rank-one fit leaves it, and the diagram's pole is
    put back; the fit holds the mode at 181.0 Hz, zeta 8.0 %, beside the selection. The sd was
    widened only as far as the column reaches (zeta 0.68 %): the truth lay within 1.96 sd(zeta)
    in 0 of 20 seeds. A mode held beside the selection at the column's frequency is another
    estimate of its resonance and widens the sd too: 20 of 20 (measured 2026-12-04)."""
    targets, err, sd, verdict, kind = coverage_tool.intervals(0.08, [1], 20)
    k = int(np.argmin(np.abs(np.array(targets) - 180.625)))
    counted = coverage_tool.cases_counted(err, sd, verdict)[:, k]
    assert counted.sum() >= 15, counted.sum()
    hit = coverage_tool.covered(err, sd)[counted, k]
    print("180.6 Hz, reference at point 1: f / zeta covered", hit.sum(axis=0), "of", counted.sum(),
          "classes", sorted(set(kind[counted, k])))
    assert hit[:, 1].mean() >= 0.9 and hit[:, 0].mean() >= 0.9


def test_the_diagram_pole_is_reported_beside_the_final_one(bench):
    targets = [t[0] for t in bench.true_modes()]
    f, h = bench.plate_frf(0.02, [0], 0.0, np.random.default_rng(0))
    r = lamdyn.ema(f, h, band_hz=bench.BAND_HZ, near_hz=targets, window_hz=0.5)
    for m in r["modes"]:
        p = complex(*m["diagram_pole"])
        assert abs(abs(p) / (2 * np.pi) / m["freq_hz"] - 1) < 0.01
        if not m["refined"]:
            assert complex(*m["pole"]) == p
    assert "diagram_freq_hz" in r and len(r["diagram_freq_hz"]) == len(targets)


@pytest.mark.parametrize("poles", ["checked", "refined"])
def test_no_refined_pole_is_taken_beside_a_lost_one(bench, poles):
    """At 8 % damping with three references and noise the refinement can send a pole out of its
    column where the diagram misses a mode: in seed 1001 it has no pole for 175.6 Hz, and
    152.5 Hz runs to 169 Hz to take it, 180.6 Hz leaves too. A neighbour fitted beside a pole
    standing elsewhere may take over that pole's mode (with one reference, before the
    pseudo-modes above the band were held, 102.5 Hz moved +1.1 % to cover both modes of its
    pair when 105.6 Hz left, and fitted the check's model better). Both the check and the
    refined estimator keep the diagram's pole of the lost one and of every pole whose
    half-power band overlaps it (docs/ema.md, "Damped poles")."""
    targets = [t[0] for t in bench.true_modes()]
    lost_seen = 0
    for seed in range(4):
        f, h = bench.plate_frf(0.08, [0, 5, 10], 0.01, np.random.default_rng(1000 + seed))
        r = bench.lamdyn_ema(f, h, targets, poles=poles)
        lost = [float(w.split(" Hz")[0].rsplit(" ", 1)[1]) for w in r["warnings"]
                if "out of its column" in w]
        lost_seen += len(lost)
        for m in r["modes"]:
            p = complex(*m["diagram_pole"])
            f0, z0 = abs(p) / (2 * np.pi), -p.real / (2 * np.pi)
            for fl in lost:
                # Half-power bands overlap: |f1 - f2| < zeta1 f1 + zeta2 f2 (both about 8 %).
                if abs(f0 - fl) < z0 + 0.08 * fl:
                    assert not m["refined"], f"seed {seed}: {f0:.2f} Hz taken beside {fl:.2f} Hz"
    assert lost_seen > 0, "no pole was lost: the case no longer tests the rule"


def test_the_paired_bootstrap_tells_scatter_from_a_loss(bench):
    """The tables' verdicts (tools/ema/damped_bias.py): two estimators with the same error
    distribution are within the seeds' scatter, one with twice another's error on the same
    seeds is significantly worse, and a bias shared by both gives a tight ratio."""
    draw = np.random.default_rng(7)
    a, b = draw.standard_normal(20), draw.standard_normal(20)
    ratio, lo, hi = bench.rms_ratio_interval(a, b, np.random.default_rng(0))
    assert lo < 1.0 < hi, (ratio, lo, hi)
    ratio, lo, hi = bench.rms_ratio_interval(2.0 * b + 0.2 * a, b, np.random.default_rng(0))
    assert 1.5 < lo and ratio < hi, (ratio, lo, hi)
    # A bias of 10 sd shared by both: 5 % more bias is a real loss, and the interval says so.
    ratio, lo, hi = bench.rms_ratio_interval(10.5 + a, 10.0 + b, np.random.default_rng(0))
    assert 1.0 < lo < ratio < hi < 1.15, (ratio, lo, hi)
    # Fewer than five seeds where both found the mode: the ratio there, no interval.
    found = np.where(np.arange(20) < 4, a, np.nan)
    ratio, lo, hi = bench.rms_ratio_interval(found, b, np.random.default_rng(0))
    assert lo is None and hi is None
    assert ratio == pytest.approx(np.sqrt(np.mean(a[:4] ** 2) / np.mean(b[:4] ** 2)))


def test_one_lscf_over_every_curve_is_sdypys_estimator(bench):
    """With three references lamdyn's default is PolyMAX, while sdypy-EMA fits one LSCF over
    every curve; `polymax=False` is that same estimator in lamdyn. On the same noisy FRFs (8 %
    damping, 1 % noise) its diagram poles agree with sdypy's per seed wherever both find the
    mode, noise bias included (at 150.6 Hz both put one pole for the pair 150.6 / 152.5 Hz,
    +0.24 % in f): measured over ten seeds within 7.3e-5 in f and 2.0e-3 in zeta, relative.
    The rest is the columns: which order each takes (sdypy: the pole nearest the column's mean;
    lamdyn: the top order), and sdypy's band ends at 199.9 Hz (the poles of one order differ by
    up to 5.2e-4 with lamdyn's band 20-200 Hz, 1.9e-4 with 20-199.9 Hz). PolyMAX's differ from
    sdypy's by 2.8e-3 in f at 150.6 Hz, where it resolves the pair. So the three-reference gaps
    to sdypy in docs/ema.md are PolyMAX against one LSCF, not lamdyn's LSCF."""
    targets = [t[0] for t in bench.true_modes()]
    win = bench.windows(targets)
    both = 0
    for seed in range(2):
        f, h = bench.plate_frf(0.08, [0, 5, 10], 0.01, np.random.default_rng(1000 + seed))
        r = bench.lamdyn_ema(f, h, targets, refine=False, polymax=False)
        mine = bench.nearest(r["freq_hz"], r["damping_ratio"], targets, win)
        theirs = bench.sdypy_poles(f, h, targets)
        found = np.isfinite(mine[:, 0]) & np.isfinite(theirs[:, 0])
        both += found.sum()
        diff = np.abs(mine[found] / theirs[found] - 1)
        assert np.all(diff[:, 0] < 2e-4), f"seed {seed}: f differs by {diff[:, 0]}"
        assert np.all(diff[:, 1] < 5e-3), f"seed {seed}: zeta differs by {diff[:, 1]}"
    # sdypy finds 25.6, 55.6 and 150.6 Hz in each of ten seeds (measured): two seeds give six.
    assert both >= 4, "sdypy found too few of the modes for the comparison"


@pytest.fixture(scope="module")
def coverage_tool(bench):
    import damped_coverage

    return damped_coverage


@pytest.mark.parametrize("zeta, refs, least", [
    (0.02, [0, 5, 10], 0.8), (0.08, [0, 5, 10], 0.8), (0.15, [0, 5, 10], 0.8),
    # One reference: at 8 % 40 of the 180 cases find no pole and 40 are smears, at 15 % 101 and
    # 18 (measured 2026-12-04).
    (0.08, [0], 0.5), (0.15, [0], 0.3),
    # The reference at other points: 100, 87 and 89 counted (measured 2026-12-04).
    (0.08, [5], 0.5), (0.15, [5], 0.4), (0.08, [10], 0.4)])
def test_pole_intervals_cover_the_damped_plates(coverage_tool, zeta, refs, least):
    """Issue 45, item 2, on modes damped 2-15 % (the coverage test of tests/it.rs has 5 % at
    most): at 1 % noise the 95 % intervals f +- 1.96 sd and zeta +- 1.96 sd of the default
    poles hold the truth on at least 90 % of the (mode, seed) cases over 20 seeds, smears apart
    (the chain leaves them out). With three references the default is the rank-one fit with its
    own covariance; measured (2026-12-04, tools/ema/damped_coverage.py): f / zeta 0.944 / 0.944
    at 2 %, 0.953 / 0.965 at 8 %, 0.951 / 0.957 at 15 %. With one reference the same fit holds
    the modes the selection left out, each pole is checked in the LSCF model's context and the
    sd is the refinement's (its residual variance holds what the LSFD model lacks): 1.000 /
    1.000 at 8 % and at 15 %. The checked pole before covered zeta at 8 % on 0.816: without
    150.6 and 175.6 Hz, which the diagram lacks at 1 % noise, 105.6 Hz's refined zeta came out
    8.3-8.4 % in every seed (docs/ema.md, "One reference: the modes left out")."""
    targets, err, sd, verdict, kind = coverage_tool.intervals(zeta, refs, 20)
    counted = coverage_tool.cases_counted(err, sd, verdict)
    assert counted.sum() >= least * err.shape[0] * len(targets), counted.sum()
    hit = coverage_tool.covered(err, sd)[counted]
    assert hit.mean(axis=0).min() >= 0.9, hit.mean(axis=0)


def test_a_free_plates_sound_poles_hold_their_damping(coverage_tool):
    """Issue 45, item 2, on a part unlike the supported plates: the same plate free, its
    rigid-body mass line twice the elastic modes' RMS (damped_bias.plate_frf's `mass_line`),
    8 % damping, one reference, 1 % noise of each curve's RMS, 20 seeds. The LSCF's damping of
    the pair 102.5 / 105.6 Hz (one pole) is 64-70 % low in every seed, its whole column too, and
    the refinement finds 8 % at the column's frequency; the diagram's pole is put back. The
    interval of every pole judged sound holds the truth in f and zeta on at least 90 % of the
    cases. Measured (2026-12-04, tools/ema/damped_coverage.py --mass-line 2): 1.000 / 1.000
    with the default (the rank-one fit, checked in the LSCF model's context). The checked pole
    before covered zeta on 0.633 (25.6 Hz in 2 of 20 seeds, its refined zeta 0.7 sd high on
    average); the rank-one fit followed by the checked pole's local refit (module
    `local_refit`), 0.683 (25.6 Hz in 1 of 20, 3.1 sd high on average). The doubtful poles are not asserted: the one near
    176 Hz for the pair 175.6 / 180.6 Hz has zeta 0.8 % against 8 %. With three references
    (the rank-one fit, its own covariance) the same free plate covers 0.950 / 0.967 of all its
    poles."""
    targets, err, sd, verdict, kind = coverage_tool.intervals(0.08, [0], 20, mass_line=2.0)
    sound = np.isfinite(err[..., 0]) & np.isfinite(sd).all(axis=-1) & (verdict == "sound")
    assert sound.sum() >= 60, sound.sum()
    hit = coverage_tool.covered(err, sd)[sound]
    assert hit.mean(axis=0).min() >= 0.9, hit.mean(axis=0)


def test_a_pole_over_a_pair_on_a_free_plate_is_not_sound(bench):
    """Issue 45, item 3, on the free plate of the test above (mass line twice the elastic
    modes' RMS, 8 %, one reference, 1 % noise): one pole near 103.2 Hz stands for the pair
    102.5 / 105.6 Hz, its damping 64-70 % low. Its residues over the band look real (MPC above
    0.5), those of the lines around it do not (0.14-0.18): the window holds a mode without its
    own pole. It is doubtful, with that reason; before the local estimate alone counted it was
    judged sound in 14 of 20 seeds (measured 2026-12-02)."""
    targets = [t[0] for t in bench.true_modes()]
    for seed in range(4):
        f, h = bench.plate_frf(0.08, [0], 0.01, np.random.default_rng(1000 + seed),
                               mass_line=2.0)
        r = bench.lamdyn_ema(f, h, targets)
        near = [k for k, fk in enumerate(r["freq_hz"]) if 100 < fk < 108]
        assert near, (seed, r["freq_hz"])
        for k in near:
            flags = r["modes"][k]["quality"]["flags"]
            assert r["verdict"][k] != "sound", (seed, r["freq_hz"][k], flags)
            assert any("LocalComplexShape" in fl for fl in flags), (seed, flags)


def test_a_pole_over_a_close_pair_is_a_smear(bench):
    """Issue 45, item 3: with one reference at 8 % damping the pairs 150.6 / 152.5 Hz (1.3 %
    apart) and 175.6 / 180.6 Hz are one pole each in the diagram, MPC above 0.7. Their curves
    hold the second shape (the second-shape test, crates/lamdyn-ema/src/second_shape.rs:
    measured Z 9.3-60 against at most 2.8 for one mode), so they are smears, kept out of the
    chain, with the reason named; every pole for one mode stays what it was. The same plate with
    three references resolves both pairs, and nothing is a smear by that test."""
    targets = [t[0] for t in bench.true_modes()]
    for seed in range(3):
        f, h = bench.plate_frf(0.08, [0], 0.01, np.random.default_rng(1000 + seed))
        r = bench.lamdyn_ema(f, h, targets)
        second = [any("SecondShape" in fl for fl in m["quality"]["flags"]) for m in r["modes"]]
        by_pair = [k for k, fk in enumerate(r["freq_hz"]) if 148 < fk < 183]
        assert by_pair and all(second[k] for k in by_pair), (seed, r["freq_hz"], second)
        assert all(r["verdict"][k] == "smear" for k in by_pair)
        assert not any(second[k] for k in range(len(second)) if k not in by_pair), second
        f, h = bench.plate_frf(0.08, [0, 5, 10], 0.01, np.random.default_rng(1000 + seed))
        r = bench.lamdyn_ema(f, h, targets)
        assert not any("SecondShape" in fl for m in r["modes"] for fl in m["quality"]["flags"]), \
            [m["quality"] for m in r["modes"]]


@pytest.fixture(scope="module")
def shapes_tool(repo):
    sys.path.insert(0, str(repo / "tools" / "ema"))
    import damped_shapes

    return damped_shapes


@pytest.mark.parametrize("zeta", [0.02, 0.08])
def test_an_isolated_damped_mode_keeps_its_real_shape(bench, shapes_tool, zeta):
    """Each mode's shape comes from the lines around its pole (local_residues.rs): the band's
    fit, whose real residual terms cannot hold the damped modes above the band, made the
    plate's real shapes complex (2 %: the 25.6 Hz mode at MAC 0.947 with its true shape, MPC
    0.80; 8 %, one reference: the poles of the isolated 25.6 and 102.5 Hz modes smears by
    their MPC, 0.31 and 0.04, in 20 of 20 seeds). Measured over 20 seeds
    (tools/ema/damped_shapes.py): MAC 1.000 and 0.999 at 25.6 Hz, 0.904 at 102.5 Hz at 8 %
    (beside its pair's 105.6 Hz), none a smear; three seeds here, at the diagram's poles, so
    that the shapes are tested and not the pole estimator (since 2026-12-02 the check takes
    the refined pair 102.5 / 105.6 Hz at 8 % in seeds 1000 and 1012, 0.5 % high in f and
    10–26 % in zeta: MAC 0.80 at 102.5 Hz there, docs/ema.md). The poles over the unresolved
    pairs stay smears (test_a_pole_over_a_close_pair_is_a_smear)."""
    targets = [t[0] for t in bench.true_modes()]
    truth = shapes_tool.true_shapes()
    win = bench.windows(targets)
    for seed in range(3):
        f, h = bench.plate_frf(zeta, [0], 0.01, np.random.default_rng(1000 + seed))
        r = bench.lamdyn_ema(f, h, targets, poles="diagram")
        found = bench.nearest_index(r["freq_hz"], targets, win)
        for i, least in ((0, 0.99), (3, 0.85)):
            k = found[i]
            assert k is not None, (seed, targets[i])
            m = shapes_tool.mac(np.asarray(r["shapes"][k]), truth[i])
            assert m >= least, (zeta, seed, targets[i], m)
            assert r["verdict"][k] != "smear", (zeta, seed, targets[i], r["modes"][k]["quality"])


def test_a_pole_that_ran_away_does_not_widen_its_deviation_without_bound(bench):
    """At 15 % damping with one reference (seed 1000) the refinement sends four poles out of
    their columns; the diagram's poles are put back, and each one's sd is widened by how far the
    data pull it, up to its column's edge, not to where the refinement ran (before 2026-12-01,
    when one pole ran from 25.6 Hz to 1.1e8 Hz: sd(f) 1.1e8 Hz). Since each pole is refined
    beside the outside roots that do not reach it (2026-12-02) none leaves the band here (the
    four reach 59.4–189.9 Hz; nor at 8 % and 15 %, seeds 1000–1019); the run to 1.1e8 Hz is
    kept in `a_runaway_pole_is_clamped_onto_its_columns_edge` (stabilization.rs). An sd(f)
    below 5 % of f and an sd(zeta) below twice zeta still say where the mode is (measured at
    most 1.5 % and 115 % over the damped plates: tools/ema/damped_coverage.py). The default
    since 2026-12-04 (the rank-one fit, holding a mode the selection left out at 103.6 Hz) keeps
    every pole in its column here, so the put-back is run with the checked poles; the bound is
    asserted for both."""
    targets = [t[0] for t in bench.true_modes()]
    f, h = bench.plate_frf(0.15, [0], 0.01, np.random.default_rng(1000))
    default = bench.lamdyn_ema(f, h, targets)
    assert np.all(default["freq_sd_hz"] < 0.05 * default["freq_hz"]), default["freq_sd_hz"]
    assert np.all(default["damping_sd"] < 2 * default["damping_ratio"]), default["damping_sd"]
    r = bench.lamdyn_ema(f, h, targets, poles="checked")
    left = [w for w in r["warnings"] if "out of its column" in w]
    assert len(left) >= 1, r["warnings"]
    # Each such mode says so, with the pole the refinement reached beside the diagram's.
    gone = [k for k, q in enumerate(r["refinement"]) if q == "left its column"]
    assert len(gone) == len(left), (r["refinement"], left)
    for k in gone:
        assert not r["refined"][k]
        assert np.isclose(r["freq_hz"][k], r["diagram_freq_hz"][k], rtol=1e-12)
        assert any(f"to {r['refined_freq_hz'][k]:.3f} Hz" in w for w in left), (k, left)
    assert np.all(r["freq_sd_hz"] < 0.05 * r["freq_hz"]), (r["freq_hz"], r["freq_sd_hz"])
    assert np.all(r["damping_sd"] < 2 * r["damping_ratio"]), (r["damping_ratio"], r["damping_sd"])

"""EMA on numpy arrays beside sdypy-EMA (pip install sdypy-EMA; tested with 0.31.0) on the
measured free-free beam (crates/lamdyn-ema/tests/fixtures/free-free-beam, MIT, from sdypy-EMA's
own examples): the same band and orders; sdypy's poles picked near lamdyn's with its
select_closest_poles (tools/ema/compare_sdypy.py does the same from the CLI)."""

import time
import warnings

import numpy as np
import pytest

import lamdyn

sdypy = pytest.importorskip("sdypy.EMA")


def test_poles_agree_with_sdypy(repo):
    frf = np.array([np.loadtxt(repo / "crates/lamdyn-ema/tests/fixtures/free-free-beam" / f"meas_point_{i}.txt",
                               dtype=complex) for i in (1, 2, 3)])
    freq = np.arange(frf.shape[1]) * 1.0
    t = time.perf_counter()
    ours = lamdyn.ema(freq[1:], frf[:, 1:], band_hz=(10, 1000), orders=(2, 60, 2))
    t_ours = time.perf_counter() - t
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = time.perf_counter()
        m = sdypy.Model(frf=frf, freq=freq, lower=10, upper=1000, pol_order_high=30, frf_type="accelerance")
        m.get_poles(show_progress=False)
        m.select_closest_poles(list(ours["freq_hz"]))
        t_sdypy = time.perf_counter() - t
    f_ours, f_sdypy = ours["freq_hz"], np.asarray(m.nat_freq)
    z_ours, z_sdypy = ours["damping_ratio"], np.asarray(m.nat_xi)
    print(f"\nlamdyn {t_ours * 1e3:.0f} ms, sdypy-EMA {t_sdypy * 1e3:.0f} ms")
    for a, b, za, zb in zip(f_ours, f_sdypy, z_ours, z_sdypy):
        print(f"  f {a:10.4f} vs {b:10.4f} Hz ({a / b - 1:+.1e})   zeta {100 * za:.4f} vs {100 * zb:.4f} %")
    # The four bending modes of the beam are both tools' (and the automatic selection's).
    assert len(f_ours) >= 4
    # The same LSCF estimator on the same lines: docs/ema.md measured 1.8e-5 at most (lamdyn's
    # refined poles against sdypy's diagram poles at order 60); 5e-5 holds that with margin.
    assert np.max(np.abs(f_ours / f_sdypy - 1)) < 5e-5
    # Damping ratios of 0.013-0.06 % on 1 Hz lines: the half-power band of mode 1 is 0.03 Hz,
    # thirty times narrower than a line, so its damping is barely observable and the two
    # differ by 2x (docs/ema.md); the others within 25 % (measured 1-18 %).
    assert 0.45 < z_ours[0] / z_sdypy[0] < 2.2
    assert np.max(np.abs(z_ours[1:] / z_sdypy[1:] - 1)) < 0.25
    # The regenerated FRFs correlate with the data (FRAC; sdypy's: 0.995-0.999).
    assert min(ours["correlation"]) > 0.99
    # Shapes: one per mode over the three responses, MPC of a real bending mode near 1.
    assert ours["shapes"].shape == (len(f_ours), 3)
    assert np.all(ours["mpc"] > 0.9)


@pytest.mark.parametrize("ratio", [1.2, 2.0, 5.0])
def test_cmif_peaks_are_scipys_prominent_peaks(repo, ratio):
    """The CMIF peak list against scipy.signal.find_peaks with the prominence taken on log
    sigma_1 (an independent implementation of the same definition), on the measured beam."""
    signal = pytest.importorskip("scipy.signal")
    frf = np.array([np.loadtxt(repo / "crates/lamdyn-ema/tests/fixtures/free-free-beam" / f"meas_point_{i}.txt",
                               dtype=complex) for i in (1, 2, 3)])
    freq = np.arange(frf.shape[1]) * 1.0
    ours = lamdyn.ema(freq[1:], frf[:, 1:], band_hz=(10, 1000), cmif_prominence=ratio)
    band = (freq[1:] >= 10) & (freq[1:] <= 1000)
    log_sigma = np.log(ours["cmif"][band, 0])
    peaks, _ = signal.find_peaks(log_sigma, prominence=np.log(ratio))
    want = freq[1:][band][peaks]
    got = np.array([p["freq_hz"] for p in ours["cmif_peaks"]])
    assert len(want) >= 4
    np.testing.assert_array_equal(got, want)


def test_cmif_prominence_below_one_is_refused():
    f = np.linspace(1, 100, 200)
    frf = (1 / (1 - (f / 50) ** 2 + 0.02j))[None, :]
    with pytest.raises(Exception, match="CMIF prominence"):
        lamdyn.ema(f, frf, cmif_prominence=0.5)

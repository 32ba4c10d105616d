"""`lamdyn ema --excitation sweep|random` against scipy.signal's Welch estimates on the measured
plate sweep (crates/lamdyn-ema/tests/fixtures/plate-sweep, MIT): H1 and coherence at every line
of 60-500 Hz, with each run whole (rectangular) and with Hann segments of 0.25 s, half
overlapping."""

import numpy as np
import pytest

sg = pytest.importorskip("scipy.signal")

FIXTURE = "crates/lamdyn-ema/tests/fixtures/plate-sweep"


@pytest.mark.parametrize(
    "flags, kw",
    [
        (["--excitation", "sweep"], dict(window="boxcar", nperseg=None, noverlap=0)),
        (["--excitation", "random", "--segment-s", "0.25", "--overlap", "0.5"],
         dict(window="hann", nperseg=6400, noverlap=3200)),
    ],
)
def test_h1_and_coherence_equal_scipys(repo, cli, tmp_path, flags, kw):
    d = repo / FIXTURE
    runs = [d / f"run{i}.csv" for i in (1, 2, 3, 4)]
    cli("ema", "--channels", d / "channels.csv", "--time", *runs, *flags, "--quantity", "accelerance",
        "--band-hz", "60,500", "--out", tmp_path / "out")
    pxy = pxx = pyy = 0.0
    for r in runs:
        a = np.loadtxt(r, delimiter=",", comments="#", skiprows=2)
        x, y = a[:, 1], a[:, 2]
        k = dict(kw, nperseg=kw["nperseg"] or len(x))
        f, p = sg.csd(x, y, fs=25600.0, detrend="constant", **k)
        pxy = pxy + p
        pxx = pxx + sg.welch(x, fs=25600.0, detrend="constant", **k)[1]
        pyy = pyy + sg.welch(y, fs=25600.0, detrend="constant", **k)[1]
    h1, coh = pxy / pxx, np.abs(pxy) ** 2 / (pxx * pyy)
    ours = np.loadtxt(tmp_path / "out" / "frf.csv", delimiter=",", skiprows=2)
    our_coh = np.loadtxt(tmp_path / "out" / "coherence.csv", delimiter=",", skiprows=1)
    band = (f >= 60) & (f <= 500)
    k = np.rint(f[band] / (ours[1, 0] - ours[0, 0])).astype(int)
    assert np.max(np.abs(ours[k, 0] - f[band])) < 1e-6
    err = np.abs(ours[k, 1] + 1j * ours[k, 2] - h1[band]) / np.abs(h1[band])
    print(f"\n{flags}: max relative H1 difference {err.max():.1e} over {band.sum()} lines")
    assert err.max() < 1e-9
    assert np.max(np.abs(our_coh[k, 1] - coh[band])) < 1e-9

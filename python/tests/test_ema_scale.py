"""FRFs in any unit: the measured dam (26 accelerance FRFs, BSD licence) scaled by 1e+100 and
1e-100 gives the same modes as the data as measured (the identification works at a unit scale
of its own, issue 46.5: before, both gave "no stable pole ... raise the order"), the shapes
and CMIF scaled alike; FRFs that are zero over the band are named as such."""
import pathlib

import numpy as np
import pytest

import lamdyn

DAM = pathlib.Path(__file__).parents[2] / "crates/lamdyn-ema/tests/fixtures/dam/dam0.unv"


@pytest.fixture(scope="module")
def dam():
    data = lamdyn.read_uff(str(DAM))
    return data.freqs_hz, data.frf[:, 0, :]


def identify(freqs, frf):
    return lamdyn.ema(freqs, frf, band_hz=(2.0, 12.5))


@pytest.mark.parametrize("factor", [1e100, 1e-100, 3.0])
def test_a_scaled_dam_gives_the_same_modes(dam, factor):
    freqs, frf = dam
    measured, scaled = identify(freqs, frf), identify(freqs, frf * factor)
    assert list(scaled["verdict"]) == list(measured["verdict"])
    # A factor that is not a power of two changes the data in their last bit (1e-16), and the
    # diagram's roots by ~1e-7 (test_uff_time measures 2.6e-8 for its band). Where that tips
    # the check between a mode's diagram pole and its refined pole, the two lie within the
    # poles' own sds; elsewhere the modes agree (below).
    # The refinement holds the LSCF model's roots outside the band, and a cluster of real roots
    # at the band's edge moves far more than the diagram's poles under a last-bit change: a
    # refined pole moves by up to 0.03 of its sd (measured on all three factors: 4e-4 of zeta,
    # 7e-6 of f), asserted at 0.1 sd; a diagram's pole stays within 1e-5.
    same = scaled["refined"] == measured["refined"]
    diagram = same & ~measured["refined"]
    for key, sd in (("freq_hz", "freq_sd_hz"), ("damping_ratio", "damping_sd")):
        moved = np.abs(scaled[key] - measured[key])
        assert np.all(moved <= 2 * measured[sd]), (key, moved / measured[sd])
        assert np.all(moved[same] <= 0.1 * measured[sd][same]), (key, moved / measured[sd])
        np.testing.assert_allclose(scaled[key][diagram], measured[key][diagram], rtol=1e-5)
    # The shapes (residues: every mode's shift in one least-squares fit moves all of them a
    # little) correlate as one shape, and scale with the data.
    a, b = scaled["shapes"], measured["shapes"]
    mac = np.abs(np.sum(a * b.conj(), 1)) ** 2 / (np.sum(np.abs(a) ** 2, 1) * np.sum(np.abs(b) ** 2, 1))
    assert np.all(mac > 0.99), mac
    np.testing.assert_allclose(
        np.linalg.norm(a[same], axis=1), np.linalg.norm(b[same], axis=1) * factor, rtol=1e-2
    )
    np.testing.assert_allclose(scaled["cmif"], measured["cmif"] * factor, rtol=1e-10)


def test_zero_frfs_are_named(dam):
    freqs, frf = dam
    with pytest.raises(lamdyn.LamdynError, match="every FRF is zero over the band"):
        identify(freqs, np.zeros_like(frf))

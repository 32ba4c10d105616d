"""lamdyn.master_curve on points from a known law (no simulation): exact points give the law
and the WLF constants back; noisy points keep the truth inside the 95 % intervals; Arrhenius;
bad input raises LamdynError."""

import numpy as np
import pytest

import lamdyn


def zener(f_hz, g0=0.8e6, ginf=1e9, tau=3e-7, alpha=0.4):
    s = (2j * np.pi * f_hz * tau) ** alpha
    return (g0 + ginf * s) / (1 + s)


def points(log10_shift, temps, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    t, f, g, eta = [], [], [], []
    for T in temps:
        for fr in (17.0, 25.0, 44.0, 51.0, 64.0):
            G = zener(fr * 10 ** log10_shift(T))
            t.append(T)
            f.append(fr)
            g.append(G.real * (1 + noise * rng.standard_normal()))
            eta.append(G.imag / G.real * (1 + 2 * noise * rng.standard_normal()))
    return dict(temperature_k=t, freq_hz=f, storage_pa=g, loss_factor=eta)


def wlf(c1=12.0, c2=90.0, tref=293.15):
    return lambda T: -c1 * (T - tref) / (c2 + T - tref)


TEMPS = [287.15, 290.15, 293.15, 296.15, 299.15]


def test_exact_points_give_the_constants_back():
    m = lamdyn.master_curve(**points(wlf(), TEMPS))
    assert abs(m["parameters"]["c1"]["value"] - 12.0) < 1e-3
    assert abs(m["parameters"]["c2_k"]["value"] - 90.0) < 1e-2
    assert abs(m["parameters"]["alpha"]["value"] - 0.4) < 1e-5
    # The curve at its reference temperature is the law.
    f = m["reduced_freq_hz"]
    np.testing.assert_allclose(m["storage_pa"], zener(f).real, rtol=1e-4)
    np.testing.assert_allclose(m["log10_a_t"], wlf()(m["temperatures_k"]), atol=1e-4)


def test_95_percent_intervals_cover_the_truth():
    """Coverage over 40 noisy cases (1 % in G', 2 % in eta, as the layered inverse's scatter).
    Measured on 200 seeds: the profile-likelihood intervals hold C1 and C2 in 94 %, alpha in
    92.5 % (the symmetric delta-method ones held C1 in 85 %); 85 % of 40 is the bound a true
    94 % passes with 99 % probability."""
    n, inside = 40, {"c1": 0, "c2_k": 0, "alpha": 0}
    truth = {"c1": 12.0, "c2_k": 90.0, "alpha": 0.4}
    for seed in range(n):
        m = lamdyn.master_curve(**points(wlf(), TEMPS, noise=0.01, seed=seed))
        for name in inside:
            lo, hi = m["parameters"][name]["ci95"]
            inside[name] += lo <= truth[name] <= hi
    print({k: v / n for k, v in inside.items()})
    assert all(v >= 0.85 * n for v in inside.values()), inside


def test_arrhenius():
    ea = 2.5e5  # J/mol
    shift = lambda T: ea / (8.314462618 * np.log(10)) * (1 / T - 1 / 293.15)  # noqa: E731
    m = lamdyn.master_curve(**points(shift, TEMPS), shift="arrhenius")
    assert abs(m["parameters"]["activation_energy_j_mol"]["value"] / ea - 1) < 1e-4


def test_bad_input_is_refused():
    p = points(wlf(), TEMPS[:1])
    with pytest.raises(lamdyn.LamdynError, match="temperature"):
        lamdyn.master_curve(**p)
    p = points(wlf(), TEMPS)
    p["storage_pa"][3] = -1.0
    with pytest.raises(lamdyn.LamdynError, match="point 3"):
        lamdyn.master_curve(**p)
    with pytest.raises(lamdyn.LamdynError, match="shift"):
        lamdyn.master_curve(**points(wlf(), TEMPS), shift="vft")
    with pytest.raises(lamdyn.LamdynError, match="temperature_k"):
        lamdyn.master_curve([{"job": "x.toml", "temperature_k": None, "modal": {}}])

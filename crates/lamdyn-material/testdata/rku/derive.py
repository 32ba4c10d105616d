#!/usr/bin/env python3
"""Independent reference for the RKU / Mead-Markus flexural rigidity with E2 = 0.

A three-layer beam of unit width in a sinusoidal wave w = W sin(kx): faces 1 and 3 bend
(Euler-Bernoulli) and stretch (axial amplitudes U1, U3); the core's axial displacement varies
linearly between the faces it joins and it carries shear G2 only (E2 = 0 here). The strain
energy per wavelength is minimised over U1, U3 for fixed W (static condensation; axial inertia
neglected, as in RKU and Mead-Markus), and EI = U / (k^4 W^2) up to the common factor.

Derived symbolically with sympy, evaluated in exact rationals, then printed to 17 digits.
Run: python3 derive.py > values.json   (sympy 1.14)
"""
import json
import sympy as sp

E1, E2, E3, H1, H2, H3, G2, k, W, U1, U3 = sp.symbols("E1 E2 E3 H1 H2 H3 G2 k W U1 U3", positive=True)
a = U1 - H1 * k * W / 2  # axial amplitude at the top of face 1
b = U3 + H3 * k * W / 2  # axial amplitude at the bottom of face 3
energy = (
    E1 * H1 * k**2 * U1**2 + E1 * H1**3 / 12 * k**4 * W**2
    + E3 * H3 * k**2 * U3**2 + E3 * H3**3 / 12 * k**4 * W**2
    + E2 * H2 / 3 * (a**2 + a * b + b**2) * k**2
    + G2 * H2 * ((b - a) / H2 + k * W) ** 2
)
sol = sp.solve([sp.diff(energy, U1), sp.diff(energy, U3)], [U1, U3], dict=True)[0]
ei = sp.simplify(energy.subs(sol) / (k**4 * W**2))

cases = []
for h1, h2, h3, e1, e3, g2, kk in [
    ("1.715e-3", "0.42e-3", "1.715e-3", "70e9", "70e9", "3e6", "10"),
    ("2e-3", "0.5e-3", "1.5e-3", "70e9", "50e9", "1e7", "20"),
    ("1e-3", "2e-3", "3e-3", "200e9", "70e9", "1e5", "3"),
    ("1.5e-3", "0.25e-3", "1.5e-3", "200e9", "200e9", "2e6", "60"),
]:
    vals = {E1: sp.Rational(e1), E2: 0, E3: sp.Rational(e3), H1: sp.Rational(h1), H2: sp.Rational(h2),
            H3: sp.Rational(h3), G2: sp.Rational(g2), k: sp.Rational(kk)}
    cases.append({
        "h1_m": float(h1), "h2_m": float(h2), "h3_m": float(h3),
        "e1_pa": float(e1), "e3_pa": float(e3), "g2_pa": float(g2), "k_rad_m": float(kk),
        "flexural_rigidity_n_m": float(sp.N(ei.subs(vals), 20)),
    })
print(json.dumps({"generated_by": "testdata/rku/derive.py (sympy 1.14)", "cases": cases}, indent=2))

#!/usr/bin/env python3
"""The independent reference for `lamdyn ema --excitation sweep` on the measured plate sweep:
H1 = sum Pxy / sum Pxx and the coherence |sum Pxy|^2 / (sum Pxx sum Pyy) over the four runs, each
run one segment (nperseg = its length, window 'boxcar', detrend 'constant', scipy.signal.csd and
welch), printed every 5 Hz on 60-500 Hz with full precision.

Usage: python3 tools/ema/plate_sweep_h1.py > crates/lamdyn-ema/tests/fixtures/plate-sweep/h1_scipy.csv
"""
import os

import numpy as np
import scipy.signal as sg

HERE = os.path.dirname(os.path.abspath(__file__))
DIR = os.path.join(HERE, "../../crates/lamdyn-ema/tests/fixtures/plate-sweep")
FS = 25600.0


def reference():
    pxy = pxx = pyy = 0.0
    for i in (1, 2, 3, 4):
        r = np.loadtxt(os.path.join(DIR, f"run{i}.csv"), delimiter=",", comments="#", skiprows=2)
        x, y = r[:, 1], r[:, 2]
        kw = dict(fs=FS, window="boxcar", nperseg=len(x), noverlap=0, detrend="constant")
        f, a = sg.csd(x, y, **kw)
        _, b = sg.welch(x, **kw)
        _, c = sg.welch(y, **kw)
        pxy, pxx, pyy = pxy + a, pxx + b, pyy + c
    return f, pxy / pxx, np.abs(pxy) ** 2 / (pxx * pyy)


if __name__ == "__main__":
    f, h1, coh = reference()
    print("f_hz,h1_re,h1_im,coherence")
    for target in np.arange(60.0, 500.0 + 1e-9, 5.0):
        k = int(round(target / (f[1] - f[0])))
        print(f"{float(f[k])!r},{float(h1[k].real)!r},{float(h1[k].imag)!r},{float(coh[k])!r}")

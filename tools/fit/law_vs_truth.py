#!/usr/bin/env python3
"""The FRF fit's law against the test bench's truth, and G' against the core thickness found.

Each RUN is `truth.csv:out_dir`: the truth's law as `lamdyn demo` writes it into the case's
input folder (truth.csv: f_hz, storage_pa, loss_pa, loss_factor, after one comment line) and
the output folder of `lamdyn run` (or `lamdyn demo`) on that case (core_frf_law.csv and
result.json). For each run it prints, over the band, the law's error in G' and eta against the
truth, how many lines hold the truth inside the law's 95 % band, and the inputs the fit found
beside the law (result.json's frf_fit.inputs, per cent).

With several runs it then fits G' at the band's log-middle as a constant per truth plus k
times the core thickness found (least squares): how much of the runs' spread in G' is where
the fit landed along the core thickness (docs/fit.md, "The mode's own error against the
line's").

Usage: law_vs_truth.py --band-hz 16,67 truth.csv:out [truth.csv:out ...]
Needs numpy only.
"""

import argparse
import json
import os
import sys

import numpy as np


def read_run(spec, band):
    truth_path, out = spec.split(":", 1)
    truth = np.genfromtxt(truth_path, delimiter=",", names=True, skip_header=1)
    law = np.genfromtxt(os.path.join(out, "core_frf_law.csv"), delimiter=",", names=True)
    with open(os.path.join(out, "result.json")) as f:
        result = json.load(f)
    f_hz = law["f_hz"]
    inside = (f_hz >= band[0]) & (f_hz <= band[1])
    if not inside.any():
        sys.exit(f"{out}: no line of core_frf_law.csv in {band[0]}-{band[1]} Hz")
    g_true = np.interp(f_hz, truth["f_hz"], truth["storage_pa"])
    eta_true = np.interp(f_hz, truth["f_hz"], truth["loss_factor"])
    inputs = {i["name"]: 100.0 * i["change"] for i in result["frf_fit"].get("inputs", [])}
    mid = np.exp(np.log(f_hz[inside]).mean())
    g_err = law["storage_pa"] / g_true - 1.0
    return {
        "truth": os.path.abspath(truth_path),
        "out": out,
        "g_err": 100.0 * g_err[inside],
        "eta_err": 100.0 * (law["loss_factor"] / eta_true - 1.0)[inside],
        "g_in": int(((law["storage_lo_pa"] <= g_true) & (g_true <= law["storage_hi_pa"]))[inside].sum()),
        "eta_in": int(((law["loss_factor_lo"] <= eta_true) & (eta_true <= law["loss_factor_hi"]))[inside].sum()),
        "lines": int(inside.sum()),
        "g_mid": 100.0 * np.interp(mid, f_hz, g_err),
        "inputs": inputs,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--band-hz", required=True, help="lo,hi in Hz")
    parser.add_argument("runs", nargs="+", help="truth.csv:out_dir")
    args = parser.parse_args()
    band = [float(v) for v in args.band_hz.split(",")]
    runs = [read_run(spec, band) for spec in args.runs]
    for r in runs:
        found = ", ".join(f"{k} {v:+.2f}" for k, v in r["inputs"].items())
        print(
            f"{r['out']}: G' {r['g_err'].min():+.2f} … {r['g_err'].max():+.2f} % "
            f"(log-middle {r['g_mid']:+.2f} %), eta {r['eta_err'].min():+.2f} … "
            f"{r['eta_err'].max():+.2f} %, in band {r['g_in']}, {r['eta_in']} of {r['lines']}; "
            f"inputs found (%): {found}"
        )
    with_thickness = [r for r in runs if "core thickness" in r["inputs"]]
    truths = sorted({r["truth"] for r in with_thickness})
    if len(with_thickness) <= len(truths):
        return
    x = np.array(
        [[float(r["truth"] == t) for t in truths] + [r["inputs"]["core thickness"]] for r in with_thickness]
    )
    y = np.array([r["g_mid"] for r in with_thickness])
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    resid = x @ coef - y
    print(
        f"G' at the log-middle = constant per truth + {coef[-1]:.2f} x core thickness found "
        f"(%), residual rms {np.sqrt(np.mean(resid ** 2)):.2f} %, max {np.abs(resid).max():.2f} % "
        f"over {len(y)} runs"
    )
    for t, c in zip(truths, coef):
        print(f"  at the true core thickness: {c:+.2f} %  ({t})")


if __name__ == "__main__":
    main()

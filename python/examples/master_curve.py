"""The core's master curve from impact tests at several temperatures, on a Dask cluster.

The demo roof (laminated glass, a PVB-like core) is tested virtually at five or more
temperatures: its core's law, given at 20 degC, is moved to each temperature by a WLF shift
(C1 = 12, C2 = 90 K: lamdyn.DEMO_WLF). Each test is written as a job folder, the jobs run as a
batch on a LocalCluster (lamdyn.batch), and one fractional Zener law with a WLF shift is fitted
to the cores found by the layered inverse at every mode and temperature (lamdyn.master_curve).
The recovered C1 and C2 are printed with their 95 % intervals beside the truth.

    python python/examples/master_curve.py [OUT] [--temperatures 14,17,20,23,26] [--workers 2]
                                           [--cache DIR]

Writes OUT/T<..>/ (each test's job and report), OUT/batch.csv, OUT/master_curve.csv (G' and
eta against reduced frequency with 95 % bands) and OUT/shift_factors.csv (log10 a_T(T)).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import lamdyn
import lamdyn.batch


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="?", default="lamdyn-master", help="results folder")
    ap.add_argument("--temperatures", default="14,17,20,23,26", help="test temperatures, degC")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    ap.add_argument("--address", default=None, help="scheduler address of a running cluster")
    ap.add_argument("--force", action="store_true", help="replace files lamdyn did not write")
    ap.add_argument(
        "--cache",
        default="shared",
        help="the batch's cache folder (default: .lamdyn-cache beside the jobs); another batch's "
        "cache lets a rerun, or a run with more temperatures, take the stages it already has",
    )
    args = ap.parse_args(argv)
    from distributed import Client, LocalCluster

    temps_k = [float(t) + 273.15 for t in args.temperatures.split(",")]
    if len(temps_k) < 3:
        print("give three or more temperatures (five or more to judge the WLF fit)", file=sys.stderr)
        return 2
    out = Path(args.out)
    wlf = lamdyn.DEMO_WLF
    clock = time.perf_counter()
    cluster = None
    if args.address:
        client = Client(args.address)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, dashboard_address=None)
        client = Client(cluster)
    try:
        # The virtual tests, one Dask task each.
        names = [f"T{t - 273.15:g}C" for t in temps_k]
        sims = client.map(
            lamdyn.write_demo_job,
            [str(out / n) for n in names],
            temps_k,
            force=args.force,
            pure=False,
        )
        jobs = client.gather(sims)
        print(f"simulated {len(jobs)} tests in {time.perf_counter() - clock:.1f} s", file=sys.stderr)
        batch = lamdyn.batch.run_batch(jobs, out=out / "reports", cache=args.cache, client=client, force=args.force)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    print(batch.table())
    if not batch.ok:
        print("some jobs failed: the master curve uses the others", file=sys.stderr)
    m = lamdyn.master_curve(batch.ordered_results(), reference_temperature_k=wlf["reference_temperature_k"])
    print(f"\nmaster curve at T_ref = {m['reference_temperature_k']:.2f} K from {m['points']} cores "
          f"(scatter {100 * m['residual_sd'][0]:.2f} % in G', {100 * m['residual_sd'][1]:.2f} % in eta)")
    truth = {"c1": wlf["c1"], "c2_k": wlf["c2_k"], "g0_pa": 0.8e6, "g_inf_pa": 1.0e9, "tau_s": 3e-7, "alpha": 0.4}
    inside = True
    for name, p in m["parameters"].items():
        lo, hi = p["ci95"]
        ok = lo <= truth[name] <= hi
        inside &= name not in ("c1", "c2_k") or ok
        print(f"  {name:<10} {p['value']:12.5g}  95 % [{lo:.5g}, {hi:.5g}]  truth {truth[name]:.5g}  {'inside' if ok else 'OUTSIDE'}")
    with open(out / "master_curve.csv", "w", encoding="utf-8") as f:
        f.write("reduced_freq_hz,storage_pa,storage_lo_pa,storage_hi_pa,loss_factor,loss_factor_lo,loss_factor_hi\n")
        for k in range(len(m["reduced_freq_hz"])):
            f.write(",".join(f"{v:.6e}" for v in (
                m["reduced_freq_hz"][k], m["storage_pa"][k], *m["storage_ci95"][:, k],
                m["loss_factor"][k], *m["loss_factor_ci95"][:, k])) + "\n")
    with open(out / "shift_factors.csv", "w", encoding="utf-8") as f:
        f.write("temperature_k,log10_a_t,log10_a_t_lo,log10_a_t_hi\n")
        for k in range(len(m["temperatures_k"])):
            f.write(f"{m['temperatures_k'][k]:.3f},{m['log10_a_t'][k]:.6f},"
                    f"{m['log10_a_t_ci95'][0, k]:.6f},{m['log10_a_t_ci95'][1, k]:.6f}\n")
    print(f"\nwritten to {out}/ in {time.perf_counter() - clock:.1f} s", file=sys.stderr)
    return 0 if inside else 1


if __name__ == "__main__":
    sys.exit(main())

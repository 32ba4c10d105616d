"""lamdyn.batch on a Dask LocalCluster with two workers: the demo roof at five temperatures
(14-26 degC, WLF core) gives the serial run's numbers and a master curve that recovers the
WLF constants; bad batches end with a report per job and nothing lost."""

import os
import re
import shutil
import signal
import threading
import time

import numpy as np
import pytest

import lamdyn
import lamdyn.batch
from conftest import TEMPERATURES_K


@pytest.fixture(scope="module")
def shared_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(scope="module")
def batch(temperature_jobs, shared_cache, tmp_path_factory):
    out = tmp_path_factory.mktemp("batch")
    t = time.perf_counter()
    b = lamdyn.batch.run_batch(temperature_jobs, out=out, cache=shared_cache, n_workers=2)
    b.wall_s = time.perf_counter() - t
    b.out = out
    return b


#: The batch's jobs that also run serially: the first and the last (the coldest and the
#: warmest core).
SERIAL = [0, len(TEMPERATURES_K) - 1]


@pytest.fixture(scope="module")
def serial(temperature_jobs):
    return [lamdyn.run(temperature_jobs[k], cache=None) for k in SERIAL]


def test_batch_equals_serial(batch, serial):
    print("\n" + batch.table() + f"\nwall {batch.wall_s:.1f} s on {os.cpu_count()} cores")
    assert batch.ok
    assert [r["status"] for r in batch.rows] == ["ok"] * len(TEMPERATURES_K)
    assert [r["temperature_k"] for r in batch.rows] == TEMPERATURES_K
    results = batch.ordered_results()
    for got, want in zip([results[k] for k in SERIAL], serial):
        for col, values in want["modal"].items():
            # The same code on the same data and thread count: the same doubles, whether a
            # stage came from the shared cache or not (entries hold the doubles' bytes).
            np.testing.assert_array_equal(got["modal"][col], values, err_msg=col)
    # One table at the end, beside each job's report.
    text = (batch.out / "batch.csv").read_text()
    assert text.count("\n") == 1 + len(TEMPERATURES_K)
    assert all((batch.out / r["name"] / "report.html").exists() for r in batch.rows)


def test_master_curve_recovers_the_wlf_constants(batch):
    # Measured 2026-11-29 (2 cores, three temperatures): c1 11.877 [9.999, 14.603] (truth 12),
    # c2 89.13 K [75.1, 109.5] (truth 90); docs/python.md's table. With five temperatures
    # (2026-11-26): c1 11.93 [10.50, 13.80], c2 89.5 K [78.9, 103.5]. Until the ladder's finer levels got three orders of core sensitivities
    # (2026-11-26) this was a strict xfail: the 14 degC roof's stiffer core came out 6-7 % stiff
    # and c1's interval [7.2, 11.6] missed 12.
    m = lamdyn.master_curve(batch.ordered_results(), reference_temperature_k=293.15)
    truth = lamdyn.DEMO_WLF
    for name in ("c1", "c2_k"):
        p = m["parameters"][name]
        print(f"{name}: {p['value']:.3f}, 95 % [{p['ci95'][0]:.3f}, {p['ci95'][1]:.3f}], truth {truth[name]}")
        assert p["ci95"][0] <= truth[name] <= p["ci95"][1]
    # The demo core at 20 degC: fractional Zener G0 0.8 MPa, Ginf 1 GPa, tau 3e-7 s, alpha 0.4.
    assert m["parameters"]["alpha"]["ci95"][0] <= 0.4 <= m["parameters"]["alpha"]["ci95"][1]
    assert m["points"] >= 4 * len(TEMPERATURES_K)
    # The layered inverse recovers each mode within ~1-2 %: the scatter about the curve says so.
    assert m["residual_sd"][0] < 0.02 and m["residual_sd"][1] < 0.04
    assert np.all(m["storage_ci95"][0] <= m["storage_pa"]) and np.all(m["storage_pa"] <= m["storage_ci95"][1])


def test_bad_batch_reports_each_job_and_keeps_the_others(temperature_jobs, shared_cache, tmp_path):
    bad = tmp_path / "bad" / "job.toml"
    bad.parent.mkdir()
    for f in temperature_jobs[0].parent.iterdir():
        if f.is_file():
            shutil.copy(f, bad.parent / f.name)
    text = bad.read_text()
    bad.write_text(text.replace("tolerance_m = ", "tolerance_m = -"))
    jobs = [temperature_jobs[0], tmp_path / "missing" / "job.toml", bad]
    lines = []
    b = lamdyn.batch.run_batch(jobs, out=tmp_path / "out", cache=shared_cache, progress=lines.append)
    print("\n" + b.table())
    assert [r["status"] for r in b.rows] == ["ok", "failed", "failed"]
    assert "does not exist" in b.rows[1]["error"]
    assert "tolerance_m" in b.rows[2]["error"]
    assert b.rows[0]["name"] in b.results and len(b.results) == 1
    assert len([line for line in lines if "failed" in line]) == 2
    assert (tmp_path / "out" / "batch.csv").read_text().count("failed") == 2


def test_a_killed_worker_s_job_is_rerun(temperature_jobs, batch, shared_cache, tmp_path):
    """One worker holds two jobs, one running and one queued behind it, and is killed 2 s into
    the first: its nanny starts a new worker, both jobs run there and give the batch's numbers,
    and the attempts count runs that started (2 and 1; Dask's own count said 2 and 2)."""
    import dask
    from distributed import Client, LocalCluster

    jobs = temperature_jobs[:2]
    # Every task goes to the worker at once, so the second one is queued there, not on the
    # scheduler.
    unqueued = {"distributed.scheduler.worker-saturation": float("inf")}
    with dask.config.set(unqueued), LocalCluster(
        n_workers=1, threads_per_worker=1, dashboard_address=None
    ) as cluster, Client(cluster) as client:
        done = {}
        th = threading.Thread(
            target=lambda: done.setdefault(
                "b", lamdyn.batch.run_batch(jobs, cache=shared_cache, client=client, progress=False)
            )
        )
        th.start()
        victim = None
        deadline = time.time() + 60
        while victim is None and time.time() < deadline:
            held = {w: ks for w, ks in client.processing().items() if sum("lamdyn-" in str(k) for k in ks) == 2}
            if held:
                time.sleep(2.0)  # inside the first job (about 7 s with the batch's cache)
                victim = next(iter(held))
            else:
                time.sleep(0.2)
        assert victim is not None, "the worker never held both jobs"
        pid = client.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)
        th.join(timeout=300)
        b = done["b"]
    print("\n" + b.table())
    assert b.ok, b.table()
    assert sorted(r["attempts"] for r in b.rows) == [1, 2], b.table()
    for name, want in zip([r["name"] for r in b.rows], batch.ordered_results()[:2]):
        np.testing.assert_array_equal(b.results[name]["modal"]["g_layered_storage_pa"], want["modal"]["g_layered_storage_pa"])


def test_the_master_curve_example_runs(repo, tmp_path, batch, shared_cache):
    """python/examples/master_curve.py as the README runs it (three temperatures here, to keep
    the suite short): tests simulated and run on its own LocalCluster, the curve written. It
    takes the batch fixture's cache (``--cache``): its tests are the same bytes, so their
    stages come from the cache, as a user's rerun would take them."""
    import subprocess
    import sys

    out = tmp_path / "m"
    p = subprocess.run(
        [sys.executable, str(repo / "python/examples/master_curve.py"), str(out), "--temperatures", "14,20,26",
         "--cache", str(shared_cache)],
        capture_output=True, text=True, timeout=900,
    )
    print(p.stdout[-3000:])
    assert p.returncode == 0, p.stderr[-3000:]
    assert "c1" in p.stdout and "inside" in p.stdout
    # docs/python.md's table is this run's output: it fails here when they part.
    printed = {
        m.group(1): [float(m.group(k)) for k in (2, 3, 4, 5)]
        for m in re.finditer(r"^  (\w+) +(\S+)  95 % \[(\S+), (\S+)\]  truth (\S+)", p.stdout, re.M)
    }
    documented = documented_master_curve(repo / "docs" / "python.md")
    assert set(documented) == set(printed), (documented, printed)
    for name, values in documented.items():
        np.testing.assert_allclose(printed[name], values, rtol=2e-3, err_msg=name)
    assert (out / "master_curve.csv").read_text().count("\n") == 61
    assert (out / "shift_factors.csv").exists() and (out / "reports" / "batch.csv").exists()


def documented_master_curve(path):
    """docs/python.md's master-curve table (between its generator's markers): per parameter,
    fitted value, 95 % interval and truth."""
    text = path.read_text(encoding="utf-8")
    start = text.index("<!-- master-curve table")
    table = text[start:text.index("<!-- end master-curve table -->", start)]
    rows = {}
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[0].startswith("`"):
            rows[cells[0].strip("`")] = [float(c) for c in cells[1:]]
    return rows

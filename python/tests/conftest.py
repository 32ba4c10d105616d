"""Shared fixtures: the lamdyn CLI (the reference the Python results must equal), the
repository's data, and the demo roof's virtual tests at five temperatures (simulated once per
session, on a LocalCluster: they are the slow part)."""

import os
import subprocess
import json
from pathlib import Path

import pytest

import lamdyn

REPO = Path(__file__).resolve().parents[2]
#: Temperatures of the master-curve batch, K (14, 20 and 26 degC: the WLF constants' two
#: parameters need three; five took 100 s more of the suite on 2 cores).
TEMPERATURES_K = [287.15, 293.15, 299.15]


@pytest.fixture(scope="session")
def lamdyn_exe():
    """The lamdyn binary: LAMDYN_BIN, default target/release/lamdyn."""
    exe = Path(os.environ.get("LAMDYN_BIN", REPO / "target" / "release" / "lamdyn"))
    if not exe.exists():
        pytest.fail(f"the lamdyn binary '{exe}' is missing: cargo build --release (or set LAMDYN_BIN)")
    return exe


@pytest.fixture(scope="session")
def cli(lamdyn_exe):
    """A function running the lamdyn binary (`lamdyn_exe`) and returning its --json output."""
    exe = lamdyn_exe

    def call(*args, check=True):
        p = subprocess.run([str(exe), *map(str, args), "--json"], capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"lamdyn {' '.join(map(str, args))} exited {p.returncode}: {p.stderr[-2000:]}")
        return json.loads(p.stdout) if p.stdout.strip() else None

    return call


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def temperature_jobs(tmp_path_factory):
    """Job files of the demo roof tested at TEMPERATURES_K (WLF core, lamdyn.DEMO_WLF)."""
    from distributed import Client, LocalCluster

    root = tmp_path_factory.mktemp("temperatures")
    outs = [str(root / f"T{t:.2f}") for t in TEMPERATURES_K]
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, Client(cluster) as client:
        jobs = client.gather(client.map(lamdyn.write_demo_job, outs, TEMPERATURES_K, pure=False))
    return [Path(j) for j in jobs]

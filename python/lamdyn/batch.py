"""Many lamdyn jobs as Dask tasks: a lab's temperatures, a plant's parts.

:func:`run_batch` submits one :func:`lamdyn.run` per job file to a Dask ``distributed``
cluster: a ``LocalCluster`` of ``n_workers`` processes by default, the scheduler at
``address`` for a real cluster, or a ``client`` you already hold. Dask schedules, retries and
reports; lamdyn adds only the job itself. The jobs share one cache folder, keyed by content
(the modal model, the EMA and the layered model of identical inputs are computed once and
read by every later job; entries are written under a unique name and renamed, so workers may
store at once). A job that fails (a missing file, bad input, a computation that finds no
answer) is reported with lamdyn's message and the others go on; a worker that dies in the
middle of a job is replaced by Dask and its job re-run on another worker, up to Dask's
``distributed.scheduler.allowed-failures`` (3 by default), then reported as failed.

The answer is a :class:`BatchResult`: one row per job, in the order given, and each job's
result as :func:`lamdyn.run` returns it; with ``out`` each job's report is written to
``out/<name>/`` and the table to ``out/batch.csv`` and ``out/batch.json``.

Requires ``dask[distributed]`` (``pip install "lamdyn[batch]"``). In a script, call
:func:`run_batch` under ``if __name__ == "__main__":``: the local cluster's workers start by
importing the script, and a batch at its top level would start again in each of them.
"""

from __future__ import annotations

import csv
import io
import json
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional, Sequence, Union

import lamdyn

__all__ = ["BatchResult", "run_batch", "job_names"]

PathLike = Union[str, os.PathLike]

_COLUMNS = ("name", "job", "status", "temperature_k", "modes", "attempts", "seconds", "error")


@dataclass
class BatchResult:
    """What a batch gave.

    Attributes:
        rows: one dict per job, in the order given: ``name``, ``job``, ``status`` (``ok`` or
            ``failed``), ``temperature_k``, ``modes`` (modal frequencies with a core),
            ``attempts`` (how many times the job started: 1, or more when a worker died in
            the middle of it), ``seconds`` (the job's own time),
            ``error`` (lamdyn's message, or the worker's death).
        results: each successful job's result (as :func:`lamdyn.run` returns it), by name.
    """

    rows: list = field(default_factory=list)
    results: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Whether every job succeeded."""
        return all(r["status"] == "ok" for r in self.rows)

    @property
    def failed(self) -> list:
        """The rows of the jobs that failed."""
        return [r for r in self.rows if r["status"] != "ok"]

    def ordered_results(self) -> list:
        """The successful jobs' results, in the order the jobs were given."""
        return [self.results[r["name"]] for r in self.rows if r["status"] == "ok"]

    def to_csv(self) -> str:
        """The table as CSV text."""
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=_COLUMNS, lineterminator="\n")
        w.writeheader()
        for r in self.rows:
            w.writerow({k: ("" if r[k] is None else r[k]) for k in _COLUMNS})
        return buf.getvalue()

    def table(self) -> str:
        """The table as aligned text (one line per job)."""
        lines = [f"{'name':<24} {'status':<7} {'T (K)':>8} {'modes':>5} {'tries':>5} {'s':>7}  error"]
        for r in self.rows:
            t = "" if r["temperature_k"] is None else f"{r['temperature_k']:.2f}"
            lines.append(
                f"{r['name']:<24} {r['status']:<7} {t:>8} {r['modes']:>5} {r['attempts']:>5} "
                f"{r['seconds']:>7.1f}  {r['error'] or ''}"
            )
        return "\n".join(lines)


def job_names(jobs: Sequence[PathLike]) -> list:
    """A unique, readable name per job: its folder's name for ``*/job.toml``, else the file's
    stem; repeated names get ``-2``, ``-3``..."""
    names, seen = [], {}
    for j in jobs:
        p = Path(j)
        base = p.parent.name if p.stem == "job" and p.parent.name else p.stem
        n = seen.get(base, 0) + 1
        seen[base] = n
        names.append(base if n == 1 else f"{base}-{n}")
    return names


# The scheduler's event topic on which each run of a job says that it started.
_ATTEMPT_TOPIC = "lamdyn-batch-attempt"


def _run_one(job: str, out: Optional[str], cache: Optional[str], samples, seed, force) -> dict:
    """One job on a worker: its result, or lamdyn's error as data (not an exception, so the
    batch goes on and the message is kept whole)."""
    _say_attempt_started()
    t = time.perf_counter()
    try:
        r = lamdyn.run(job, out=out, cache=cache, samples=samples, seed=seed, force=force)
        return {"ok": True, "result": r, "seconds": time.perf_counter() - t, "error": None}
    except lamdyn.LamdynError as e:
        return {"ok": False, "result": None, "seconds": time.perf_counter() - t, "error": str(e)}


def _say_attempt_started() -> None:
    """Logs this task's start on the scheduler (:data:`_ATTEMPT_TOPIC`), so that the batch
    counts runs that started. The scheduler's own count (``suspicious``) also blames a task
    that was only queued on a worker when it died."""
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):  # called outside a Dask worker
        return
    worker.log_event(_ATTEMPT_TOPIC, {"key": str(worker.get_current_task())})


def _default_cache(jobs: Sequence[PathLike]) -> Path:
    parents = [os.path.abspath(Path(j).parent) for j in jobs]
    return Path(os.path.commonpath(parents)) / ".lamdyn-cache"


def run_batch(
    jobs: Sequence[PathLike],
    *,
    out: Optional[PathLike] = None,
    cache: Union[PathLike, None, str] = "shared",
    client: Any = None,
    address: Optional[str] = None,
    n_workers: int = 2,
    samples: Optional[int] = None,
    seed: Optional[int] = None,
    force: bool = False,
    progress: Union[bool, Callable[[str], None]] = True,
) -> BatchResult:
    """Runs the job files as Dask tasks and collects one table (module docs).

    Args:
        jobs: job files (``lamdyn run`` jobs).
        out: a folder for the reports (``out/<name>/``) and the table (``batch.csv``,
            ``batch.json``); None: no files written.
        cache: the shared cache folder: ``"shared"`` (``.lamdyn-cache`` in the jobs' common
            folder), a path, or None (no cache).
        client: a ``distributed.Client`` to use (its cluster is left running).
        address: a scheduler address (``tcp://host:8786``) when no ``client`` is given.
        n_workers: processes of the ``LocalCluster`` started when neither is given (one
            thread each: lamdyn's own threads use the cores).
        samples, seed: override each job's Monte Carlo.
        force: passed to each report folder (see :func:`lamdyn.run`).
        progress: print a line per finished job to stderr (True), stay quiet (False), or a
            function that takes each line.
    """
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError as e:  # pragma: no cover
        raise lamdyn.LamdynError(
            'lamdyn.batch needs Dask: pip install "dask[distributed]" (or "lamdyn[batch]")'
        ) from e
    say = (lambda s: print(s, file=sys.stderr, flush=True)) if progress is True else (progress or (lambda s: None))
    jobs = [os.path.abspath(os.fspath(j)) for j in jobs]
    if not jobs:
        raise lamdyn.LamdynError("run_batch: no job files given")
    names = job_names(jobs)
    if cache == "shared":
        cache = _default_cache(jobs)
    cache = None if cache is None else os.fspath(cache)
    out_root = None if out is None else Path(out)
    if out_root is not None:
        out_root.mkdir(parents=True, exist_ok=True)

    own_client = None
    cluster = None
    if client is None:
        if address is not None:
            client = own_client = Client(address)
        else:
            cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None)
            client = own_client = Client(cluster)
    try:
        futures = {}
        for job, name in zip(jobs, names):
            report = None if out_root is None else os.fspath(out_root / name)
            # pure=False: a job is run each time it is asked for, never taken from Dask's memory.
            f = client.submit(_run_one, job, report, cache, samples, seed, force, key=f"lamdyn-{name}-{time.time_ns()}", pure=False)
            futures[f] = (job, name)
        say(f"lamdyn.batch: {len(jobs)} job(s) on {len(client.scheduler_info().get('workers', {}))} worker(s)")
        outcome = {}
        done = 0
        for f in as_completed(list(futures)):
            job, name = futures[f]
            done += 1
            try:
                outcome[name] = f.result()
            except Exception as e:  # a worker died more often than allowed, or Dask failed
                outcome[name] = {
                    "ok": False,
                    "result": None,
                    "seconds": float("nan"),
                    "error": f"{type(e).__name__}: {e}",
                }
            o = outcome[name]
            state = "ok" if o["ok"] else f"failed: {o['error']}"
            say(f"lamdyn.batch: {done}/{len(jobs)} {name} {state}")
        attempts = _attempts(client, futures)
    finally:
        if own_client is not None:
            own_client.close()
        if cluster is not None:
            cluster.close()

    result = BatchResult()
    for job, name in zip(jobs, names):
        o = outcome[name]
        r = o["result"]
        result.rows.append(
            {
                "name": name,
                "job": job,
                "status": "ok" if o["ok"] else "failed",
                "temperature_k": None if r is None else r.get("temperature_k"),
                "modes": 0 if r is None else int(len(r["modal"]["f_hz"])),
                "attempts": attempts[name],
                "seconds": o["seconds"],
                "error": o["error"],
            }
        )
        if r is not None:
            result.results[name] = r
    if out_root is not None:
        (out_root / "batch.csv").write_text(result.to_csv(), encoding="utf-8")
        (out_root / "batch.json").write_text(json.dumps(result.rows, indent=1), encoding="utf-8")
    return result


def _attempts(client: Any, futures: dict) -> dict:
    """How many times each job started, from the events its runs logged (a worker's death
    in the middle of a job makes two; a job only queued there still counts one)."""
    names = {str(f.key): name for f, (_, name) in futures.items()}
    counts = {name: 0 for name in names.values()}
    for _, event in client.get_events(_ATTEMPT_TOPIC):
        name = names.get(event.get("key")) if isinstance(event, dict) else None
        if name is not None:
            counts[name] += 1
    return counts

"""Runs a sweep's pending points on a Dask cluster and writes its table.

By default a LocalCluster is started with one single-threaded worker process per core (no
set-up); given a scheduler address (``tcp://host:8786``) the points go to that existing
cluster instead, whose workers must import the same gpme_core and gpme_study.  With
``in_process=True`` the points run one after another in the calling process, without Dask
(tiny sweeps, tests, a debugger).  The crane's points run gpme_study.point.run_point, a
model file's gpme_study.model_point.run_model_point.  Finished
points are stored one by one (gpme_study.store), so an interrupted sweep resumes where it
stopped; a point that fails is a row with its status and error, never a stopped sweep.
"""
import json
import logging
import os
import time
from pathlib import Path

import pandas as pd

from gpme_core.atomic import atomic_write_bytes, atomic_write_text

from .point import point_key, run_point
from .store import ResultStore


def point_job(spec):
    """(key function, point function, leading arguments) of ``spec``'s points:
    key(*args, point, settings) and run(*args, point, settings)."""
    if spec.model is None:
        return point_key, run_point, ()
    from .model_point import model_point_key, run_model_point
    return model_point_key, run_model_point, (spec.model,)

TABLE_CSV = "results.csv"
TABLE_PARQUET = "results.parquet"


def _client(scheduler, n_workers):
    from dask.distributed import Client, LocalCluster
    if scheduler:
        return Client(scheduler)
    cluster = LocalCluster(n_workers=n_workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR)
    client = Client(cluster)
    client._gpme_own_cluster = cluster     # closed with the client in run_sweep
    return client


def run_sweep(spec, out_dir, scheduler=None, n_workers=None, retry_errors=False,
              report=print, in_process=False):
    """Run every point of ``spec`` (a gpme_study.spec.SweepSpec) not yet in ``out_dir``.

    scheduler    : address of an existing Dask scheduler, or None for a local cluster
    n_workers    : worker processes of the local cluster (default: one per core)
    retry_errors : recompute stored points whose status is 'error' (an unexpected failure,
                   e.g. a lost worker; 'infeasible', 'diverged', 'invalid' are kept)
    report       : callable taking one progress line (str), or None
    in_process   : run the points here, one after another, without Dask
    Returns the table (one row per point, in spec order; see gpme_study.point.run_point)
    and writes it as <out_dir>/results.csv and results.parquet; df.attrs holds the counts
    and the wall time of this call.
    """
    out = Path(out_dir)
    store = ResultStore(out)
    report = report or (lambda line: None)
    key_of, run, args = point_job(spec)
    keys = [key_of(*args, p, spec.run) for p in spec.points]
    pending = {}
    for key, point in zip(keys, spec.points):
        row = store.load(key)
        if row is None or (retry_errors and row.get("status") == "error"):
            pending.setdefault(key, point)
    n_cached = len(set(keys)) - len(pending)
    report(f"{len(spec.points)} points ({len(set(keys))} distinct): {n_cached} already done, "
           f"{len(pending)} to run")
    start = time.perf_counter()
    n_workers_used = 0
    if pending and in_process:
        n_workers_used = 0
        for done, (key, point) in enumerate(pending.items(), 1):
            row = run(*args, point, spec.run)
            store.save(row)
            _report_point(report, done, len(pending), key, row)
    elif pending:
        n_workers_used = _compute(pending, spec, store, scheduler, n_workers, report)
    wall = time.perf_counter() - start
    table = assemble_table(spec, keys, store)
    table.attrs.update(points=len(spec.points), computed=len(pending), cached=n_cached,
                       wall_time_s=wall, workers=n_workers_used)
    write_table(table, out)
    atomic_write_text(out / "last_run.json", json.dumps(dict(table.attrs), indent=1))
    return table


def _report_point(report, done, total, key, row):
    report(f"[{done}/{total}] {key} {row['status']}"
           + (f" {row.get('wall_time_s', float('nan')):.1f} s" if row["status"] == "ok"
              else f": {row['error'][:120]}"))


def _compute(pending, spec, store, scheduler, n_workers, report):
    from dask.distributed import as_completed
    _, run, args = point_job(spec)
    client = _client(scheduler, n_workers)
    try:
        n_workers_used = len(client.scheduler_info().get("workers", {}))
        report(f"dask: {n_workers_used} workers at {client.scheduler.address}")
        futures = {client.submit(run, *args, point, spec.run, key=f"gpme-point-{key}",
                                 pure=False): key for key, point in pending.items()}
        done = 0
        for fut in as_completed(futures):
            key = futures[fut]
            try:
                row = fut.result()
            except Exception as exc:   # a lost worker or unpicklable result: record it
                row = {"key": key, **pending[key], "status": "error", "failed_run": "",
                       "error": f"{type(exc).__name__}: {exc}"}
            store.save(row)
            done += 1
            _report_point(report, done, len(pending), key, row)
    finally:
        cluster = getattr(client, "_gpme_own_cluster", None)
        client.close()
        if cluster is not None:
            cluster.close()
    return n_workers_used


def assemble_table(spec, keys, store):
    """The table in spec order: key, status, error, failed_run, every parameter of the
    spec (values from the spec: a stored row may come from an equal point written with
    other names swept), the metrics, then the remaining columns."""
    params = []
    for point in spec.points:
        params += [nm for nm in point if nm not in params]
    rows = []
    for key, point in zip(keys, spec.points):
        row = store.load(key)
        if row is not None:
            rows.append({**row, **point})
    head = ["key", "status", "error", "failed_run"] + params + list(spec.metric_table)
    table = pd.DataFrame(rows)
    for col in head:
        if col not in table:
            table[col] = pd.Series(dtype=float)
    return table[head + [c for c in table.columns if c not in head]]


def write_table(table, out_dir):
    """<out_dir>/results.csv and results.parquet (atomically); returns their paths."""
    out = Path(out_dir)
    paths = {"csv": out / TABLE_CSV, "parquet": out / TABLE_PARQUET}
    atomic_write_text(paths["csv"], table.to_csv(index=False))
    import io
    buf = io.BytesIO()
    clean = table.copy()
    clean.attrs = {}
    clean.to_parquet(buf, index=False)
    atomic_write_bytes(paths["parquet"], buf.getvalue())
    return paths

"""Runs a sweep's pending points on a Dask cluster and writes its table.

By default a local cluster (gpme_io.dask_cluster) is started with one single-threaded
worker process per core (no set-up); given a scheduler address (``tcp://host:8786``) the points go to that existing
cluster instead, whose workers must import the same gpme_core and gpme_study.  With
``in_process=True`` the points run one after another in the calling process, without Dask
(tiny sweeps, tests, a debugger).  The crane's points run gpme_study.point.run_point, a
model file's gpme_study.model_point.run_model_point.  Finished
points are stored one by one (gpme_study.store), so an interrupted sweep resumes where it
stopped; a point that fails is a row with its status and error, never a stopped sweep.
"""
import io
import json
import math
import time
from pathlib import Path

import pandas as pd

from gpme_core.integrate import simulate
from gpme_examples.crane import CraneParameters, crane_system, initial_state
from gpme_io.atomic import atomic_write_bytes, atomic_write_text
from gpme_io.dask_cluster import ClusterError
from gpme_io.dask_cluster import as_completed, close, connect, local_client, worker_count

from .store import ResultStore
from .sweep_kinds import sweep_kind


# progress lines of a sweep whose output is not a terminal (a log): about this many
MAX_LOG_LINES = 20
TABLE_CSV = "results.csv"
TABLE_PARQUET = "results.parquet"


def point_job(spec):
    """(key function, point function, leading arguments) of ``spec``'s points:
    key(*args, point, settings) and run(*args, point, settings)."""
    return sweep_kind(spec).point_job(spec)


def run_sweep(spec, out_dir, scheduler=None, n_workers=None, retry_errors=False,
              report=print, in_process=False, client=None, terminal=True):
    """Run every point of ``spec`` (a gpme_study.spec_points.SweepSpec) not yet in ``out_dir``.

    scheduler    : address of an existing Dask scheduler, or None for a local cluster
    n_workers    : worker processes of the local cluster (default: one per core)
    retry_errors : recompute stored points whose status is 'error' (an unexpected failure,
                   e.g. a lost worker; 'infeasible', 'diverged', 'invalid' are kept)
    report       : callable taking one progress line (str), or None
    in_process   : run the points here, one after another, without Dask
    client       : a connected Dask client to use instead of ``scheduler`` (closed here)
    terminal     : progress for a terminal (a line per point) or for a log (at most
                   about MAX_LOG_LINES lines; see PointProgress)
    Returns the table (one row per point, in spec order; see gpme_study.point.run_point)
    and writes it as <out_dir>/results.csv and results.parquet; df.attrs holds the counts
    and the wall time of this call.

    Every finished point is stored at once, atomically (gpme_study.store).  An
    interruption (KeyboardInterrupt, or gpme.cli.Terminated for SIGTERM) propagates at
    once: the points stored so far and any earlier table stay whole (every file is
    written to a temporary file in its folder and moved into place), the cluster is closed.
    """
    out = Path(out_dir)
    store = ResultStore(out)
    report = report or (lambda line: None)
    _, run, args = point_job(spec)
    keys, pending = pending_points(spec, out, retry_errors)
    n_cached = len(set(keys)) - len(pending)
    report(f"{len(spec.points)} points ({len(set(keys))} distinct): {n_cached} already done, "
           f"{len(pending)} to run")
    start = time.perf_counter()
    n_workers_used = 0
    progress = PointProgress(report, len(pending), terminal)
    if not pending or in_process:
        if client is not None:
            client.close()
        for key, point in pending.items():
            row = run(*args, point, spec.run)
            store.save(row)
            progress.point(key, row)
    else:
        if client is None and scheduler:
            client, problem = connect(scheduler)
            if client is None:
                raise ClusterError(problem)
        elif client is None:
            client = local_client(n_workers)
        try:
            n_workers_used = _compute(pending, spec, store, client, progress, report)
        finally:
            close(client)
    wall = time.perf_counter() - start
    table = assemble_table(spec, keys, store)
    table.attrs.update(points=len(spec.points), computed=len(pending), cached=n_cached,
                       wall_time_s=wall, workers=n_workers_used)
    write_table(table, out)
    atomic_write_text(out / "last_run.json", json.dumps(dict(table.attrs), indent=1))
    return table


def pending_points(spec, out_dir, retry_errors=False):
    """(keys of every point in spec order, {key: point} of those not stored in ``out_dir``
    yet, or stored with status 'error' when ``retry_errors``)."""
    store = ResultStore(out_dir)
    key_of, _, args = point_job(spec)
    keys = [key_of(*args, p, spec.run) for p in spec.points]
    pending = {}
    for key, point in zip(keys, spec.points):
        if key in pending:
            continue
        row = store.load(key)
        if row is None or (retry_errors and row.get("status") == "error"):
            pending[key] = point
    return keys, pending


class PointProgress:
    """Progress lines of the points.  On a terminal, one per finished point; elsewhere (a
    log, a pipe) at most about MAX_LOG_LINES: every ceil(n / MAX_LOG_LINES)-th point and
    the last, with the counts by status.  Each line gives the time left at the rate
    measured so far, from the first point on (the kernels are compiled or loaded before,
    gpme_study.cost and _warm_up_worker, and said so)."""

    def __init__(self, report, total, terminal=True):
        self.report, self.total = report, total
        self.every = 1 if terminal else max(1, math.ceil(total / MAX_LOG_LINES))
        self.start = time.perf_counter()
        self.counts, self.done = {}, 0

    def point(self, key, row):
        """Count one finished point (its row) and report if it is a reporting one."""
        self.done += 1
        status = row.get("status", "error")
        self.counts[status] = self.counts.get(status, 0) + 1
        if self.done % self.every and self.done != self.total:
            return
        elapsed = time.perf_counter() - self.start
        left = elapsed / self.done * (self.total - self.done)
        timing = (f"; {elapsed:.0f} s elapsed, ~{left:.0f} s left" if self.done < self.total
                  else f"; {elapsed:.0f} s")
        if self.every == 1:
            what = f"{key} {status}" + (
                f" {row.get('wall_time_s', float('nan')):.1f} s" if status == "ok"
                else f": {str(row.get('error', ''))[:120]}")
        else:
            what = ", ".join(f"{n} {s}" for s, n in sorted(self.counts.items()))
        self.report(f"[{self.done}/{self.total}] {what}{timing}")


def _warm_up_worker():
    """Compile the numba kernels (or load them from numba's on-disk cache) on a Dask
    worker before its first point, so that point's time is its own (running this function
    there imports this module, and with it gpme and both kinds of points, gpme_study.point
    and gpme_study.model_point): a few RK4 steps of the flexible crane with every row
    recorded (the solve, the history's frame positions and energies)."""
    params = CraneParameters()
    system = crane_system(1, params)
    q0, q_dot0 = initial_state(system.model, params)
    simulate(system, 5e-5, q0, q_dot0, dt=1e-5, output_dt=1e-5, on_manifold=True)


def _compute(pending, spec, store, client, progress, report):
    _, run, args = point_job(spec)
    workers = worker_count(client)
    report(f"dask: {workers} workers at {client.scheduler.address}; importing gpme and "
           "compiling the numba kernels on each (first call) ...")
    start = time.perf_counter()
    client.run(_warm_up_worker)
    report(f"  workers ready in {time.perf_counter() - start:.1f} s")
    progress.start = time.perf_counter()
    futures = {client.submit(run, *args, point, spec.run, key=f"gpme-point-{key}",
                             pure=False): key for key, point in pending.items()}
    for fut in as_completed(futures):
        key = futures[fut]
        try:
            row = fut.result()
        except Exception as exc:   # a lost worker or unpicklable result: record it
            row = {"key": key, **pending[key], "status": "error", "failed_run": "",
                   "error": f"{type(exc).__name__}: {exc}"}
        store.save(row)
        progress.point(key, row)
    return workers


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
    buf = io.BytesIO()
    clean = table.copy()
    clean.attrs = {}
    clean.to_parquet(buf, index=False)
    atomic_write_bytes(paths["parquet"], buf.getvalue())
    return paths

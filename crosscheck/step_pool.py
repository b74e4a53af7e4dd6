"""Verify's steps run one after another in this process, or at once on a Dask cluster.

In process (:func:`run_in_process`): each step writes straight into the run's staging
directory and logs as it goes.  On a cluster (:func:`run_on_cluster`, the client of
gpme_io.dask_cluster: a local cluster of one single-threaded worker process per core, or
``--scheduler ADDRESS``): every (step, scenario) pair is one task
(crosscheck.verify_steps.run_part), submitted longest step first (by the step times of the
previous report, or :data:`TYPICAL_ORDER`), so the models of one run spread over the
workers too; one part per worker thread is in flight, the next submitted when one ends, so
a worker that frees up takes the next part instead of waiting behind a busy one.  A
worker runs its part in a temporary directory of its own and returns the part, the bytes
of every file it wrote (written here, atomically, under the staging directory: workers on
other machines need no shared file system) and its log records
(printed here when the part ends).  When a step's parts are all back, its page and rows
are made here (verify_steps.finish_step).  Either way the gpme runs several steps compare
against are computed once (crosscheck.run_memo, on a directory under the staging
directory, removed before the report is published; shared between the workers of one
machine).
"""
import logging
import tempfile
import uuid
import warnings
from collections import deque
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from gpme_core.errors import OutputWriteError
from gpme_io import dask_cluster
from gpme_io.atomic import atomic_write_bytes

from . import run_memo, verify_steps
from .verify_steps import PartOutcome, StepOutcome

log = logging.getLogger("gpme.verify")
# the steps, longest first, when no earlier report gives their times (crane, quick and
# full runs of this machine, 2026-11; MuJoCo's and Pinocchio's take about as long, and
# MuJoCo goes first: its finish here, the report's figures and 3D pages, is the longest
# of any step, better done while the workers still run parts than after the last one)
TYPICAL_ORDER = ("exudyn", "continuum", "drake", "mujoco", "pinocchio", "gpme")
# where the shared gpme runs live during the run (under the staging directory)
SHARED_RUNS_DIR = ".shared_runs"

Record = Tuple[str, int, str]      # (logger name, level, message)


def run_in_process(steps: Sequence[str], staging: Path, scenarios, quick, progress,
                   max_wall_s, on_done: Callable[[StepOutcome], None]) -> Dict[str, int]:
    """Run ``steps`` here, one after another, into ``staging``; on_done(outcome) after each.
    Returns {"computed": n, "shared": n}: the gpme runs the steps computed and those one
    step found already computed by another (crosscheck.run_memo)."""
    with run_memo.shared_runs(Path(staging) / SHARED_RUNS_DIR) as counts:
        for step in steps:
            log.info(f"[{step}] ...")
            on_done(verify_steps.run_step(step, staging, scenarios, quick, progress,
                                          max_wall_s))
        return dict(counts)


def submission_order(steps: Sequence[str], previous_times: Optional[Dict[str, float]]) -> List[str]:
    """``steps`` longest first: by ``previous_times`` (s, the last report's step times) for
    the steps it has, the others before them in :data:`TYPICAL_ORDER` (unknown ones first)."""
    previous_times = previous_times or {}
    typical = {s: i for i, s in enumerate(TYPICAL_ORDER)}
    return sorted(steps, key=lambda s: (s in previous_times, -previous_times.get(s, 0.0),
                                        typical.get(s, -1)))


def part_name(step: str, scenario_name: str) -> str:
    """The name of one part in the report's part times: "<step>/<scenario>"."""
    return f"{step}/{scenario_name}"


def part_order(plan: Dict[str, list], previous: Optional[Dict[str, float]]) -> list:
    """[(step, index, scenario)] of ``plan`` ({step: scenarios}, longest step first): the
    longest part first by ``previous`` ({part name: s}, the last report's part times),
    parts it does not have before them (in the plan's order); without ``previous`` the
    plan's order.  Longest first keeps a long part from starting last and the workers
    finish close together."""
    parts = [(step, index, scenario) for step, chosen in plan.items()
             for index, scenario in enumerate(chosen)]
    if not previous:
        return parts
    rank = {p[:2]: k for k, p in enumerate(parts)}

    def key(p):
        seconds = previous.get(part_name(p[0], p[2].name))
        return (seconds is not None, -(seconds or 0.0), rank[p[:2]])
    return sorted(parts, key=key)


def run_on_cluster(client, steps: Sequence[str], staging: Path, scenarios, quick, max_wall_s,
                   on_done: Callable[[StepOutcome], None],
                   previous_times: Optional[Dict[str, float]] = None,
                   previous_part_times: Optional[Dict[str, float]] = None,
                   part_times: Optional[Dict[str, float]] = None) -> Tuple[int, Dict[str, int]]:
    """Run the parts of ``steps`` as tasks on ``client``'s cluster; write each part's files
    into ``staging`` and replay its log records as it ends, finish a step (its page, rows
    and on_done(outcome)) when its parts are all back.  Returns (the number of workers,
    {"computed": n, "shared": n} gpme runs over all parts, as :func:`run_in_process`).  A
    task that raises OutputWriteError raises here; one that fails otherwise (a lost worker)
    is a crashed part of its step (the step's crash row).

    previous_times, previous_part_times : {step: s}, {part name: s} of the last report (the
        order of submission: :func:`submission_order`, :func:`part_order`)
    part_times : a dict filled with {part name: s} of this run (for the report)"""
    staging = Path(staging)
    shared = str(staging.resolve() / SHARED_RUNS_DIR)
    order = submission_order(steps, previous_times)
    workers = dask_cluster.worker_count(client)
    plan = {}
    for step in order:
        chosen = verify_steps.step_scenarios(step, scenarios, quick)
        if chosen is None:
            on_done(verify_steps.missing_step(step, staging))
        elif not chosen:
            on_done(verify_steps.finish_step(step, staging, [], quick))
        else:
            plan[step] = chosen
    n_parts = sum(len(c) for c in plan.values())
    log.info(f"[dask] {n_parts} parts of {len(plan)} steps on {workers} workers at "
             f"{client.scheduler.address}, longest step first: {', '.join(plan)}")
    token = uuid.uuid4().hex[:8]
    pending = deque(part_order(plan, previous_part_times))
    futures = {}
    completed = dask_cluster.as_completed([])

    def submit_next():
        step, index, scenario = pending.popleft()
        future = client.submit(part_task, step, index, scenario, shared, quick, max_wall_s,
                               key=f"gpme-verify-{step}-{index}-{token}", pure=False)
        futures[future] = (step, index)
        completed.add(future)

    # as many parts in flight as the workers run at once, the next one submitted when one
    # ends: Dask would otherwise queue parts on a busy worker ahead of time (their length
    # is unknown to it) while another stands idle (measured: a worker idle 17-29 s of a
    # full crane verify after its long Exudyn part ended)
    for _ in range(min(dask_cluster.thread_count(client), len(pending))):
        submit_next()
    done: Dict[str, List[PartOutcome]] = {step: [] for step in plan}
    shared_runs = {"computed": 0, "shared": 0}
    try:
        for future in completed:
            if pending:
                submit_next()
            try:
                outcome, files, records, counts = future.result()
            except OutputWriteError:
                raise
            except Exception as exc:   # a lost worker (Dask's KilledWorker), a part that
                # cannot travel back: that part crashed, the run goes on
                step, index = futures[future]
                outcome, files, records = verify_steps.crashed_part(step, index, exc), {}, []
                counts = {}
            for key in shared_runs:
                shared_runs[key] += counts.get(key, 0)
            for relative, data in files.items():
                atomic_write_bytes(staging / relative, data)
            name = plan[outcome.step][outcome.index].name
            if part_times is not None:
                part_times[part_name(outcome.step, name)] = round(float(outcome.seconds), 3)
            log.info(f"[{outcome.step}] {name} done on a worker in {outcome.seconds:.1f} s")
            for logger_name, level, message in records:
                logging.getLogger(logger_name).log(level, message)
            parts = done[outcome.step]
            parts.append(outcome)
            if len(parts) == len(plan[outcome.step]):
                parts.sort(key=lambda p: p.index)
                on_done(verify_steps.finish_step(outcome.step, staging, parts, quick))
    finally:
        for future in futures:
            future.cancel()
    return workers, shared_runs


def part_task(step, index, scenario, shared_dir, quick, max_wall_s) -> tuple:
    """The task a worker runs: ``step`` on one scenario in a temporary directory (removed
    after), sharing gpme runs through ``shared_dir``; returns (outcome, {relative path:
    bytes} of every file it wrote, its log records and warnings, {"computed": n,
    "shared": n} gpme runs)."""
    with tempfile.TemporaryDirectory(prefix=f"gpme-verify-{step}-") as tmp, \
            _recorded() as records, run_memo.shared_runs(shared_dir) as counts:
        root = Path(tmp)
        outcome = verify_steps.run_part(step, index, root, scenario, quick, False, max_wall_s)
        files = {str(p.relative_to(root)): p.read_bytes()
                 for p in sorted(root.rglob("*")) if p.is_file()}
        counts = dict(counts)
    return outcome, files, records, counts


class _Collect(logging.Handler):
    def __init__(self, records):
        super().__init__(logging.INFO)
        self.records = records

    def emit(self, record):
        self.records.append((record.name, record.levelno, record.getMessage()))


@contextmanager
def _recorded():
    """Records of the "gpme" loggers (INFO and above) and Python warnings inside the block,
    as a list of (logger name, level, message), the warnings under "gpme.warnings"."""
    records: List[Record] = []
    logger = logging.getLogger("gpme")
    handler, level, propagate = _Collect(records), logger.level, logger.propagate
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    logger.propagate = False
    try:
        with warnings.catch_warnings(record=True) as caught:
            yield records
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
        logger.propagate = propagate
    records.extend(("gpme.warnings", logging.WARNING, f"{w.message} ({w.category.__name__})")
                   for w in caught)

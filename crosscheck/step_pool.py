"""Verify's steps run one after another in this process, or at once on a Dask cluster.

In process (:func:`run_in_process`): each step writes straight into the run's staging
directory and logs as it goes.  On a cluster (:func:`run_on_cluster`, the client of
gpme_io.dask_cluster: a local cluster of one single-threaded worker process per core, or
``--scheduler ADDRESS``): each step is one task, submitted longest first (by the step
times of the previous report, or :data:`TYPICAL_ORDER`); a worker runs it in a temporary
directory of its own and returns its outcome, the bytes of every file it wrote (written
here, atomically, under the staging directory: workers on other machines need no shared
file system) and its log records (printed here when the step ends, under its name).
Either way the gpme runs several steps compare against are computed once
(crosscheck.run_memo, on a directory under the staging directory that is removed before
the report is published).
"""
import logging
import tempfile
import uuid
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from gpme_io import dask_cluster
from gpme_io.atomic import atomic_write_bytes

from . import run_memo
from .verify_steps import StepOutcome, run_step

log = logging.getLogger("gpme.verify")
# the steps, longest first, when no earlier report gives their times (crane, quick and
# full runs of this machine, 2026-11)
TYPICAL_ORDER = ("continuum", "exudyn", "drake", "mujoco", "pinocchio", "gpme")
# where the shared gpme runs live during the run (under the staging directory)
SHARED_RUNS_DIR = ".shared_runs"

Record = Tuple[str, int, str]      # (logger name, level, message)


def run_in_process(steps: Sequence[str], staging: Path, scenarios, quick, progress,
                   max_wall_s, on_done: Callable[[StepOutcome], None]) -> None:
    """Run ``steps`` here, one after another, into ``staging``; on_done(outcome) after each."""
    with run_memo.shared_runs(Path(staging) / SHARED_RUNS_DIR):
        for step in steps:
            log.info(f"[{step}] ...")
            on_done(run_step(step, staging, scenarios, quick, progress, max_wall_s))


def submission_order(steps: Sequence[str], previous_times: Optional[Dict[str, float]]) -> List[str]:
    """``steps`` longest first: by ``previous_times`` (s, the last report's step times) for
    the steps it has, the others before them in :data:`TYPICAL_ORDER` (unknown ones first)."""
    previous_times = previous_times or {}
    typical = {s: i for i, s in enumerate(TYPICAL_ORDER)}
    return sorted(steps, key=lambda s: (s in previous_times, -previous_times.get(s, 0.0),
                                        typical.get(s, -1)))


def run_on_cluster(client, steps: Sequence[str], staging: Path, scenarios, quick, max_wall_s,
                   on_done: Callable[[StepOutcome], None],
                   previous_times: Optional[Dict[str, float]] = None) -> int:
    """Run ``steps`` as tasks on ``client``'s cluster; write each one's files into
    ``staging``, replay its log records and call on_done(outcome) as it ends.  Returns the
    number of workers.  A task that raises (OutputWriteError, a lost worker) raises here."""
    staging = Path(staging)
    shared = str(staging.resolve() / SHARED_RUNS_DIR)
    order = submission_order(steps, previous_times)
    workers = dask_cluster.worker_count(client)
    log.info(f"[dask] {len(order)} steps on {workers} workers at {client.scheduler.address}, "
             f"longest first: {', '.join(order)}")
    token = uuid.uuid4().hex[:8]
    futures = {client.submit(step_task, step, shared, scenarios, quick, max_wall_s,
                             key=f"gpme-verify-{step}-{token}", pure=False,
                             priority=len(order) - i): step
               for i, step in enumerate(order)}
    try:
        for future in dask_cluster.as_completed(futures):
            outcome, files, records = future.result()
            for relative, data in files.items():
                atomic_write_bytes(staging / relative, data)
            log.info(f"[{outcome.step}] done on a worker in {outcome.seconds:.1f} s:")
            for name, level, message in records:
                logging.getLogger(name).log(level, message)
            on_done(outcome)
    finally:
        for future in futures:
            future.cancel()
    return workers


def step_task(step, shared_dir, scenarios, quick, max_wall_s) -> Tuple[StepOutcome, Dict[str, bytes], List[Record]]:
    """The task a worker runs: ``step`` in a temporary directory (removed after), sharing
    gpme runs through ``shared_dir``; returns (outcome, {relative path: bytes} of every file
    the step wrote, its log records and warnings)."""
    with tempfile.TemporaryDirectory(prefix=f"gpme-verify-{step}-") as tmp, \
            _recorded() as records, run_memo.shared_runs(shared_dir):
        outcome = run_step(step, Path(tmp), scenarios, quick, False, max_wall_s)
        root = Path(tmp)
        files = {str(p.relative_to(root)): p.read_bytes()
                 for p in sorted(root.rglob("*")) if p.is_file()}
    return outcome, files, records


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

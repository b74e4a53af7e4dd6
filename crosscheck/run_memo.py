"""gpme runs shared by the steps of one verification: each computed once.

Several engines' steps compare against the same gpme run (the same system, start, end
time, RK4 step and output times: MuJoCo's and Exudyn's programmed runs, the halving runs
at h/2 and h/4).  Inside :func:`shared_runs` (verify opens it around every step, in every
worker process, on one directory of the run), :func:`memoised` stores each run under the
SHA-256 of what determines it (the pickled system, model and start included, so two
different systems never share a key; a key that differs between processes costs a second
computation, never a wrong run).  A run being computed by one process holds a lock on its
key (fcntl.flock): another process asking for it waits and then reads it instead of
computing it again.  Outside the block nothing is stored and every call computes.

Workers on other machines that do not share the directory each compute their own runs
(correct, only not shared).  The files are pickles this process's run wrote itself, in the
run's own staging directory, read by nothing else.
"""
import fcntl
import hashlib
import logging
import pickle
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Optional

import cloudpickle
import numpy as np

log = logging.getLogger("gpme.verify")

_directory: Optional[Path] = None
_counts = {"computed": 0, "shared": 0}


@contextmanager
def shared_runs(directory):
    """Runs asked for through :func:`memoised` inside the block are stored in (and read from)
    ``directory`` (created; None: nothing is shared).  Yields the counts dict
    {"computed": n, "shared": n} of the block."""
    global _directory
    previous = _directory
    _directory = None if directory is None else Path(directory)
    if _directory is not None:
        _directory.mkdir(parents=True, exist_ok=True)
    _counts.update(computed=0, shared=0)
    try:
        yield _counts
    finally:
        _directory = previous


def run_key(*parts) -> str:
    """SHA-256 hex digest of ``parts`` (systems, arrays, numbers, strings), pickled with
    cloudpickle (numpy arrays by their bytes, dtype and shape).

    An object is hashed by the pickle of its pickled-and-loaded copy: the pickle of an
    object built here and of its copy unpickled in a worker differ (shared references and
    read-only arrays come back otherwise), while a loaded copy pickles the same again, in
    any process (tests/test_step_pool.py checks the keys of one run in process and on a
    cluster are the same)."""
    digest = hashlib.sha256()
    for part in parts:
        if isinstance(part, np.ndarray):
            part = (str(part.dtype), part.shape, np.ascontiguousarray(part).tobytes())
        digest.update(cloudpickle.dumps(cloudpickle.loads(cloudpickle.dumps(part))))
    return digest.hexdigest()


def memoised(key: str, compute: Callable):
    """compute() once per ``key`` among the processes sharing the directory of
    :func:`shared_runs`; outside that block compute() every time."""
    if _directory is None:
        return compute()
    path = _directory / f"{key}.pkl"
    with open(_directory / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)        # released when the file closes
        if path.is_file():
            with open(path, "rb") as fh:
                _counts["shared"] += 1
                return pickle.load(fh)
        result = compute()
        partial = path.with_suffix(".partial")
        with open(partial, "wb") as fh:
            pickle.dump(result, fh, protocol=pickle.HIGHEST_PROTOCOL)
        partial.replace(path)
        _counts["computed"] += 1
        return result

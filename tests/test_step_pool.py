"""Verify's steps at once on a Dask cluster (crosscheck.step_pool) give the rows and files
the same steps give one after another in one process, and the gpme runs several steps
compare against are computed once among processes (crosscheck.run_memo)."""
import logging
import multiprocessing
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from crosscheck import run_gates, run_memo, step_pool
from crosscheck.convergence import COARSEST, FINEST
from crosscheck.verify_steps import default_scenarios
from gpme_examples.crane import CraneParameters, crane_system, initial_state


def _slow_square(x, log_path):
    with open(log_path, "a") as fh:       # one line per computation
        fh.write("computed\n")
    time.sleep(0.5)                       # long enough for the other process to ask meanwhile
    return x * x


def _ask(directory, key, x, log_path, queue):
    with run_memo.shared_runs(directory):
        queue.put(run_memo.memoised(key, lambda: _slow_square(x, log_path)))


def test_a_run_asked_for_by_two_processes_at_once_is_computed_once(tmp_path):
    log_path = tmp_path / "computations.txt"
    queue = multiprocessing.get_context("fork").Queue()
    procs = [multiprocessing.get_context("fork").Process(
        target=_ask, args=(tmp_path / "shared", "k", 7, log_path, queue)) for _ in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(30)
    assert [p.exitcode for p in procs] == [0, 0]
    assert sorted(queue.get(timeout=5) for _ in procs) == [49, 49]
    assert log_path.read_text().splitlines() == ["computed"]


def test_outside_the_block_every_call_computes(tmp_path):
    log_path = tmp_path / "computations.txt"
    for _ in range(2):
        assert run_memo.memoised("k", lambda: _slow_square(3, log_path)) == 9
    assert len(log_path.read_text().splitlines()) == 2


def test_keys_differ_with_any_part_and_agree_on_equal_ones():
    q = np.array([0.1, 0.2])
    key = run_memo.run_key("run", q, 1.0)
    assert key == run_memo.run_key("run", q.copy(), 1.0)
    assert key != run_memo.run_key("run", q + np.array([0.0, 1e-15]), 1.0)
    assert key != run_memo.run_key("run", q, 1.0 + 2e-16)
    assert key != run_memo.run_key("run", q.astype(np.float32), 1.0)


def test_refined_runs_of_two_steps_share_their_runs(tmp_path):
    """The same system and start asked for by two steps (a run gate's COARSEST criterion
    and a halving gate's FINEST): the second finds h, h/2, h/4 stored, equal to a fresh
    computation."""
    params = CraneParameters()
    system = crane_system(1, params)
    q0, q_dot0 = initial_state(system.model, params)
    args = (system, q0, q_dot0, 0.02, 1e-4, 2e-3)
    with run_memo.shared_runs(tmp_path) as counts:
        first = run_gates.refined_gpme_runs(*args, compared=COARSEST)
        computed = counts["computed"]
        second = run_gates.refined_gpme_runs(*args, compared=FINEST)
        assert counts["computed"] == computed and counts["shared"] >= 3
    fresh = run_gates.refined_gpme_runs(*args, compared=FINEST)
    for a, b, c in zip(first.runs, second.runs, fresh.runs):
        pd.testing.assert_frame_equal(a, b)
        pd.testing.assert_frame_equal(b, c)


def test_longest_steps_are_submitted_first():
    steps = ["gpme", "pinocchio", "mujoco", "continuum"]
    assert step_pool.submission_order(steps, None) == ["continuum", "mujoco", "pinocchio",
                                                       "gpme"]
    # the previous report's times decide for the steps it has; a step it lacks goes first
    times = {"gpme": 50.0, "pinocchio": 5.0, "mujoco": 20.0}
    assert step_pool.submission_order(steps, times) == ["continuum", "gpme", "mujoco",
                                                        "pinocchio"]


@pytest.fixture(scope="module")
def cluster():
    from dask.distributed import LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=logging.ERROR) as c:
        yield c


def _files(root):
    return sorted(str(p.relative_to(root)) for p in Path(root).rglob("*") if p.is_file())


def _comparable(table):
    """The rows without the measured wall times (they differ run to run)."""
    return table[~table["quantity"].str.contains("wall time")].reset_index(drop=True)


def test_steps_on_a_cluster_equal_the_steps_in_process(cluster, tmp_path, caplog):
    """gpme's and Pinocchio's quick crane steps on two worker processes: the same rows
    (every value), the same files, the steps' log lines replayed here, the shared runs'
    directory under the staging directory."""
    from dask.distributed import Client
    steps = ["gpme", "pinocchio"]
    here, there = tmp_path / "here", tmp_path / "there"
    outcomes = {"here": {}, "there": {}}
    counted_here = step_pool.run_in_process(steps, here, None, True, False, None,
                                            lambda o: outcomes["here"].__setitem__(o.step, o))
    with caplog.at_level(logging.INFO, logger="gpme"), Client(cluster.scheduler_address) as c:
        workers, counted_there = step_pool.run_on_cluster(
            c, steps, there, None, True, None,
            lambda o: outcomes["there"].__setitem__(o.step, o))
    assert workers == 2
    # Pinocchio's refined gpme runs (h, h/2, h/4 of its scenarios), counted on both sides
    assert counted_here == counted_there and counted_here["computed"] >= 3
    for step in steps:
        a, b = outcomes["here"][step], outcomes["there"][step]
        assert a.crash is None and b.crash is None
        pd.testing.assert_frame_equal(_comparable(a.table), _comparable(b.table))
        pd.testing.assert_frame_equal(a.prerequisites, b.prerequisites)
    assert _files(here) == _files(there)
    assert any("crane" in r.getMessage() and r.name == "gpme.verify" for r in caplog.records)
    assert any(r.getMessage().startswith("[pinocchio] crane") and "done on a worker" in
               r.getMessage() for r in caplog.records)


def test_default_scenarios_pickle_for_the_workers():
    import cloudpickle
    for step in ("gpme", "pinocchio", "mujoco"):
        scenarios = default_scenarios(step, True)
        again = cloudpickle.loads(cloudpickle.dumps(scenarios))
        assert [s.name for s in again] == [s.name for s in scenarios]


class _LostFuture:
    """A Dask future whose worker died: result() raises as KilledWorker does."""

    def result(self):
        raise RuntimeError("Attempted to run task gpme-verify-pinocchio-0 on 4 different "
                           "workers, but all those workers died while running it")

    def cancel(self):
        pass


class _LostClient:
    """A client whose every task loses its worker."""

    class scheduler:
        address = "tcp://lost:0"

    def submit(self, *args, **kwargs):
        return _LostFuture()


class _Completed:
    """Dask's as_completed for fake futures: each in the order it was added, futures added
    while iterating included."""

    def __init__(self, futures):
        self.queue = list(futures)

    def add(self, future):
        self.queue.append(future)

    def __iter__(self):
        while self.queue:
            yield self.queue.pop(0)


def _fake_cluster(monkeypatch, threads=1):
    monkeypatch.setattr(step_pool.dask_cluster, "worker_count", lambda client: threads)
    monkeypatch.setattr(step_pool.dask_cluster, "thread_count", lambda client: threads)
    monkeypatch.setattr(step_pool.dask_cluster, "as_completed", _Completed)


def test_a_part_whose_worker_is_lost_is_its_steps_crash_row(tmp_path, monkeypatch):
    _fake_cluster(monkeypatch)
    outcomes = []
    step_pool.run_on_cluster(_LostClient(), ["pinocchio"], tmp_path, None, True, None,
                             outcomes.append)
    (outcome,) = outcomes
    assert outcome.crash is not None and "workers died" in outcome.crash.message
    assert outcome.table["status"].tolist() == ["fail"]
    assert (tmp_path / "checks").is_dir()          # the crash row is written like any row


class _CountingClient(_LostClient):
    """A client that records how many submitted parts have not come back yet."""

    def __init__(self):
        self.in_flight, self.most, self.keys = 0, 0, []

    def submit(self, *args, key=None, **kwargs):
        self.in_flight += 1
        self.most = max(self.most, self.in_flight)
        self.keys.append(key)
        return _LostFuture()


def test_no_more_parts_are_in_flight_than_the_workers_run_at_once(tmp_path, monkeypatch):
    """One part per worker thread is submitted at a time (Dask would queue the rest on
    busy workers ahead of time), every part in the longest-step-first order."""
    _fake_cluster(monkeypatch, threads=2)
    client = _CountingClient()

    class _Finishing(_Completed):          # a future handed out is a part that ended
        def __iter__(self):
            for future in super().__iter__():
                client.in_flight -= 1
                yield future
    monkeypatch.setattr(step_pool.dask_cluster, "as_completed", _Finishing)
    outcomes = []
    step_pool.run_on_cluster(client, ["gpme", "pinocchio"], tmp_path, None, True, None,
                             outcomes.append, previous_times={"gpme": 1.0, "pinocchio": 9.0})
    parts = {"gpme": 2, "pinocchio": 2}           # the quick plan: rigid and n = 3 each
    assert client.most == 2 and len(client.keys) == sum(parts.values())
    assert [k.split("-")[2] for k in client.keys] == ["pinocchio"] * 2 + ["gpme"] * 2
    assert sorted(o.step for o in outcomes) == ["gpme", "pinocchio"]


def test_parts_go_longest_first_by_the_last_reports_part_times():
    """part_order: without times the plan's order; with them the longest part first, a
    part the last report does not have before every known one."""
    from types import SimpleNamespace as NS
    plan = {"exudyn": [NS(name="rigid"), NS(name="n3")],
            "drake": [NS(name="rigid"), NS(name="n3"), NS(name="n10")]}
    names = [f"{s}/{sc.name}" for s, _, sc in step_pool.part_order(plan, None)]
    assert names == ["exudyn/rigid", "exudyn/n3", "drake/rigid", "drake/n3", "drake/n10"]
    previous = {"exudyn/rigid": 19.0, "exudyn/n3": 165.0, "drake/rigid": 11.0,
                "drake/n3": 38.0}
    names = [f"{s}/{sc.name}" for s, _, sc in step_pool.part_order(plan, previous)]
    assert names == ["drake/n10", "exudyn/n3", "drake/n3", "exudyn/rigid", "drake/rigid"]


def test_a_cluster_run_reports_each_parts_time(tmp_path, monkeypatch):
    _fake_cluster(monkeypatch, threads=2)
    times = {}
    step_pool.run_on_cluster(_CountingClient(), ["gpme"], tmp_path, None, True, None,
                             lambda o: None, part_times=times)
    assert sorted(times) == ["gpme/crane_flexible_n3", "gpme/crane_rigid"]
    assert all(v >= 0.0 for v in times.values())

"""The cost of one sweep point, measured: the step, row and fixed costs of a model size
(warm-up runs, :class:`Sampler`) and the plan of each run a point makes
(:func:`crane_point_plans`: the crane's rigid and flexible runs; :func:`model_point_plans`:
a model file's one run).  gpme_study.cost adds them up into a sweep's estimate and
explains the model of the cost.
"""
import logging
import math
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from gpme_core import stability
from gpme_core.errors import GpmeError
from gpme_core.integrate import simulate
from gpme_core.run_cost import kernels_compiled
from gpme_examples.crane import crane_system, initial_state
from gpme_io.runs import resolved_step

from .model_point import scenario_from_document
from .point import resolved_parameters, rk4_step

log = logging.getLogger("gpme.sweep")

# what stops a point at its start (its run records the same as its status): gpme's errors
# and numerical failures of a singular start
POINT_FAILURES = (GpmeError, ValueError, ArithmeticError, np.linalg.LinAlgError)

# passes over the recorded rows per run: the history frame, then the metrics
ROW_PASSES = 2
# the history of one run in memory: the integrated states (2n + 3 floats, a numpy array of
# ~112 bytes each row while recorded) and the DataFrame built from them
ARRAY_OVERHEAD_BYTES = 112


def warm_up_steps(n):
    """Steps of the timed warm-up run of a model with n coordinates: long enough that the
    stability check at the start (about 4n solves) is at most half of it."""
    return int(min(400, max(40, 2 * n)))


@dataclass(frozen=True)
class StepCost:
    """Measured costs of one model size: s per RK4 step (adaptive: per simulated second,
    ``per_sim_s``), s per recorded row, the warm-up's dt (s) and s once per run."""

    step_s: float
    row_s: float
    dt: float
    per_sim_s: Optional[float] = None
    fixed_s: float = 0.0


@dataclass(frozen=True)
class RunPlan:
    """One run of one point: its step count, rows and history size (bytes)."""

    steps: float
    rows: float
    seconds: float
    history_bytes: float


@dataclass
class Sampler:
    """The measurements shared by the sampled points: the first call and the step costs
    per model size."""

    report: Callable[[str], None]
    first_call_s: Optional[float] = None
    costs: dict = field(default_factory=dict)

    def first_call(self, system, q0, q_dot0):
        """Time the first reduced solve in this process on its own (numba compilation or
        its cache load), once, and say so."""
        if self.first_call_s is not None:
            return
        compiling = not kernels_compiled()
        if compiling:
            self.report("compiling the numba kernels (first call in this process; numba "
                        "keeps them in its on-disk cache) ...")
        start = time.perf_counter()
        system.solve(0.0, q0, q_dot0)
        self.first_call_s = time.perf_counter() - start
        if compiling:
            self.report(f"  first call: {self.first_call_s:.1f} s (compilation or cache "
                        "load, not counted in the per-point cost)")

    def cost(self, key, system, q0, q_dot0, dt, method="RK4", on_manifold=False):
        """StepCost of model size ``key``, measured on ``system`` the first time."""
        if key not in self.costs:
            self.first_call(system, q0, q_dot0)
            self.costs[key] = _warm_up(system, q0, q_dot0, dt, method, on_manifold)
        return self.costs[key]


def _timed_run(system, q0, q_dot0, dt, steps, method, on_manifold):
    """(integration s, whole call s, rows) of a run of ``steps`` steps, every one recorded."""
    kwargs = {"dt": dt} if method == "RK4" else {}
    start = time.perf_counter()
    df = simulate(system, steps * dt, q0, q_dot0, method=method, output_dt=dt,
                  on_manifold=on_manifold, **kwargs)
    total = time.perf_counter() - start
    return float(df.attrs.get("wall_time_s", total)), total, len(df)


def _warm_up(system, q0, q_dot0, dt, method, on_manifold):
    """StepCost from two warm-up runs, of k and 2k steps: their differences give the cost
    per step and per row without what every run costs once (the stability check at the
    start, the start on the constraints, building the table), which is ``fixed_s``."""
    k = warm_up_steps(system.model.n_coordinates)
    # one untimed step first: the compiled integrator loops (gpme_core.kernels) compile or
    # load from their cache on a method's first run in a process, which no point repeats
    _timed_run(system, q0, q_dot0, dt, 1, method, on_manifold)
    int1, tot1, rows1 = _timed_run(system, q0, q_dot0, dt, k, method, on_manifold)
    int2, tot2, rows2 = _timed_run(system, q0, q_dot0, dt, 2 * k, method, on_manifold)
    step_s = (int2 - int1) / k
    row_s = ((tot2 - int2) - (tot1 - int1)) / max(rows2 - rows1, 1)
    if step_s <= 0 or row_s <= 0:       # timing noise (a busy machine): the plain ratios
        step_s, row_s = int2 / (2 * k), (tot2 - int2) / rows2
    fixed_s = max(tot1 - k * step_s - rows1 * row_s, 0.0)
    if method == "RK4":
        return StepCost(step_s, row_s, dt, fixed_s=fixed_s)
    return StepCost(step_s, row_s, dt, per_sim_s=step_s / dt, fixed_s=fixed_s)


def _history_bytes(system, rows):
    model = system.model
    n, m = model.n_coordinates, system.n_constraints
    columns = 1 + 2 * n + 3 * m + len(model.drives) + 3 * len(model.frames) + 6
    return rows * (8.0 * (columns + 2 * n + 3) + ARRAY_OVERHEAD_BYTES)


def _run_plan(cost, system, t_end, output_dt, dt):
    rows = math.floor(t_end / output_dt + 1e-9) + 1
    if cost.per_sim_s is not None:
        integration = cost.per_sim_s * t_end
        steps = t_end / cost.dt
    else:
        steps = math.ceil(t_end / dt - 1e-9)
        integration = steps * cost.step_s
    return RunPlan(steps, rows, cost.fixed_s + integration + rows * ROW_PASSES * cost.row_s,
                   _history_bytes(system, rows))


def crane_point_plans(point, settings, sampler):
    """RunPlans of one crane point (gpme_study.point.run_point): the rigid run and, with
    n_rfe > 0, the flexible one; stops at a run that cannot start."""
    plans = []
    try:
        params = resolved_parameters(point)
        n_rfe = int(point.get("n_rfe", settings.n_rfe))
        for n in ([0, n_rfe] if n_rfe else [0]):
            system = crane_system(n, params)
            q0, q_dot0 = initial_state(system.model, params)
            dt = rk4_step(system, q0, settings)
            cost = sampler.cost(("crane", n), system, q0, q_dot0, dt, on_manifold=True)
            plans.append(_run_plan(cost, system, settings.t_end, settings.output_dt, dt))
    except POINT_FAILURES as exc:    # the point stops here when it runs, too, and says why
        log.debug("cost of point %s: stops at its start: %s", point, exc)
    return plans


def model_point_plans(document, point, settings, sampler):
    """(build s, RunPlans) of one model-file point (gpme_study.model_point)."""
    start = time.perf_counter()
    try:
        scenario = scenario_from_document(document, point, settings)
    except POINT_FAILURES as exc:    # the point fails at its build, recorded then
        log.debug("cost of point %s: not built: %s", point, exc)
        return time.perf_counter() - start, []
    build = time.perf_counter() - start
    method = scenario.integrator
    system, q0, q_dot0 = scenario.system, scenario.q0, scenario.q_dot0
    try:
        if method == "RK4":
            dt = resolved_step(scenario)
        else:                    # the warm-up's span: as many stable RK4 steps
            dt = stability.rk4_step(scenario.system, q0)
        key = ("model", scenario.model.n_coordinates, method)
        cost = sampler.cost(key, system, q0, q_dot0, dt, method)
    except POINT_FAILURES as exc:    # the point stops at its start, recorded then
        log.debug("cost of point %s: stops at its start: %s", point, exc)
        return build, []
    return build, [_run_plan(cost, system, scenario.t_end, scenario.output_dt, dt)]

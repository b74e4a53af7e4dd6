"""What a sweep will cost, known before it starts: wall time, output on disk and the history
one run holds in memory; and the limits above which `gpme sweep` refuses without --force.

Per point, the runs it makes (the crane: a rigid run and, with n_rfe > 0, a flexible one at
the same parameters; a model file: one run of its integrator), each of

    steps = t_end / dt RK4 steps,  rows = t_end / output_dt + 1 recorded rows,
    seconds = fixed_s + steps x step_s + rows x ROW_PASSES x row_s (+ the model file's build)

step_s, row_s and fixed_s are measured, not modelled: two warm-up runs of k and 2k steps
(k = warm_up_steps(n)) with every step recorded, on the first sampled point of each model
size (n coordinates), give step_s = the difference of their integration wall times / k
(four right-hand-side evaluations and the state check), row_s = the difference of the
rest of the calls / the extra rows (one reduced solve, energies and frame positions per
row), fixed_s = what is left of the first (the RK4 stability check and the start on the
constraints, once per run).  A row is
evaluated ROW_PASSES times in a point: the history, then the metrics (reactions, Jacobian).
dt is each sampled point's own step (the sweep's --dt, else the model file's or the
suggested stable step, exactly as the point will run).  The adaptive integrators of a
model file (RK45, DOP853, Radau) are timed the same way on a warm-up over the same
simulated time and scaled by t_end.

Up to SAMPLE_POINTS pending points are estimated (evenly spread, plus the largest model),
within SAMPLE_BUDGET_S; the sweep's estimate is their mean x the pending points / the
workers.  A point that fails at its start (unreachable, refused) is counted at what it
cost to find that out.  The first call of the numba kernels in this process (compilation,
or loading numba's on-disk cache) is timed on its own and reported as such.
"""
import logging
import math
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from gpme_core.errors import GpmeError
from gpme_core.integrate import simulate
from gpme_core.run_cost import format_bytes, format_seconds, kernels_compiled
from gpme_core import stability
from gpme_examples.crane import crane_system, initial_state
from gpme_io.runs import resolved_step

from .model_metrics import heat_map_metrics
from .model_paths import INTEGER_KEYS
from .model_point import scenario_from_document
from .plots import HEAT_MAP_METRICS
from .point import resolved_parameters, rk4_step

log = logging.getLogger("gpme.sweep")
# what stops a point at its start (its run records the same as its status): gpme's errors
# and numerical failures of a singular start
POINT_FAILURES = (GpmeError, ValueError, ArithmeticError, np.linalg.LinAlgError)

# refusal limits (without --force): a sweep estimated to take longer than MAX_WALL_S on
# its workers, to write more than MAX_OUTPUT_BYTES, or whose runs hold a history larger
# than MAX_HISTORY_BYTES in memory (per worker, one run at a time)
MAX_WALL_S = 2 * 3600.0
MAX_OUTPUT_BYTES = 2 * 2 ** 30
MAX_HISTORY_BYTES = 2 * 2 ** 30
SAMPLE_POINTS = 12
SAMPLE_BUDGET_S = 5.0
# passes over the recorded rows per run: the history frame, then the metrics
ROW_PASSES = 2
# s, starting a local Dask cluster, importing gpme and loading the kernels on its workers
# (measured 11-15 s for 2 workers on the shared 2-core machine, docs/sweep.md)
DASK_START_S = 15.0
# bytes on disk: a point file per stored key/value (JSON, indent 1), a table cell (CSV and
# Parquet together), a heat map
POINT_FILE_BYTES_PER_VALUE = 45
TABLE_BYTES_PER_CELL = 30
FIGURE_BYTES = 40_000       # measured 35-38 kB (120 dpi, 6.4 x 4.8 in)
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


def _sample(points, spec):
    """Indices of the points to estimate: evenly spread, the largest model first."""
    if not points:
        return []
    if spec.model is None:
        size = [pt.get("n_rfe", spec.run.n_rfe) for pt in points]
    else:
        ints = [nm for nm in points[0] if nm.rsplit(".", 1)[-1] in INTEGER_KEYS]
        size = [sum(pt[nm] for nm in ints) for pt in points]
    largest = int(np.argmax(size))
    spread = np.linspace(0, len(points) - 1, min(len(points), SAMPLE_POINTS)).round()
    return list(dict.fromkeys([largest] + [int(k) for k in spread]))


@dataclass(frozen=True)
class CostEstimate:
    """The estimate of the pending points of a sweep.

    points        : pending points (to be computed)
    sampled       : points whose cost was estimated
    point_s       : (min, mean, max) s of a sampled point on one worker
    workers       : worker processes the points are spread over
    wall_s        : s, estimated wall time of the sweep (start-up included)
    output_bytes  : bytes written (point files, table, plots)
    history_bytes : bytes of the largest run's history in memory
    steps         : most RK4 steps of one sampled run
    first_call_s  : s, the first call of the kernels in this process (None: not made)
    measure_s     : s, spent making this estimate
    """

    points: int
    sampled: int
    point_s: tuple
    workers: int
    wall_s: float
    output_bytes: float
    history_bytes: float
    steps: float
    first_call_s: Optional[float]
    measure_s: float

    def summary(self):
        """One line: the estimate and what it rests on."""
        if not self.points:
            return "estimate: nothing to compute"
        lo, mean, hi = self.point_s
        spread = f"{format_seconds(mean)} per point" + (
            f" ({format_seconds(lo)} - {format_seconds(hi)} over {self.sampled} sampled)"
            if self.sampled > 1 and hi > 1.05 * lo else "")
        return (f"estimate: {self.points} points x {spread} on {self.workers} worker"
                f"{'s' if self.workers != 1 else ''}: about {format_seconds(self.wall_s)} wall; "
                f"output {format_bytes(self.output_bytes)}, largest run history "
                f"{format_bytes(self.history_bytes)} in memory (estimated in "
                f"{self.measure_s:.1f} s)")

    def problems(self):
        """Why the sweep is refused without --force (empty when within every limit)."""
        out = []
        reduce = ("reduce it (fewer points, a smaller --t-end, a larger --dt or "
                  "--output-dt{more}) or pass --force to run it anyway")
        if self.wall_s > MAX_WALL_S:
            lo, mean, hi = self.point_s
            out.append(
                f"the sweep is estimated at {format_seconds(self.wall_s)} wall time ({self.points} "
                f"points x {format_seconds(mean)} each on {self.workers} worker(s); the longest "
                f"sampled run has {self.steps:.3g} RK4 steps), above the limit of "
                f"{format_seconds(MAX_WALL_S)} (gpme_study.cost.MAX_WALL_S); "
                + reduce.format(more=", more --workers"))
        if self.output_bytes > MAX_OUTPUT_BYTES:
            out.append(f"the sweep would write about {format_bytes(self.output_bytes)}, above the "
                       f"limit of {format_bytes(MAX_OUTPUT_BYTES)} (gpme_study.cost."
                       "MAX_OUTPUT_BYTES); " + reduce.format(more=""))
        if self.history_bytes > MAX_HISTORY_BYTES:
            out.append(f"one run would hold a history of about {format_bytes(self.history_bytes)} "
                       f"in memory, above the limit of {format_bytes(MAX_HISTORY_BYTES)} per "
                       "worker (gpme_study.cost.MAX_HISTORY_BYTES); reduce it (a smaller "
                       "--t-end or a larger --output-dt) or pass --force to run it anyway")
        return out


def estimate(spec, points, workers=1, dask=False, report=None, budget_s=SAMPLE_BUDGET_S):
    """CostEstimate of running ``points`` (the pending points of ``spec``, a
    gpme_study.spec_points.SweepSpec) on ``workers`` worker processes (``dask``: a cluster,
    whose start-up is counted); ``report`` gets the first-call lines."""
    start = time.perf_counter()
    sampler = Sampler(report or (lambda line: None))
    seconds, history, steps = [], 0.0, 0.0
    for k in _sample(points, spec):
        if spec.model is None:
            build, plans = 0.0, crane_point_plans(points[k], spec.run, sampler)
        else:
            build, plans = model_point_plans(spec.model, points[k], spec.run, sampler)
        seconds.append(build + sum(p.seconds for p in plans))
        history = max([history] + [p.history_bytes for p in plans])
        steps = max([steps] + [p.steps for p in plans])
        if time.perf_counter() - start > budget_s:
            break
    n = len(points)
    if n:
        mean = float(np.mean(seconds))
        point_s = (float(min(seconds)), mean, float(max(seconds)))
        parallel = max(1, min(workers, n))
        wall = mean * n / parallel + (DASK_START_S if dask else 0.0)
    else:
        point_s, parallel, wall = (0.0, 0.0, 0.0), max(1, workers), 0.0
    columns = len(spec.metric_table) + len(spec.swept) + 15
    plots = _figures(spec) if spec.plot_x and spec.plot_y else 0
    output = (len(spec.points) * columns * (POINT_FILE_BYTES_PER_VALUE + TABLE_BYTES_PER_CELL)
              + plots * FIGURE_BYTES)
    return CostEstimate(n, len(seconds), point_s, parallel, wall, float(output), history,
                        steps, sampler.first_call_s, time.perf_counter() - start)


def _figures(spec):
    """Number of figures the sweep draws (gpme_study.plots.write_plots)."""
    if spec.model is None:
        maps = len(HEAT_MAP_METRICS)
    else:
        maps = len(heat_map_metrics(spec.metric_table, spec.limits))
    return maps + (1 if spec.limits else 0)

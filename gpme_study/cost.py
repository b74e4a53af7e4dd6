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
import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from gpme_core.run_cost import format_bytes, format_seconds

from .point_cost import Sampler
from .sweep_kinds import sweep_kind

# refusal limits (without --force): a sweep estimated to take longer than MAX_WALL_S on
# its workers, to write more than MAX_OUTPUT_BYTES, or whose runs hold a history larger
# than MAX_HISTORY_BYTES in memory (per worker, one run at a time)
MAX_WALL_S = 2 * 3600.0
MAX_OUTPUT_BYTES = 2 * 2 ** 30
MAX_HISTORY_BYTES = 2 * 2 ** 30
SAMPLE_POINTS = 12
SAMPLE_BUDGET_S = 5.0
# s, starting a local Dask cluster, importing gpme and loading the kernels on its workers
# (measured 11-15 s for 2 workers on the shared 2-core machine, docs/sweep.md)
DASK_START_S = 15.0
# bytes on disk: a point file per stored key/value (JSON, indent 1), a table cell (CSV and
# Parquet together), a heat map
POINT_FILE_BYTES_PER_VALUE = 45
TABLE_BYTES_PER_CELL = 30
FIGURE_BYTES = 40_000       # measured 35-38 kB (120 dpi, 6.4 x 4.8 in)
def _sample(points, spec):
    """Indices of the points to estimate: evenly spread, the largest model first."""
    if not points:
        return []
    size = [sweep_kind(spec).size(spec, pt) for pt in points]
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
        build, plans = sweep_kind(spec).plans(spec, points[k], sampler)
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
    maps = len(sweep_kind(spec).heat_maps(spec))
    return maps + (1 if spec.limits else 0)

"""What a run will cost before it starts: wall time, the recorded history's size in memory
and as CSV, from the model, the step and one measured right-hand-side evaluation.

The estimate is made of counts that are exact for RK4 (steps x 4 evaluations of the reduced
GPME) and lower bounds for the adaptive methods (an explicit method is held to about RK4's
stability step by the stiffest mode whatever its tolerance; Radau's steps follow its error
control and are not known before the run, so only its rows are counted), times the cost of
one evaluation measured on this machine after the numba kernels are compiled.
"""
import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import fast
from .blas_threads import single_threaded_blas
from .methods import DOP853, EXPLICIT_ADAPTIVE_METHODS, RADAU, RADAU_IIA, RK4, RK45
from .progress import Compiling

# evaluations of the right-hand side per step of each method
# RadauIIA: 3 stages x 2-3 Newton passes plus a Jacobian (2n + 1 evaluations) every ~30
# steps: measured 9.2 evaluations per step on the flexible crane (n_rfe = 5, dt = 1 ms);
# not exact
STAGES = {RK4: 4, RADAU_IIA: 9, RK45: 6, DOP853: 12, RADAU: 3}
# CSV bytes per value: '%.17g' of a double is at most 24 characters plus the separator
CSV_BYTES_PER_VALUE = 25
# the history in memory: the integrated states (float64) and the DataFrame built from them
MEMORY_COPIES = 3
# evaluations timed to measure the cost of one (after the first, which may compile)
TIMED_EVALUATIONS = 20
# ... in this many batches, the median batch counted (one busy moment of a shared machine
# does not set the estimate)
TIMED_BATCHES = 5
# wall time per evaluation over the bare reduced solve: the state update, the divergence
# and joint-range check per step, and building the history (one more solve per row);
# measured 1.3-1.4 on the crane (n_rfe = 3, RK4, 0.05 s)
STEP_OVERHEAD = 1.35


@dataclass(frozen=True)
class RunCost:
    """Estimated cost of one run.

    method           : the integrator
    steps            : number of steps (RK4: exact; adaptive explicit: a lower bound from
                       the stability step; Radau: None, not known before the run)
    evaluations      : right-hand-side evaluations (same exactness as steps)
    seconds_per_eval : s, measured cost of one evaluation on this machine
    rows, columns    : the recorded history's shape
    memory_bytes     : bytes of the history in memory while the run is written out
    csv_bytes        : bytes of the history as CSV
    exact            : True when ``steps`` is a count, False when it is a lower bound
    """
    method: str
    steps: Optional[int]
    evaluations: Optional[int]
    seconds_per_eval: float
    rows: int
    columns: int
    memory_bytes: float
    csv_bytes: float
    exact: bool

    @property
    def wall_s(self):
        """s, the integration's wall time (None when not known before the run)."""
        if self.evaluations is None:
            return None
        return (self.evaluations + self.rows) * self.seconds_per_eval * STEP_OVERHEAD

    def describe(self):
        """One line: '~2.1 min wall (RK4: 250,000 steps x 4 evaluations of 126 us),
        history 10,001 rows x 45 columns: 11 MB CSV, 11 MB in memory'."""
        if self.wall_s is None:
            time_text = (f"wall time not known before the run ({self.method} chooses its "
                         f"steps; one evaluation costs {format_seconds(self.seconds_per_eval)})")
        else:
            bound = "" if self.exact else "at least "
            time_text = (f"{bound}{format_seconds(self.wall_s)} wall ({self.method}: "
                         f"{bound}{self.steps:,} steps x {STAGES[self.method]} evaluations "
                         f"of {format_seconds(self.seconds_per_eval)})")
        return (f"{time_text}; history {self.rows:,} rows x {self.columns} columns: "
                f"{format_bytes(self.csv_bytes)} CSV, {format_bytes(self.memory_bytes)} in memory")


def format_seconds(s):
    """'126 us', '3 s', '2.1 min', '8.6 h', '3.2 days', '1.2e+05 years'."""
    if s < 1e-3:
        return f"{s * 1e6:.0f} us"
    if s < 1.0:
        return f"{s * 1e3:.0f} ms"
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.1f} min"
    if s < 2 * 86400:
        return f"{s / 3600:.1f} h"
    if s < 2 * 365 * 86400:
        return f"{s / 86400:.1f} days"
    return f"{s / (365.25 * 86400):.3g} years"


def format_bytes(b):
    """'54.8 kB', '6.63 MB', '2.1 GB'."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if b >= size:
            return f"{b / size:.3g} {unit}"
    return f"{b:.0f} B"


def kernels_compiled(compiled=None):
    """Whether the numba kernels are compiled (or loaded from their cache) in this process;
    True when the compiled path is off.  compiled: a gpme_core.compiled.CompiledSystem whose
    fused evaluation counts too (None: only the Python path's kernels)."""
    if not fast.ENABLED:
        return True
    from . import kernels    # numba's compiled kernels, ~20 ms to load: only when asked
    done = (all(getattr(fast, name).signatures for name in ("chain_and_terms", "point"))
            and bool(kernels.reduced_solve.signatures))
    return done and (compiled is None or bool(compiled.module.evaluate.signatures))


def time_evaluation(system, q0, q_dot0, progress=None, compiled=None):
    """(compile_s, seconds_per_eval): the first reduced solve at (0, q0, q_dot0) timed on its
    own (it compiles the numba kernels, or loads them from their cache, when this process has
    not yet), then the median over TIMED_BATCHES batches of TIMED_EVALUATIONS more.

    system   : gpme_core.gpme.ProgrammedMotion with its dependent coordinates set
    progress : None or a callable (gpme_core.progress.ProgressCallback) told of a compilation
               before it starts and after it ends (gpme_core.progress.Compiling)
    compiled : None (the Python path's ProgrammedMotion.solve is timed) or the run's
               gpme_core.compiled.CompiledSystem, whose fused evaluation is timed instead
               (its first call compiles gpme_core.kernels; called from Python, so it costs
               ~3 us more than inside the compiled loops: a cautious estimate)
    """
    if compiled is None:
        return _timed(system, q0, q_dot0, progress, None)
    # timed as the compiled runs go: BLAS on one thread (gpme_core.compiled); outside the
    # block, OpenBLAS's pools (numpy's and SciPy's) waited on each other after the Python
    # path's first solve: a 500-link chain timed 555 ms per evaluation instead of 3 ms,
    # and its run was estimated at 30.6 min for 8.8 s
    with single_threaded_blas():
        return _timed(system, q0, q_dot0, progress, compiled)


def _timed(system, q0, q_dot0, progress, compiled):
    """time_evaluation's measurement (see there)."""
    # writeable copies: the run's own states are, and a read-only q0 would compile the
    # kernels a second time (gpme_core.fast.state_array)
    q0, q_dot0 = fast.state_array(q0), fast.state_array(q_dot0)
    if compiled is not None:
        solve = compiled.accelerator(system.ic, system.dc)
    else:
        solve = system.solve
    reported = progress is not None and not kernels_compiled(compiled)
    if reported:
        progress(Compiling(finished=False))
    start = time.perf_counter()
    system.solve(0.0, q0, q_dot0)
    if compiled is not None:
        try:
            solve(0.0, q0, q_dot0)
        except RuntimeError:            # the compiled evaluation fails where the Python
            solve = system.solve        # one does not: time the Python one (cautious)
    first = time.perf_counter() - start
    if reported:
        progress(Compiling(finished=True, wall_s=first))
    batches = []
    for _ in range(TIMED_BATCHES):
        start = time.perf_counter()
        for _ in range(TIMED_EVALUATIONS // TIMED_BATCHES):
            solve(0.0, q0, q_dot0)
        batches.append((time.perf_counter() - start) / (TIMED_EVALUATIONS // TIMED_BATCHES))
    return first, float(np.median(batches))


def estimate_run(method, t_end, output_dt, n_coordinates, columns, seconds_per_eval,
                 dt=None, stable_step=None):
    """RunCost of a run.

    method          : "RK4", "RadauIIA", "RK45", "DOP853" or "Radau"
    t_end, output_dt: s
    n_coordinates   : n (the integrated state is 2n + 3 numbers)
    columns         : columns of the recorded history (gpme_core.integrate.history_frame)
    seconds_per_eval: s, one right-hand-side evaluation (:func:`time_evaluation`)
    dt              : s, RK4's step (after gpme_core.integrate.rk4_step_plan); for the
                      adaptive methods their largest step (None: unbounded)
    stable_step     : s, RK4's stability limit at the start (gpme_core.stability.rk4_limit):
                      the explicit adaptive methods' steps stay about that short
    """
    rows = int(np.floor(t_end / output_dt + 1e-9)) + 1
    state = 2 * n_coordinates + 3
    memory = rows * (state + columns) * 8.0 * MEMORY_COPIES / 2
    csv = rows * columns * float(CSV_BYTES_PER_VALUE)
    if method == "RK4":
        steps, exact = int(round(t_end / dt)), True
    elif method == "RadauIIA":
        steps, exact = int(round(t_end / dt)), False
    elif method in EXPLICIT_ADAPTIVE_METHODS:
        longest = min(x for x in (dt, stable_step, np.inf) if x is not None)
        steps = int(np.ceil(t_end / longest)) if np.isfinite(longest) else 1
        exact = False
    else:
        steps, exact = (int(np.ceil(t_end / dt)), False) if dt else (None, False)
    evaluations = None if steps is None else steps * STAGES[method]
    return RunCost(method, steps, evaluations, seconds_per_eval, rows, columns, memory, csv,
                   exact)

"""Driving the compiled integrator loops (gpme_core.kernels) from Python, one output
interval per call: recording, progress, the wall-time limit, partition switches and
errors stay here, the steps run compiled.

A failed step comes back as a status code with the state evaluated; the error is then
raised by the Python reference at that state (gpme_core.gpme / gpme_core.integrate), so
the messages are the same as on the Python path.
"""
import numpy as np

from . import kernels
from .blas_threads import single_threaded_blas
from .compiled import DIVERGENCE_LIMIT
from .errors import ConstraintError, SimulationError
from .gpme import partition_rcond
from .methods import RADAU_IIA, RK4

COMPILED_METHODS = {RK4: "rk4_advance", RADAU_IIA: "radau_advance"}   # kernels' loops
# Newton's stage equations count as solved when the largest increment of a stage velocity,
# relative to 1 + |velocity|, is below this.  A stage velocity wrong by 1e-10 rad/s moves a
# position by h x 1e-10 per step: at most 1e-9 rad over 10^4 steps even if every step's
# error had the same sign, far below the truncation error of any step worth taking (5e-8
# rad at 1 ms on the flexible crane).  Measured on the flexible crane (n_rfe = 5, 1 s, dt =
# 1 ms): 1e-12 ... 1e-8 give the same error to 3 digits; 1e-12 costs 11.4 evaluations per
# step, 1e-10 9.2.
NEWTON_TOL = 1e-10


def radau_work(n):
    """Fresh work arrays of gpme_core.kernels.radau_advance for n coordinates."""
    ctrl = np.zeros(kernels.RADAU_CTRL)
    ctrl[kernels.R_JAC_AGE] = -1.0
    ctrl[kernels.R_STEP] = np.nan
    ctrl[kernels.R_NEWTON_TOL] = NEWTON_TOL
    return (np.zeros((3 * n, 3 * n)), np.zeros((n, n)), np.zeros((n, n)), np.zeros((4, n)),
            ctrl)


def run_compiled(method, compiled, partition, t_end, y0, dt, record_every, bar,
                 wall_check, raise_state_error, on_error):
    """(times (k,), states (k, 2 n + 3), evaluations) of a fixed-step run.

    method        : "RK4" or "RadauIIA"
    compiled      : gpme_core.compiled.CompiledSystem of the run's system
    partition     : gpme_core.integrate.RunPartition (switched here when the kernel asks)
    dt            : s, the step; t_end = n_steps dt
    record_every  : steps between recorded rows
    bar           : the run's progress reporter (gpme_core.integrate._Reporter: update(step))
    wall_check    : callable(t) raising when the run has taken too long
    raise_state_error: callable(t, y, dt) raising the error of a state that diverged or left
                    its range (gpme_core.integrate._check_state)
    on_error      : callable(t, y, exc) given the last recorded state when the run fails with
                    exc (a SimulationError or ConstraintError); it may raise a better error,
                    else exc is raised
    """
    advance = getattr(compiled.module, COMPILED_METHODS[method])
    n = compiled.n
    n_steps = int(round(t_end / dt))
    y = np.array(y0, dtype=float)
    fail_y = np.empty_like(y)
    ts, ys = [0.0], [y.copy()]
    work = radau_work(n) if method == "RadauIIA" else None
    switch_below = partition.switch_below
    step = 0
    with single_threaded_blas():
        try:
            after_switch = False
            while step < n_steps:
                wall_check(step * dt)
                chunk = min(record_every - step % record_every, n_steps - step)
                if after_switch:
                    # the step that asked for the switch is taken with the new partition
                    # and no further switch (the Python path switches mid-step and goes
                    # on); otherwise its start could ask to switch back, and so on forever
                    chunk, below = 1, 0.0
                else:
                    below = switch_below
                system = partition.system
                args = (step * dt, y, dt, chunk, compiled.md, compiled.cd,
                        compiled.options(below), system.ic, system.dc)
                args += (work, fail_y) if work is not None else (fail_y,)
                status, done, t_fail = advance(*args)
                step += done
                after_switch = False
                if status == kernels.OK:
                    if step % record_every == 0 or step == n_steps:
                        ts.append(step * dt)
                        ys.append(y.copy())
                    bar.update(step)
                elif status == kernels.SWITCH:
                    switch_below = _switch(partition, t_fail, fail_y, n)
                    after_switch = True
                else:
                    _raise_status(status, method, partition, t_fail, fail_y, n, dt,
                                  raise_state_error)
        except (SimulationError, ConstraintError) as exc:
            on_error(ts[-1], ys[-1], exc)
            raise
    evaluations = 4 * n_steps if work is None else int(work[-1][kernels.R_EVALUATIONS])
    return np.array(ts), np.array(ys), evaluations


def _switch(partition, t, y, n):
    """Re-choose the dependent coordinates at the state the kernel stopped at (the
    partition records the event); returns the kernel's next switch threshold."""
    before = partition.dependent
    partition.solve(t, y[:n], y[n:2 * n])
    if partition.dependent != before:
        return partition.switch_below
    # the pivoted choice is this partition: keep it and ask again only when its
    # conditioning has halved (the Python path asks at every evaluation below the threshold)
    _, _, a, _ = partition.system.constraints(t, y[:n], y[n:2 * n])
    return 0.5 * partition_rcond(a, partition.system.dc)


def _raise_status(status, method, partition, t, y, n, dt, raise_state_error):
    """Raise the error of a failed compiled step (the reference path's message)."""
    if status in (kernels.DIVERGED, kernels.OUT_OF_RANGE):
        raise_state_error(t, y, dt)
    if status == kernels.NEWTON_FAILED:
        raise SimulationError(
            f"{method}: the implicit stage equations did not converge at t = {t:.6g} s with "
            f"dt = {dt:g} s, even with a new Jacobian; a smaller dt follows the motion more "
            "closely (or use method='RK4' to see where the motion becomes violent)")
    state = y[:2 * n]
    if not (np.isfinite(state).all() and np.abs(state).max() <= DIVERGENCE_LIMIT):
        raise_state_error(t, y, dt)          # a diverged stage: the run diverged
    # evaluation failures: the Python reference raises the proper ConstraintError
    partition.system.solve(t, y[:n], y[n:2 * n], switch_below=partition.switch_below)
    if status == kernels.SINGULAR_REDUCED:
        raise SimulationError(
            f"{method}: at t = {t:.6g} s the reduced mass matrix N^T M N is not positive "
            "definite in floating point (the Python reference's LU still solves it): the "
            f"state is far from any physical one, the run is probably diverging (dt = {dt:g} "
            f"s; q = {np.round(y[:n], 6).tolist()})")
    raise SimulationError(
        f"{method}: the compiled right-hand side failed (status {status}) at t = {t:.6g} s but "
        "the Python reference evaluates the same state; please report this with the model "
        f"(q = {np.round(y[:n], 6).tolist()})")

"""Time integration of the GPME: fixed-step classical RK4 (as in the paper), the compiled
RadauIIA, or SciPy's solve_ivp (RK45, DOP853, Radau).  :func:`run` returns a
gpme_core.run_result.RunResult (the histories as arrays, the metadata as fields);
:func:`simulate` its tidy pandas DataFrame.

The integrated state is y = (q, q_dot, W_dissipated, W_drive, W_reaction): the three
work integrals (J) are integrated with the same scheme, so the energy balance

    E_k + E_p - (E_k + E_p)(0) = W_drive + W_reaction - W_dissipated

holds to the integrator's order (W_reaction is the work of the constraint reactions,
non-zero for time-dependent constraints and while Baumgarte pulls onto the manifold).

A run keeps its own copy of the system's partition into dependent and independent
coordinates: the system passed to :func:`simulate` is not changed.  When the partition
becomes badly conditioned (gpme_core.gpme.SWITCH_RCOND) the run re-chooses it by pivoting
and records the switch in ``df.attrs["events"]`` (see :func:`simulate`).
"""
import logging
import time

import numpy as np
from scipy.integrate import solve_ivp

from .dynamics import kinetic_energy, potential_energy
from .errors import (ConstraintError, GpmeError, ModelError, SimulationError,
                     UnstableStepError)
from .compiled import DIVERGENCE_LIMIT, for_system
from .compiled_runs import COMPILED_METHODS, run_compiled
from .expression_checks import singular_sets
from .gpme import SWITCH_RCOND, ProgrammedMotion, partition_rcond
from .methods import (EXPLICIT_ADAPTIVE_METHODS, FIXED_STEP_METHODS, IMPLICIT_METHODS,
                      METHODS)
from .progress import Progress
from .run_cost import estimate_run, time_evaluation
from .run_result import RunResult, RunSettings
from .singular_approach import approach
from .stability import rk4_limit, safe_step, unstable_step_message

log = logging.getLogger("gpme.integrate")

# s, RadauIIA's step when none is given: resolves motions up to ~30 Hz to about 1e-6 of
# their amplitude per second of run (order 5; docs/benchmarks.md measures the flexible crane)
RADAU_IIA_STEP = 1e-3
N_WORK = 3
# entries of the state named in a divergence message
MESSAGE_ENTRIES = 6
# progress of the solve_ivp methods: t_end in this many parts (their steps are not known)
SCIPY_PROGRESS_UNITS = 1000
# evaluations between two looks at the clock (progress and the wall-time limit)
WALL_CHECK_EVERY = 200
# a recorded history above this many bytes in memory is refused before the run
MAX_HISTORY_BYTES = 4 * 2 ** 30


class RunPartition:
    """The partition of one run: its own copy of the system, switched when badly
    conditioned.

    system       : gpme_core.gpme.ProgrammedMotion with its dependent coordinates set
                   (copied: the object given is never changed)
    switch_below : re-choose the dependent coordinates when the partition's
                   gpme_core.gpme.partition_rcond falls below it (None: never)
    events       : list the switches are appended to (None: not recorded), each a dict
                   {"event": "dependent_switch", "t": s, "old_dependent": [names],
                   "new_dependent": [names], "rcond": partition_rcond of the old
                   partition that triggered it, "new_rcond": of the new one}
    """

    def __init__(self, system, switch_below=SWITCH_RCOND, events=None):
        self.system = system.with_dependent(system.dependent)
        self.switch_below = switch_below
        self.events = events

    @property
    def dependent(self):
        """Names of the current dependent coordinates."""
        return self.system.dependent

    def solve(self, t, q, q_dot):
        """GpmeSolution at (t, q, q_dot), switching the partition first if needed."""
        sol = self.system.solve(t, q, q_dot, switch_below=self.switch_below)
        if sol.dependent != self.system.dependent:
            old = self.system
            self.system = old.with_dependent(sol.dependent)
            if self.events is not None:
                event = {"event": "dependent_switch", "t": float(t),
                         "old_dependent": list(old.dependent),
                         "new_dependent": list(sol.dependent),
                         "rcond": partition_rcond(sol.jacobian, old.dc),
                         "new_rcond": sol.partition_rcond}
                self.events.append(event)
                log.info("t = %.6g s: dependent coordinates %s -> %s (partition rcond "
                         "%.2e < %.0e)", t, event["old_dependent"], event["new_dependent"],
                         event["rcond"], self.switch_below)
        return sol


def _rhs_factory(partition, n):
    def rhs(t, y):
        q, q_dot = y[:n], y[n:2 * n]
        sol = partition.solve(t, q, q_dot)
        terms = sol.terms
        dy = np.empty_like(y)
        dy[:n] = q_dot
        dy[n:2 * n] = sol.q_ddot
        dy[2 * n] = q_dot @ terms.d
        dy[2 * n + 1] = q_dot @ terms.t
        dy[2 * n + 2] = q_dot @ sol.reaction_forces
        return dy
    return rhs


def _check_state(model, t, y, n, dt=None):
    q = y[:n]
    bad = ~np.isfinite(y[:2 * n]) | (np.abs(y[:2 * n]) > DIVERGENCE_LIMIT)
    if bad.any():
        names = [f"{model.coordinate_names[k % n]}{'' if k < n else '_dot'}"
                 for k in np.flatnonzero(bad)]
        hint = f" with dt = {dt:g} s" if dt else ""
        values = ", ".join(f"{name} = {v:.3g}" for name, v in
                           zip(names[:MESSAGE_ENTRIES], y[np.flatnonzero(bad)]))
        more = f" and {len(names) - MESSAGE_ENTRIES} more" if len(names) > MESSAGE_ENTRIES else ""
        raise SimulationError(
            f"the run diverged at t = {t:.6g} s{hint}: {values}{more} (non-finite or above "
            f"{DIVERGENCE_LIMIT:g} in SI units)")
    outside = model.limit_violations(q)
    if outside:
        raise ConstraintError(
            f"at t = {t:.6g} s the motion reaches {outside}: the mechanism cannot follow it "
            "(a programmed motion that needs this cannot be met)")


def rk4_step_plan(t_end, dt, output_dt):
    """(step, steps per record): equal steps no longer than dt that land on every
    output time when t_end is a whole number of output_dt, else on t_end only."""
    outputs = t_end / output_dt
    if output_dt >= dt and abs(outputs - round(outputs)) < 1e-9 * max(outputs, 1.0):
        per_output = int(np.ceil(output_dt / dt - 1e-9))
        return output_dt / per_output, per_output
    n_steps = int(np.ceil(t_end / dt - 1e-9))
    step = t_end / n_steps
    return step, max(1, int(round(output_dt / step)))


def _rk4(rhs, model, t_end, y0, dt, record_every, n, progress, partition=None,
         max_wall_s=None):
    n_steps = int(round(t_end / dt))
    ts, ys = [0.0], [y0.copy()]
    y = y0.copy()
    bar = _Reporter(progress, n_steps, t_end, "RK4")
    try:
        for k in range(n_steps):
            t = k * dt
            k1 = rhs(t, y)
            k2 = rhs(t + 0.5 * dt, y + 0.5 * dt * k1)
            k3 = rhs(t + 0.5 * dt, y + 0.5 * dt * k2)
            k4 = rhs(t + dt, y + dt * k3)
            y = y + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            _check_state(model, t + dt, y, n, dt)
            if max_wall_s is not None and k % WALL_CHECK_EVERY == 0:
                _check_wall(bar.start, max_wall_s, t + dt, t_end, "RK4")
            if (k + 1) % record_every == 0 or k + 1 == n_steps:
                ts.append((k + 1) * dt)
                ys.append(y.copy())
            bar.update(k + 1)
    except (SimulationError, ConstraintError) as exc:
        if partition is not None:
            _raise_if_singular(partition.system, ts[-1], ys[-1], y0, t_end, exc)
            _raise_if_unstable(partition, dt, ts[-1], ys[-1], n, exc)
            _raise_with_singular_sets(partition.system, exc)
        raise
    finally:
        bar.close()
    return np.array(ts), np.array(ys)


def _run_compiled(method, compiled, partition, t_end, y0, dt, record_every, progress,
                  max_wall_s):
    """(times, states, evaluations) of a fixed-step run in the compiled loops, with the
    errors of the Python path (gpme_core.compiled_runs)."""
    model, n = partition.system.model, compiled.n
    bar = _Reporter(progress, int(round(t_end / dt)), t_end, method)

    def on_error(t_good, y_good, exc):
        _raise_if_singular(partition.system, t_good, y_good, y0, t_end, exc)
        if method == "RK4":
            _raise_if_unstable(partition, dt, t_good, y_good, n, exc)
        _raise_with_singular_sets(partition.system, exc)
    try:
        return run_compiled(method, compiled, partition, t_end, y0, dt, record_every, bar,
                            lambda t: _check_wall(bar.start, max_wall_s, t, t_end, method),
                            lambda t, y, step: _check_state(model, t, y, n, step), on_error)
    finally:
        bar.close()


def _raise_if_singular(system, t_good, y_good, y0, t_end, exc):
    """Re-raise a failed run naming the expression (constraint, programme, drive) that runs
    into a pole or domain edge at the last recorded state (gpme_core.singular_approach),
    before the failure is blamed on the step; else leave the original error.  An
    expression's own error for a value that is not finite (constraints.SympyPointConstraint,
    time_functions.SympyTimeFunction: it names the expression, the time and where it is not
    smooth) is raised as it is, whatever the step."""
    if isinstance(exc, ConstraintError) and "is not finite at t =" in str(exc):
        raise exc
    try:
        cause = approach(system, float(t_good), np.asarray(y_good, dtype=float),
                         np.asarray(y0, dtype=float), float(t_end))
    except (ArithmeticError, ValueError, TypeError, np.linalg.LinAlgError, GpmeError):
        return
    if cause:
        raise type(exc)(f"the run failed near t = {t_good:.6g} s because {cause}. The "
                        f"failure it caused: {exc}") from None


def _raise_if_unstable(partition, dt, t_good, y_good, n, exc):
    """Re-raise a failed RK4 run as UnstableStepError when dt is above the stability limit at
    the last recorded state before the failure (else leave the original error)."""
    try:
        limit, mode = rk4_limit(partition.system, t_good, y_good[:n], y_good[n:2 * n])
    except (ArithmeticError, ValueError, np.linalg.LinAlgError, GpmeError):
        return
    if dt > limit:
        raise UnstableStepError(
            unstable_step_message(dt, limit, mode, f"at t = {t_good:.6g} s, the last "
                                  "recorded state before the run failed") +
            f". The failure it caused: {exc}") from None


def nonsmooth_expressions(system):
    """['constraint 'C': division: where t - 0.03 = 0', ...]: where the SymPy expressions of
    ``system`` (constraints, programmes, drives) are not smooth (poles, domain edges)."""
    found = []
    named = [(f"constraint {c.name!r}", c) for c in system.constraint_specs]
    named += [(f"drive on {d.joint!r}", d) for d in system.model.drives]
    for label, item in named:
        for holder in (item, getattr(item, "function", None)):
            expr = getattr(holder, "expr", None)
            if expr is not None:
                found += [f"{label}: {where}" for where in singular_sets(expr)]
    return found


def _raise_with_singular_sets(system, exc):
    """Re-raise a divergence or a coordinate leaving its range with the places where the
    run's expressions are not smooth (a pole the step grid stepped over gives huge, finite
    values, not a non-finite one)."""
    if not ("diverged" in str(exc) or "the motion reaches" in str(exc)):
        return
    hints = nonsmooth_expressions(system)
    if hints:
        raise type(exc)(f"{exc}. Expressions of this run that are not smooth "
                              f"everywhere (a pole or domain edge the run may have crossed): "
                              f"{'; '.join(hints)}") from None


def _check_wall(start, max_wall_s, t, t_end, method):
    """Stop a run that has used more than max_wall_s of wall time (None: no limit)."""
    if max_wall_s is None:
        return
    elapsed = time.perf_counter() - start
    if elapsed > max_wall_s:
        raise SimulationError(
            f"stopped after {elapsed:.3g} s of wall time (the limit is {max_wall_s:.3g} s) "
            f"at t = {t:.6g} s of t_end = {t_end:.6g} s ({method}); at this rate the run "
            f"would take about {elapsed * t_end / max(t, 1e-300) / 3600:.3g} h. Shorten "
            "t_end, use a method suited to the model (Radau for stiff models, RK4 with a "
            "stable step otherwise), or lift the limit (--force)")


class _Reporter:
    """A run's progress over ``total`` units (steps, or parts of t_end) up to ``t_end`` s,
    sent to ``callback`` as gpme_core.progress.Progress events (None: nothing is sent; see
    that module for when).  ``start`` is the wall clock of the run, read by the wall-time
    limit too; compilation happens before it (gpme_core.run_cost.time_evaluation)."""

    def __init__(self, callback, total, t_end, method):
        self.callback, self.total, self.t_end, self.method = callback, total, t_end, method
        self.start, self.done = time.perf_counter(), 0
        self._send(0, False)

    def _send(self, done, finished):
        if self.callback is not None:
            self.callback(Progress(self.method, done, self.total,
                                   self.t_end * done / max(self.total, 1), self.t_end,
                                   time.perf_counter() - self.start, finished))

    def update(self, done):
        self.done = done
        self._send(done, False)

    def close(self):
        self._send(self.done, True)


def _scipy(rhs, model, t_end, y0, method, output_dt, rtol, atol, n, max_step=None,
           progress=None, max_wall_s=None, last_good=None):
    """(times, states, evaluations) of a solve_ivp run; ``last_good`` (a list, or None) is
    set to [t, y] of the last state evaluated without an error."""
    t_eval = np.linspace(0.0, t_end, int(round(t_end / output_dt)) + 1)
    bar = _Reporter(progress, SCIPY_PROGRESS_UNITS, t_end, method)
    start = time.perf_counter()
    calls = [0, 0]          # evaluations, progress units reached

    def checked(t, y):
        _check_state(model, t, y, n)
        calls[0] += 1
        if calls[0] % WALL_CHECK_EVERY == 0:
            reached = int(SCIPY_PROGRESS_UNITS * min(t / t_end, 1.0))
            if reached > calls[1]:
                calls[1] = reached
                bar.update(reached)
            _check_wall(start, max_wall_s, t, t_end, method)
        dy = rhs(t, y)
        if last_good is not None:
            last_good[:] = [t, np.array(y)]
        return dy
    options = {} if max_step is None else {"max_step": max_step}
    if method in IMPLICIT_METHODS:
        # structure of d(rhs)/dy: q_dot' = q_dot (identity block), q_ddot and the work
        # rates depend on (q, q_dot) only; the work integrals feed back into nothing.  Without
        # it, finite differences along the work columns find no change and their step
        # factors overflow, and the implicit method crawls.
        sparsity = np.zeros((len(y0), len(y0)), dtype=bool)
        sparsity[:n, n:2 * n] = np.eye(n, dtype=bool)
        sparsity[n:, :2 * n] = True
        options["jac_sparsity"] = sparsity
    try:
        res = solve_ivp(checked, (0.0, t_end), y0, method=method, t_eval=t_eval, rtol=rtol,
                        atol=atol, **options)
    finally:
        bar.close()
    if not res.success:
        raise SimulationError(f"solve_ivp({method}) failed at t = {res.t[-1] if len(res.t) else 0:.6g} s:"
                              f" {res.message}")
    return res.t, res.y.T, res.nfev


def simulate(system, t_end, q0, q_dot0, dt=None, method="RK4", output_dt=1e-3,
             rtol=1e-8, atol=1e-10, on_manifold=False, progress=None,
             switch_rcond=SWITCH_RCOND, check_step=True, before_run=None,
             max_wall_s=None, compiled=True):
    """Integrate ``system`` (a gpme_core.gpme.ProgrammedMotion) from t = 0 to t_end (s);
    the history as a DataFrame: ``run(system, t_end, q0, q_dot0, RunSettings(dt=dt, ...),
    progress, before_run).to_frame()`` (:func:`run`; the settings are
    gpme_core.run_result.RunSettings' fields, documented here).

    q0, q_dot0 : (n,) initial coordinates and velocities, ordered as model.coordinate_names
    dt         : s, RK4 step; shortened if needed to fit a whole number of steps into
                 t_end; None: STEP_SAFETY x the stability limit at the start (see
                 gpme_core.stability).  With the solve_ivp methods (steps chosen from
                 rtol/atol) a given dt is their largest step (solve_ivp's max_step).
    check_step : RK4 only: refuse (UnstableStepError, before any step) a dt above the
                 stability limit of the linearised run at the start, naming the stiffest
                 mode and a stable step.  A run that fails later (diverges or leaves a
                 joint range) with dt above the limit at its last recorded state raises
                 UnstableStepError too, whatever this flag.
    before_run : None or a callable given the run's gpme_core.run_cost.RunCost (wall time,
                 history size; one evaluation timed after compilation) before the first
                 step; it may raise to refuse the run (the CLI's budget does).
    progress   : None (silent) or a callable given the run's events
                 (gpme_core.progress.ProgressCallback): the first call's numba compilation
                 (Compiling) and where the run is (Progress).  The engine prints nothing;
                 gpme_io.progress draws them on a terminal or in a log.
    max_wall_s : s, stop the run with a SimulationError once it has taken this long (None:
                 no limit); the guard for methods whose cost is not known before the run
    method     : "RK4" (fixed step, explicit), "RadauIIA" (fixed step, implicit: three-stage
                 Radau IIA of order 5, L-stable, for models whose stiff modes (RFEM
                 torsion) would hold RK4 to tiny steps; dt default RADAU_IIA_STEP, its
                 accuracy is the step's: halve dt to measure it) or a solve_ivp method:
                 "RK45", "DOP853", "Radau".  RK4 and RadauIIA run in compiled loops
                 (gpme_core.kernels) when the system compiles (gpme_core.compiled;
                 df.attrs["compiled"] and ["compiled_reason"] say), else RK4 runs in Python
    output_dt  : s, spacing of the recorded rows (a multiple of dt for RK4)
    on_manifold: start on the constraints: dependent q and q_dot solved from Phi = 0,
                 Phi_dot = 0 at t = 0 (otherwise start where given, as the paper does)
    switch_rcond: re-choose the dependent coordinates (pivoted QR of A) whenever their
                 gpme_core.gpme.partition_rcond falls below this (default SWITCH_RCOND,
                 see there for the value); None keeps them and stops with a
                 ConstraintError where they become singular

    compiled   : True (default) runs RK4 and RadauIIA in the compiled loops when the system
                 compiles; False runs RK4 in Python (the reference path; RadauIIA has none)

    ``system`` is not changed: without dependent coordinates, the run chooses its own at
    t = 0 by pivoting (``df.attrs["dependent"]``), and every switch happens in the run's
    copy.  The motion does not depend on the partition (up to round-off).

    Returns a DataFrame with columns t, <coordinate>, <coordinate>_dot, <constraint>,
    <constraint>_dot, lambda_<constraint>, tau_<driven coordinate>, x_<frame>, y_<frame>,
    z_<frame> (world position of every named frame, m), E_kin, E_pot,
    W_dissipated, W_drive, W_reaction, E_balance_error; run metadata in ``df.attrs``,
    among them "dependent" (at t = 0), "dependent_final" and "events": a list of dicts, one
    per switch of the dependent coordinates (keys in :class:`RunPartition`), in the order
    they happened; with the solve_ivp methods "t" is the time of the evaluation that
    switched, which may belong to a step the method later rejected.
    """
    settings = RunSettings(dt=dt, method=method, output_dt=output_dt, rtol=rtol, atol=atol,
                           on_manifold=on_manifold, switch_rcond=switch_rcond,
                           check_step=check_step, max_wall_s=max_wall_s, compiled=compiled)
    return run(system, t_end, q0, q_dot0, settings, progress, before_run).to_frame()


def run(system, t_end, q0, q_dot0, settings=RunSettings(), progress=None, before_run=None):
    """gpme_core.run_result.RunResult of ``system`` from t = 0 to ``t_end`` (s) integrated
    as ``settings`` (gpme_core.run_result.RunSettings) say; progress and before_run as in
    :func:`simulate` (which documents the columns, the settings and the errors)."""
    return _plan_and_run(system, t_end, q0, q_dot0, _checked_settings(settings), progress,
                         before_run, estimate_only=False)


def estimate_simulation(system, t_end, q0, q_dot0, settings=None, **changes):
    """gpme_core.run_cost.RunCost of ``run(system, t_end, q0, q_dot0, settings)`` without
    running it: the inputs and the step are checked as simulate checks them (the same
    errors), and one right-hand-side evaluation is timed (after compilation).
    settings: a RunSettings (default RunSettings()); changes: settings given by name, as
    simulate takes them (an unknown name is a TypeError naming the known ones)."""
    settings = _checked_settings(settings or RunSettings()).with_changes(**changes)
    return _plan_and_run(system, t_end, q0, q_dot0, settings, None, None, estimate_only=True)


def _checked_settings(settings):
    if not isinstance(settings, RunSettings):
        raise ModelError(f"settings must be a gpme_core.run_result.RunSettings, got "
                         f"{type(settings).__name__}")
    return settings


def _plan_and_run(system, t_end, q0, q_dot0, settings, progress, before_run, estimate_only):
    """run's work (see simulate); with ``estimate_only`` it stops before the first step
    and returns the RunCost (estimate_simulation)."""
    dt, method, output_dt = settings.dt, settings.method, settings.output_dt
    rtol, atol, on_manifold = settings.rtol, settings.atol, settings.on_manifold
    switch_rcond, check_step = settings.switch_rcond, settings.check_step
    max_wall_s, compiled = settings.max_wall_s, settings.compiled
    if not isinstance(system, ProgrammedMotion):
        raise ModelError(f"system must be a gpme_core.gpme.ProgrammedMotion (a model with its "
                         f"constraints; ProgrammedMotion(model) for none), got "
                         f"{type(system).__name__}")
    model = system.model
    n = model.n_coordinates
    problems = []
    try:
        q0 = np.asarray(q0, dtype=float)
        q_dot0 = np.asarray(q_dot0, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"q0 and q_dot0 must be arrays of numbers ordered as "
                         f"{list(model.coordinate_names)} ({exc})") from None
    not_numbers = [label for label, value in (("t_end", t_end), ("dt", dt),
                                              ("output_dt", output_dt))
                   if value is not None and (isinstance(value, bool) or not isinstance(
                       value, (int, float, np.integer, np.floating)))]
    problems += [f"{label} must be a number of seconds, got {value!r}" for label, value in
                 (("t_end", t_end), ("dt", dt), ("output_dt", output_dt))
                 if label in not_numbers]
    # the range checks below read the values that are numbers (nan stands in for the others)
    t_end = np.nan if "t_end" in not_numbers else t_end
    dt_ok = "dt" not in not_numbers
    output_dt_ok = "output_dt" not in not_numbers
    for label, arr in (("q0", q0), ("q_dot0", q_dot0)):
        if arr.shape != (n,):
            problems.append(f"{label} must have shape ({n},) ordered as {list(model.coordinate_names)}, "
                            f"got {arr.shape}")
        elif not np.all(np.isfinite(arr)):
            problems.append(f"{label} must be finite, got {arr.tolist()}")
    if method not in METHODS:
        problems.append(f"method must be one of {METHODS}, got {method!r}")
    if progress is not None and not callable(progress):
        problems.append(f"progress must be None or a callable taking gpme_core.progress "
                        f"events, got {progress!r}")
    if "t_end" not in not_numbers and not (np.isfinite(t_end) and t_end > 0):
        problems.append(f"t_end must be positive (s), got {t_end!r}")
    if not dt_ok:
        pass
    elif dt is not None and not (np.isfinite(dt) and dt > 0):
        problems.append(f"dt must be a positive step in s, got {dt!r}")
    elif dt is not None and np.isfinite(t_end) and t_end > 0 and dt > t_end:
        problems.append(f"dt = {dt!r} s is longer than the run (t_end = {t_end!r} s); give "
                        "dt <= t_end")
    if not output_dt_ok:
        pass
    elif not (np.isfinite(output_dt) and output_dt > 0):
        problems.append(f"output_dt must be a positive spacing in s, got {output_dt!r}")
    elif np.isfinite(t_end) and t_end > 0:
        history_bytes = (t_end / output_dt + 1) * (2 * n + N_WORK) * 8
        if history_bytes > MAX_HISTORY_BYTES:
            problems.append(
                f"t_end = {t_end:g} s recorded every output_dt = {output_dt:g} s is "
                f"{t_end / output_dt:.3g} rows, {history_bytes / 2 ** 30:.3g} GiB of state "
                f"in memory (limit {MAX_HISTORY_BYTES / 2 ** 30:g} GiB, "
                "gpme_core.integrate.MAX_HISTORY_BYTES); shorten t_end or raise output_dt")
    if problems:
        raise ModelError(problems)
    if switch_rcond is not None and not switch_rcond > 0:
        raise ModelError(f"switch_rcond must be a positive number or None, got {switch_rcond!r}")
    dependent = system.dependent
    if dependent is None:
        dependent = system.pivoted_dependent(0.0, q0, q_dot0)
    start_system = system.with_dependent(dependent)     # the caller's system is not changed
    if on_manifold:
        q0, q_dot0 = start_system.consistent_state(0.0, q0, q_dot0)
    y0 = np.concatenate([q0, q_dot0, np.zeros(N_WORK)])
    events = []
    partition = RunPartition(start_system, switch_rcond, events)
    rhs = _rhs_factory(partition, n)
    use_compiled = compiled
    compiled, not_compiled = None, "the method has no compiled loop"
    if method in COMPILED_METHODS:
        compiled, not_compiled = (for_system(start_system) if use_compiled else
                                  (None, "compiled=False"))
    seconds_per_eval = None
    if progress is not None or before_run is not None:   # compiles first, reported, times
        seconds_per_eval = time_evaluation(start_system, q0, q_dot0, progress=progress,
                                           compiled=compiled)[1]
    limit = None
    if method == "RK4" and (dt is None or check_step) or (
            before_run is not None and method in EXPLICIT_ADAPTIVE_METHODS):
        limit, mode = rk4_limit(start_system, 0.0, q0, q_dot0)
    if method == "RK4":
        if dt is None:
            dt = safe_step(limit, min(output_dt, t_end))
        elif check_step and dt > limit:
            raise UnstableStepError(unstable_step_message(dt, limit, mode,
                                                          "at the start (t = 0)"))
        dt, record_every = rk4_step_plan(t_end, dt, output_dt)
    if method == "RadauIIA":
        if compiled is None:
            raise ModelError(f"method 'RadauIIA' runs compiled only, and this system cannot be "
                             f"compiled: {not_compiled}; use method='Radau' (SciPy) or 'RK4'")
        dt, record_every = rk4_step_plan(t_end, min(dt or RADAU_IIA_STEP, output_dt, t_end),
                                         output_dt)
    if before_run is not None or estimate_only:
        if seconds_per_eval is None:
            seconds_per_eval = time_evaluation(start_system, q0, q_dot0, compiled=compiled)[1]
        if limit is None and method in EXPLICIT_ADAPTIVE_METHODS:
            limit = rk4_limit(start_system, 0.0, q0, q_dot0)[0]
        cost = estimate_run(method, t_end, output_dt, n, history_columns(start_system),
                            seconds_per_eval, dt=dt, stable_step=limit)
        if estimate_only:
            return cost
        before_run(cost)
    start = time.perf_counter()
    nfev = None
    if compiled is not None:
        ts, ys, nfev = _run_compiled(method, compiled, partition, t_end, y0, dt,
                                     record_every, progress, max_wall_s)
    elif method == "RK4":
        ts, ys = _rk4(rhs, model, t_end, y0, dt, record_every, n, progress, partition,
                      max_wall_s)
        nfev = 4 * int(round(t_end / dt))
    else:
        last_good = [0.0, y0]
        try:
            ts, ys, nfev = _scipy(rhs, model, t_end, y0, method, output_dt, rtol, atol, n,
                                  max_step=dt, progress=progress, max_wall_s=max_wall_s,
                                  last_good=last_good)
        except (SimulationError, ConstraintError) as exc:
            _raise_if_singular(start_system, last_good[0], last_good[1], y0, t_end, exc)
            _raise_with_singular_sets(start_system, exc)
            raise
    wall = time.perf_counter() - start
    return RunResult(history_table(start_system, ts, ys, switch_rcond), model=model.name,
                     method=method, dt=dt,
                     rtol=None if method in FIXED_STEP_METHODS else rtol, wall_time_s=wall,
                     compiled=compiled is not None,
                     compiled_reason="" if compiled is not None else not_compiled,
                     rhs_evaluations=nfev, dependent=dependent,
                     dependent_final=partition.dependent, events=events,
                     switch_rcond=switch_rcond, baumgarte=(system.alpha, system.beta),
                     on_manifold=on_manifold)


def history_columns(system):
    """Number of columns of :func:`history_table` for ``system``: t, q, q_dot, three per
    constraint, one per driven coordinate, three per frame, and six energy columns."""
    model = system.model
    drives = {d.joint for d in model.drives}
    return (1 + 2 * model.n_coordinates + 3 * system.n_constraints + len(drives)
            + 3 * len(model.frames) + 6)


def history_table(system, ts, ys, switch_rcond=SWITCH_RCOND):
    """{column name: (k,) array} of a run, one entry per recorded time, in the column
    order of :func:`simulate`'s history.

    system : ProgrammedMotion with its dependent coordinates set (not changed); the rows
             are solved with a partition switched as in a run (``switch_rcond``), which
             does not change any column (multipliers included: A has full row rank).
    ts (k,) s; ys (k, 2 n + 3) states as integrated by :func:`simulate`.
    """
    model = system.model
    partition = RunPartition(system, switch_rcond)
    n = model.n_coordinates
    names = list(model.coordinate_names)
    cols = {"t": ts}
    for k, nm in enumerate(names):
        cols[nm] = ys[:, k]
    for k, nm in enumerate(names):
        cols[f"{nm}_dot"] = ys[:, n + k]
    m = system.n_constraints
    phis = np.empty((len(ts), m))
    phis_dot = np.empty((len(ts), m))
    lams = np.empty((len(ts), m))
    e_k = np.empty(len(ts))
    e_p = np.empty(len(ts))
    drive_idx = sorted({model.index(d.joint) for d in model.drives})
    frames = sorted(model.frames)
    frame_pos = np.empty((len(ts), len(frames), 3))
    taus = np.empty((len(ts), len(drive_idx)))
    for r, (t, y) in enumerate(zip(ts, ys)):
        q, q_dot = y[:n], y[n:2 * n]
        sol = partition.solve(t, q, q_dot)
        phis[r], phis_dot[r], lams[r] = sol.phi, sol.phi_dot, sol.multipliers
        e_k[r] = kinetic_energy(model, sol.terms.kin, q_dot)
        e_p[r] = potential_energy(model, q)
        taus[r] = sol.terms.t[drive_idx]
        for j, fname in enumerate(frames):
            fr = model.frames[fname]
            frame_pos[r, j] = (sol.terms.kin.T[fr.link_index] @ fr.transform[:, 3])[:3]
    for j, nm in enumerate(system.constraint_names):
        cols[nm] = phis[:, j]
        cols[f"{nm}_dot"] = phis_dot[:, j]
        cols[f"lambda_{nm}"] = lams[:, j]
    for j, k in enumerate(drive_idx):
        cols[f"tau_{names[k]}"] = taus[:, j]
    for j, fname in enumerate(frames):
        for a, axis in enumerate("xyz"):
            cols[f"{axis}_{fname}"] = frame_pos[:, j, a]
    cols["E_kin"] = e_k
    cols["E_pot"] = e_p
    cols["W_dissipated"] = ys[:, 2 * n]
    cols["W_drive"] = ys[:, 2 * n + 1]
    cols["W_reaction"] = ys[:, 2 * n + 2]
    e_tot = e_k + e_p
    cols["E_balance_error"] = (e_tot - e_tot[0]) - (cols["W_drive"] + cols["W_reaction"]
                                                    - cols["W_dissipated"])
    return cols

"""Whole programmed runs of a scenario in Exudyn (generalized-alpha, index 3) and their rows.

The scenario's model becomes an Exudyn kinematic tree (crosscheck.exudyn.model.add_tree:
the tree, Exudyn's spring-dampers, coordinate loads for the drives, the tree's gravity) and
its constraints one ObjectConnectorCoordinateVector with time-dependent constraint and
Jacobian user functions (crosscheck.exudyn.constraints: Pinocchio's frame kinematics and
SymPy's derivatives of the task expressions).  Exudyn integrates the index-3 DAE

    M(q) q_ddot + C_q(t, q)^T lambda_exu = f(t, q, q_dot),      C(t, q) = Phi(t, q) = 0

with its implicit generalized-alpha solver (Arnold & Bruls), constant step, full Newton,
spectral radius SPECTRAL_RADIUS.  gpme writes M q_ddot = h + Q + A^T lambda with A = C_q,
so its multipliers are lambda = -lambda_exu (tests/test_exudyn.py: a pendulum held by a
coordinate constraint, lambda = +m g l by hand).

Consistent start.  Exudyn's own initial accelerations ignore constraints given by user
functions (its documentation of computeInitialAccelerations), and a generalized-alpha run
started from inconsistent accelerations carries an O(1) multiplier transient that decays
only as rho^k per step (measured on the rigid crane: lambda off by 45 % at t = 0, still
1 % after 0.05 s at dt = 1e-3 s).  So the start is made consistent here, on Exudyn's side:
q_ddot0 and lambda0 solve [M C_q^T; C_q 0] [q_ddot0; lambda_exu0] = [f; -kappa] with
Exudyn's own M and f (crosscheck.exudyn.model.mass_and_forces) and C_q, kappa from
Pinocchio + SymPy, and are handed to the solver as initial accelerations and AE
coordinates (computeInitialAccelerations = False).  The start must lie on the constraints
(ProgrammedConstraints.check_start).

No gpme constraint, kinematics, dynamics or integration code is called here.
"""
import math
import time
from dataclasses import dataclass, replace
from typing import Optional

import exudyn as exu
import numpy as np
import pandas as pd

from gpme_core.errors import ConstraintError, SimulationError
from gpme_core.stability import rk4_step

from .. import halving_gates, run_gates
from ..compare import Tolerance, compare
from ..sampling import COMPARED_DT, compared_output_dt
from ..convergence import FINEST, RefinementBudget, refine
from ..engine_steps import engine_first_step
from ..halving_gates import HalvedRuns
from ..pinocchio.runs import exact_columns, run_step
from ..run_gates import PHI_EVAL_ROUNDINGS, phi_floor, phi_term_scale
from .constraints import CONSISTENT_TOL, ProgrammedConstraints
from .model import add_tree, mass_and_forces, quiet_settings, solve_implicit

EPS = float(np.finfo(float).eps)
ENGINE = "exudyn"
SCHEME = "generalized-alpha, index 3"
ORDER = 2.0                      # global order of generalized-alpha in q, q_dot and lambda
OUTPUT_DT = COMPARED_DT          # s, spacing of the compared samples (shorter runs:
#                                  crosscheck.sampling.compared_output_dt)
SPECTRAL_RADIUS = 0.9            # rho_inf: Exudyn's default; index 3 needs rho < 1
# Newton (Exudyn's residual norm): full Newton reaches round-off within these; 1e-2 of
# these gives bit-identical runs (measured on the crane), so the converged solution does
# not depend on them; the solver floor of the gates is measured by loosening them 100x.
NEWTON_RELATIVE = 1e-10
NEWTON_ABSOLUTE = 1e-12
NEWTON_MAX_ITERATIONS = 25
LOOSE_FACTOR = 100.0


@dataclass(frozen=True)
class SolverSettings:
    """The generalized-alpha run's settings.

    spectral_radius : rho_inf in [0, 1) (index 3 needs < 1)
    relative, absolute : Newton tolerances of Exudyn's residual norm
    """

    spectral_radius: float = SPECTRAL_RADIUS
    relative: float = NEWTON_RELATIVE
    absolute: float = NEWTON_ABSOLUTE

    def loosened(self, factor: float = LOOSE_FACTOR) -> "SolverSettings":
        return SolverSettings(self.spectral_radius, self.relative * factor,
                              self.absolute * factor)

    def describe(self) -> str:
        return (f"rho_inf = {self.spectral_radius:g}, full Newton, relative tolerance "
                f"{self.relative:g}, absolute {self.absolute:g}")


def columns(model, constraint_names) -> list:
    """Column names of a run: t, coordinates, <coordinate>_dot, Phi by name, <name>_dot,
    lambda_<name> (gpme's)."""
    names = list(model.coordinate_names)
    cons = list(constraint_names)
    return ["t", *names, *(f"{c}_dot" for c in names), *cons, *(f"{c}_dot" for c in cons),
            *(f"lambda_{c}" for c in cons)]


def consistent_start(model, constraints: ProgrammedConstraints, q0, q_dot0, t0: float = 0.0):
    """(q_ddot0 (n,), lambda_exu0 (m,)): the start's accelerations (rad/s^2, m/s^2) and
    Exudyn-signed multipliers from Exudyn's M, f and Pinocchio/SymPy's C_q, kappa."""
    m_mat, f = mass_and_forces(model, t0, q0, q_dot0)
    a, kappa = constraints.acceleration_terms(t0, q0, q_dot0)
    n, k = len(f), len(kappa)
    kkt = np.block([[m_mat, a.T], [a, np.zeros((k, k))]])
    rcond = 1.0 / np.linalg.cond(kkt)
    if not rcond > 1e3 * np.finfo(float).eps:
        raise ConstraintError(
            f"the constraints {list(constraints.names)} are singular at the start t = {t0:g} s "
            f"(1/cond of [M C_q^T; C_q 0] = {rcond:.1e}, C_q = {np.array2string(a, precision=3)}): "
            "they are dependent or the frame cannot move in the constrained direction there; "
            "start elsewhere or change the task")
    sol = np.linalg.solve(kkt, np.concatenate([f, -kappa]))
    return sol[:n], sol[n:]


def _settings(t_end, steps, solver: SolverSettings):
    s = quiet_settings(t_end, steps)
    ti = s.timeIntegration
    ti.generalizedAlpha.spectralRadius = float(solver.spectral_radius)
    ti.generalizedAlpha.useIndex2Constraints = False
    ti.generalizedAlpha.useNewmark = False
    ti.generalizedAlpha.computeInitialAccelerations = False
    ti.generalizedAlpha.resetAccelerations = False
    ti.newton.useModifiedNewton = False
    ti.newton.relativeTolerance = float(solver.relative)
    ti.newton.absoluteTolerance = float(solver.absolute)
    ti.newton.maxIterations = NEWTON_MAX_ITERATIONS
    ti.adaptiveStep = False
    ti.automaticStepSize = False
    return s


def programmed_run(scenario, t_end: float, dt: float, output_dt: float = OUTPUT_DT,
                   model=None, constraint_specs=None, pin_system=None, q0=None, q_dot0=None,
                   solver: SolverSettings = SolverSettings()) -> pd.DataFrame:
    """The scenario's programmed run in Exudyn: generalized-alpha, index 3, step dt (s),
    t_end (s), recorded every output_dt (s; a whole number of steps).

    model, constraint_specs, pin_system : replace the scenario's model (Exudyn's tree and
        the data of Pinocchio's kinematics), constraint specs, or only Pinocchio's model
        (tests perturb one side); q0, q_dot0 (n,): the start (default the scenario's).
    Returns the columns of :func:`columns`, lambda with gpme's sign; attrs: engine, dt,
    steps, wall_time_s, phi_scale {name: max_t sum_j |A_kj| (|q_j| + 1), crosscheck.run_gates.phi_term_scale, the size of the terms Phi
    is formed from}, newton_iterations, start_violation (max|Phi|, max|Phi_dot|),
    solver (SolverSettings.describe()).
    Raises ConstraintError (start off the constraints) or SimulationError naming Exudyn's
    message (Newton divergence, singular Jacobian, a user function's error).
    """
    model = scenario.model if model is None else model
    specs = scenario.constraints if constraint_specs is None else constraint_specs
    q0 = np.asarray(scenario.q0 if q0 is None else q0, dtype=float)
    q_dot0 = np.asarray(scenario.q_dot0 if q_dot0 is None else q_dot0, dtype=float)
    steps = int(round(t_end / dt))
    every = int(round(output_dt / dt))
    if steps < 1 or abs(steps * dt - t_end) > 1e-9 * max(t_end, 1.0) or every < 1 or \
            abs(every * dt - output_dt) > 1e-9 * max(output_dt, 1.0):
        raise ValueError(f"t_end = {t_end!r} s and output_dt = {output_dt!r} s must be whole "
                         f"numbers of steps dt = {dt!r} s")
    pc = ProgrammedConstraints(specs, model, pin_system)
    if pc.m == 0:
        raise ValueError(f"{scenario.name}: no programmed constraints to realise")
    violation = pc.check_start(0.0, q0, q_dot0, scenario.name)
    a0, lam0 = consistent_start(model, pc, q0, q_dot0)

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    tree = add_tree(mbs, model, q0, q_dot0, scenario.system.damping_form)
    obj = pc.add_to(mbs, tree)
    n, m = tree.n, pc.m
    records = {0: (0.0, q0.copy(), q_dot0.copy(), -lam0)}

    def post_step(mbs_, t):
        k = int(round(t / dt))
        if k > 0 and k % every == 0 and abs(t - k * dt) < 1e-6 * dt:
            sd = mbs.systemData
            records[k // every] = (k * dt, np.array(sd.GetODE2Coordinates()[:n]),
                                   np.array(sd.GetODE2Coordinates_t()[:n]),
                                   -np.array(sd.GetAECoordinates())[ae])
        return True

    mbs.SetPostStepUserFunction(post_step)
    mbs.Assemble()
    ae = np.asarray(mbs.systemData.GetObjectLTGAE(obj), dtype=int)
    for cfg in (exu.ConfigurationType.Initial, exu.ConfigurationType.Current):
        acc = np.zeros(mbs.systemData.ODE2Size(cfg))
        acc[:n] = a0
        mbs.systemData.SetODE2Coordinates_tt(acc.tolist(), configuration=cfg)
        lam = np.zeros(mbs.systemData.AEsize(cfg))
        lam[ae] = lam0
        mbs.systemData.SetAECoordinates(lam.tolist(), configuration=cfg)
    settings = _settings(t_end, steps, solver)
    ok, message, wall, sim = solve_implicit(mbs, settings)
    n_out = int(round(t_end / output_dt))
    if not ok or len(records) != n_out + 1:
        reached = max(records) * output_dt
        t_fail = getattr(sim.it, "currentTime", np.nan)
        raise SimulationError(f"Exudyn run of {scenario.name} failed at t = {t_fail:.6g} s "
                              f"(dt = {dt:g} s, {solver.describe()}; last recorded t = "
                              f"{reached:g} s): "
                              f"{(message or 'no message').strip()[:400]}")
    rows, phi_scale = [], np.zeros(m)
    for k in range(n_out + 1):
        t, q, v, lam = records[k]
        phi, phi_dot, a = pc.evaluate(t, q, v)
        phi_scale = np.maximum(phi_scale, phi_term_scale(a, q))
        rows.append([t, *q, *v, *phi, *phi_dot, *lam])
    df = pd.DataFrame(rows, columns=columns(model, pc.names))
    df.attrs.update(engine=ENGINE, dt=dt, steps=steps, wall_time_s=wall,
                    phi_scale=dict(zip(pc.names, phi_scale.tolist())),
                    newton_iterations=int(sim.it.newtonStepsCount)
                    if hasattr(sim.it, "newtonStepsCount") else -1,
                    start_violation=violation, solver=solver.describe())
    return df


# --------------------------------------------------------------------------- halving and rows
EXACT = "exact programmed run"
EXUDYN_DT = 1e-3          # s, Exudyn's first coarsest step h (then h/2, h/4)
# halvings beyond the first three runs to reach the asymptotic regime at every compared
# time (crosscheck.convergence); a run projected above 120 s is not started
REFINEMENT = RefinementBudget(max_halvings=4, max_run_wall_s=120.0)


def _phi_floors(df, constraint_names) -> dict:
    """{Phi column: round-off floor}: Phi is formed from terms of size phi_scale (attrs,
    max_t sum_j |A_kj| (|q_j| + 1), crosscheck.run_gates.phi_term_scale), not from |Phi| ~ 0, so one evaluation rounds at PHI_EVAL_ROUNDINGS
    eps phi_scale.  It does not accumulate over the steps: the index-3 solver sets Phi = 0
    at every step (to Newton's tolerance, in the solver floor), and gpme's Baumgarte term
    pulls Phi back within 1/alpha (crosscheck.run_gates.phi_floor), so an older rounding
    is not carried."""
    scale = df.attrs.get("phi_scale", {})
    return {c: PHI_EVAL_ROUNDINGS * EPS * float(scale.get(c, 0.0)) for c in constraint_names}


def gpme_floors(scenario, columns_compared, exudyn_finest, n_steps, h) -> dict:
    """{Phi column: round-off floor of gpme's finest run (n_steps of h s)} beyond
    halving_gates' floor, which takes the column's own |x|max as the scale: Phi is ~0 on
    the manifold but formed from terms of size phi_scale (the scale from Exudyn's run: the
    same positions up to the compared errors), with the roundings Baumgarte has not yet
    pulled back (crosscheck.run_gates.phi_floor, one engine's half)."""
    scale = exudyn_finest.attrs.get("phi_scale", {})
    baumgarte = (scenario.system.alpha, scenario.system.beta)
    cons = [c for c in scenario.system.constraint_names if c in columns_compared]
    return {c: 0.5 * phi_floor(float(scale.get(c, 0.0)), n_steps, h, baumgarte) for c in cons}


def halved_runs(scenario, t_end: float, columns_compared, dt: float = EXUDYN_DT,
                output_dt: float = OUTPUT_DT, solver: SolverSettings = SolverSettings(),
                budget: RefinementBudget = REFINEMENT, log=None, **run_kw):
    """Exudyn's runs at h, h/2, h/4 as crosscheck.halving_gates.HalvedRuns, with solver
    floors.

    h starts at ``dt`` and is halved (crosscheck.convergence.refine, within ``budget``)
    while Exudyn's runs are not in generalized-alpha's asymptotic regime at every compared
    time: the run-wide order over the coordinates, velocities and multipliers resolved
    above their floors within 1 of 2, and the local order supporting the error bound at
    each sample (a start transient of the index-3 solver, or a flexible mode the step does
    not resolve yet, converges slower at a few samples).  Solver floor of each column:
    max_t |x_{h/4} - x_{h/4, loose}|, the change of the finest run when both Newton
    tolerances are loosened LOOSE_FACTOR times (the error a converged Newton leaves is at
    most proportional to its tolerance, so this bounds it, and it includes the round-off
    amplification of index 3 in lambda, ~eps |q| / h^2), plus for Phi the round-off of its
    terms (:func:`_phi_floors`).
    run_kw: passed to :func:`programmed_run` (model, constraint_specs, pin_system, ...).
    Returns (HalvedRuns with .refinement, info dict with wall times, halvings, dt, loose).
    """
    log = log or (lambda msg: None)
    cons = [c for c in scenario.system.constraint_names if c in columns_compared]
    # judged: coordinates and velocities.  The index-3 multipliers of generalized-alpha
    # carry an O(h) start transient that decays per step and round-off amplified as
    # eps / h^2 (Arnold & Bruls 2007), so their halving order is unreliable at both ends
    # of the step range (measured on a rigid xArm7: lambda's order -1.5 at 1.25e-4 s
    # while every q_dot converged at 2.00); they are gated by their halving difference
    # and the measured Newton floor, not used to judge the run's convergence
    state_cols = [c for c in columns_compared
                  if c not in cons and not c.startswith("lambda_")]
    walls, loose_runs = [], {}

    def run_at(h, settings=solver):
        df = programmed_run(scenario, t_end, h, output_dt, solver=settings, **run_kw)
        walls.append(df.attrs["wall_time_s"])
        return df

    def solver_floor(finest, h):
        """{column: max_t |x - x_loose|} at step h (the loose run made once per step)."""
        if h not in loose_runs:
            loose_runs[h] = run_at(h, solver.loosened())
        loose = loose_runs[h]
        return {c: float(np.abs(finest[c].to_numpy(float) - loose[c].to_numpy(float)).max())
                for c in columns_compared}

    def floors_of(runs):
        # the Newton floor belongs in the judgement too: index 3 amplifies round-off in
        # the velocities (~eps/h) and multipliers (~eps/h^2), which at small h would
        # otherwise read as unresolved-looking noise of negative order
        h4 = float(runs[-1].attrs["dt"])
        trial = HalvedRuns(ENGINE, SCHEME, ORDER, runs, 4.0 * h4, solver_floor(runs[-1], h4))
        return {c: trial.floor(c, scenario.model) for c in state_cols}

    runs, h, _, record = refine(run_at, dt, state_cols, floors_of, ORDER, FINEST, budget,
                                lambda m: log(f"exudyn {scenario.name}: {m}"))
    finest = runs[-1]
    floor = solver_floor(finest, h / 4)
    loose = loose_runs[h / 4]
    for c, f in _phi_floors(finest, cons).items():
        floor[c] += f
    out = HalvedRuns(ENGINE, SCHEME, ORDER, tuple(runs), h, floor, refinement=record,
                     judged=tuple(state_cols))
    return out, {"wall_time_s": float(sum(walls)), "halvings": record.halvings, "dt": h,
                 "loose": loose}


QUICK_T_END = 0.2         # s, run length of the quick (CI) section
# s, longest run of the full plan: the crane's whole 10 s and the UR5's whole 4 s are
# affordable (measured, docs/crosscheck-exudyn.md); gpme's RK4 runs at h, h/2, h/4 then
# take up to ~1.5 min and Exudyn's four runs up to ~2.5 min per scenario.
FULL_T_END = 10.0
# RK4 steps of gpme's coarsest run above which the comparison is not run (an information
# row says so): gpme's three runs cost ~7x this many steps.
MAX_GPME_STEPS = 250_000


def run_t_end(scenario, quick: bool) -> float:
    """s: the quick run min(quick_t_end, QUICK_T_END), else the whole run up to FULL_T_END."""
    return min(scenario.quick_t_end, QUICK_T_END) if quick else min(scenario.t_end, FULL_T_END)


def _info(scenario, quantity, case, text):
    return compare(ENGINE, scenario.name, quantity, case, [0.0], [0.0],
                   Tolerance(np.inf, 0.0, f"information: {text}"), ["-"])


def start_row(scenario, violation, case) -> dict:
    """Row: the start lies on the constraints (max|Phi(0)|, max|Phi_dot(0)|)."""
    tol = Tolerance(CONSISTENT_TOL, 0.0,
                    "an index-3 solver projects an inconsistent start onto Phi = 0 in its "
                    "first step, which gpme's Baumgarte run does not do; the runs compare "
                    f"only from a start on the constraints (|Phi|, |Phi_dot| <= "
                    f"{CONSISTENT_TOL:g}, gpme's consistent_state reaches ~1e-12)")
    return compare(ENGINE, scenario.name, f"{EXACT}: start on the constraints", case,
                   list(violation), [0.0, 0.0], tol, ["max|Phi(0)|", "max|Phi_dot(0)|"])


def consistent_start_state(scenario, log=None):
    """(q0 (n,), q_dot0 (n,), rows): the start both engines' runs begin from.

    The scenario's own start when it lies on the constraints (rows empty).  Otherwise an
    index-3 solver would begin by projecting it onto Phi = 0, Phi_dot = 0 in its first step,
    which gpme's Baumgarte run does not do (it returns to the constraints over ~1/alpha), so
    the two runs would differ by the start, not by the dynamics: both begin from the
    start's projection instead (gpme's ProgrammedMotion.consistent_state, confirmed on
    Exudyn's side by Pinocchio's kinematics, ProgrammedConstraints.check_start), and one
    information row says so with the size of the projection.  Raises ConstraintError when
    no projection reaches the constraints (the task is unreachable from that start)."""
    log = log or (lambda msg: None)
    pc = ProgrammedConstraints(scenario.constraints, scenario.model)
    q0 = np.asarray(scenario.q0, float)
    q_dot0 = np.asarray(scenario.q_dot0, float)
    try:
        pc.check_start(0.0, q0, q_dot0, scenario.name)
        return q0, q_dot0, []
    except ConstraintError as exc:
        off = str(exc)
    qc, qdc = scenario.system.consistent_state(0.0, q0, q_dot0)
    violation = pc.check_start(0.0, qc, qdc, scenario.name)     # raises if still off
    dq = float(np.abs(qc - q0).max(initial=0.0))
    dv = float(np.abs(qdc - q_dot0).max(initial=0.0))
    text = (f"the model's start is off the programmed constraints ({off.split(';')[0][:200]}); "
            "an index-3 solver would project it onto them in its first step, gpme's "
            "Baumgarte run returns to them over ~1/alpha, so both runs begin from its "
            f"projection (max|dq| = {dq:.3g}, max|dq_dot| = {dv:.3g}; then max|Phi| = "
            f"{violation[0]:.1e}, max|Phi_dot| = {violation[1]:.1e})")
    log(f"exudyn {scenario.name}: {text}")
    return qc, qdc, [_info(scenario, f"{EXACT}: start projected onto the constraints", "-",
                           text)]


def first_step(scenario) -> float:
    """s, Exudyn's default first step: EXUDYN_DT, or for a model with stiff springs (RFEM
    links) the step at which the stiffest linearised mode lambda_max at the start has
    |lambda_max| h ~ 1.4 (half RK4's stability step, gpme_core.stability.rk4_step),
    whichever is smaller.  Generalized-alpha damps a mode with |lambda| h >> 1 towards
    rho_inf per step instead of following it, so its error only becomes O(h^2) once
    |lambda| h < 1: from 1e-3 s the UR10's CFRP forearm (lambda ~ 2e4 1/s) needed more
    halvings than any budget (observed order < 1 down to 6e-5 s)."""
    return whole_steps(rk4_step(scenario.system, scenario.q0, cap=EXUDYN_DT))


def whole_steps(dt: float, output_dt: float = OUTPUT_DT) -> float:
    """s, the largest step <= dt with a whole number of steps per output sample."""
    return output_dt / math.ceil(output_dt / float(dt) - 1e-9)


def run_section(scenario, quick: bool, log=None, refined=None, exudyn_dt: Optional[float] = None,
                **run_kw) -> list:
    """Rows (crosscheck.compare dicts) of the exact programmed run of ``scenario`` in Exudyn
    against gpme: one per coordinate, velocity, constraint value and multiplier, gated by
    both engines' step-halving errors (crosscheck.halving_gates), the two observed-order
    rows and the start row.  refined: gpme's RefinedRuns when already computed (same t_end,
    OUTPUT_DT).  run_kw: passed to Exudyn's runs (tests perturb the Exudyn side).
    A scenario without constraints gives one information row."""
    log = log or (lambda msg: None)
    t_end = run_t_end(scenario, quick)
    if not scenario.system.constraint_names:
        return [_info(scenario, f"{EXACT}: nothing programmed", "-",
                      "the scenario has no programmed constraints; Exudyn's runs compare the "
                      "programmed motion only")]
    dt = run_step(scenario)
    if refined is None and t_end / dt > MAX_GPME_STEPS:
        text = (f"not compared: {t_end:g} s at gpme's RK4 step {dt:.3g} s is {t_end / dt:.3g} "
                f"steps, above the budget of {MAX_GPME_STEPS:,}")
        log(f"exudyn {scenario.name}: {text}")
        return [_info(scenario, f"{EXACT}: not run", f"{t_end:g} s", text)]
    q0, q_dot0, start_rows = consistent_start_state(scenario, log)
    if start_rows:
        refined = None                       # made from the scenario's own start
    start = time.perf_counter()
    spacing = compared_output_dt(t_end, dt)
    if refined is None:
        refined = run_gates.refined_gpme_runs(scenario.system, q0, q_dot0, t_end, dt,
                                              spacing, compared=FINEST,
                                              log=lambda m: log(f"exudyn {scenario.name}: "
                                                                f"gpme {m}"))
    gpme_wall = time.perf_counter() - start
    cols = exact_columns(scenario)
    default = first_step(scenario) if exudyn_dt is None else exudyn_dt
    first, note, budget = engine_first_step(scenario, ENGINE, default, REFINEMENT)
    first = whole_steps(first, spacing)
    run_kw = {"q0": q0, "q_dot0": q_dot0, **run_kw}
    exu_runs, info = halved_runs(scenario, t_end, cols, first, spacing, budget=budget,
                                 log=log, **run_kw)
    gpme_runs = halving_gates.from_refined(refined)
    gpme_runs = replace(gpme_runs, solver_floor=gpme_floors(
        scenario, cols, exu_runs.finest, gpme_runs.n_steps, gpme_runs.finest_dt))
    case = (f"{EXACT}, {t_end:g} s{' from the start projected onto the constraints' if start_rows else ''}, "
            f"gpme RK4 dt = {gpme_runs.finest_dt:.3g} s, Exudyn "
            f"generalized-alpha dt = {exu_runs.finest_dt:.3g} s{note} "
            f"({exu_runs.finest.attrs['solver']})")
    rows = halving_gates.run_rows(ENGINE, scenario, gpme_runs, exu_runs, cols, EXACT, case)
    rows.append(start_row(scenario, exu_runs.finest.attrs["start_violation"], case))
    rows += [dict(r, case=case) for r in start_rows]
    log(f"exudyn {scenario.name}: {t_end:g} s, gpme {gpme_wall:.1f} s, Exudyn "
        f"{info['wall_time_s']:.1f} s (h = {info['dt']:g} s, {info['halvings']} halvings)")
    for r in rows:
        r["section"] = "runs"
    return rows

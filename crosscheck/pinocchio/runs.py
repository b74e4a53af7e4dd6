"""Whole programmed runs of a scenario realised exactly in Pinocchio, and their rows.

The scenario's model is rebuilt in Pinocchio (crosscheck.pinocchio.model.from_gpme) and
integrated with classical RK4 at gpme's step and stage times (gpme_core.integrate.
rk4_step_plan, t = k dt, the same stage formula).  Each stage evaluates, on Pinocchio's
side only:

    tau    = -K (q - q_ref) - D v + drives(t)          PinocchioSystem.applied_forces
    p, v, J, drift of every constrained frame          oMf, getFrameVelocity,
                                                       computeFrameJacobian,
                                                       getFrameClassicalAcceleration
                                                       (LOCAL_WORLD_ALIGNED, a = 0)
    Phi, Phi_dot, A, kappa                             crosscheck.constraint_reference
    gamma  = kappa + 2 alpha Phi_dot + beta^2 Phi
    q_ddot, lambda_c = pin.forwardDynamics(q, v, tau, A, gamma)

Pinocchio solves M a + b = tau + A^T lambda_c, A a + gamma = 0, so A a = -kappa -
2 alpha Phi_dot - beta^2 Phi is gpme's Baumgarte row and lambda_c has gpme's sign
(M q_ddot = h + Q + A^T lambda); :func:`kkt_residual` checks this against a KKT system
built from Pinocchio's own crba M and rnea b.

No gpme constraint, kinematics or dynamics code is called here.
"""
import time
from dataclasses import replace

import numpy as np
import pandas as pd
import pinocchio as pin

from gpme_core.errors import SimulationError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import DIVERGENCE_LIMIT, rk4_step_plan
from gpme_io.runs import resolved_step

from .. import run_gates
from ..compare import Tolerance, compare
from ..sampling import COMPARED_DT, compared_output_dt
from ..constraint_reference import evaluate_reference, reference_constraints
from .model import from_gpme

ENGINE = "pinocchio"
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
EXACT = "exact programmed run"
FREE = "free run"
QUICK_T_END = 0.2          # s, run length of the quick (CI) section
OUTPUT_DT = COMPARED_DT    # s, spacing of the compared samples (shorter runs:
#                            crosscheck.sampling.compared_output_dt)


class _Stage:
    """Evaluates one RK4 stage of the constrained dynamics in Pinocchio."""

    def __init__(self, scenario, ps, constrained=True):
        self.model = scenario.model
        self.ps = ps
        self.pm = ps.model
        self.data = ps.model.createData()
        self.n = self.model.n_coordinates
        self.refs = reference_constraints(scenario.constraints, self.model.coordinate_names) \
            if constrained else []
        self.alpha, self.beta = scenario.system.alpha, scenario.system.beta
        self.zero = np.zeros(self.n)

    def point_state(self, frame):
        """(p (3,) m, v (3,) m/s, J (3, n), drift (3,) m/s^2) of a frame origin, world."""
        pm, data = self.pm, self.data
        fid = self.ps.frames[frame]
        p = data.oMf[fid].translation.copy()
        v = pin.getFrameVelocity(pm, data, fid, LWA).linear.copy()
        drift = pin.getFrameClassicalAcceleration(pm, data, fid, LWA).linear.copy()
        jac = pin.getFrameJacobian(pm, data, fid, LWA)[:3].copy()
        return p, v, jac, drift

    def __call__(self, t, q, v):
        """(q_ddot (n,), Phi (m,), Phi_dot (m,), lambda (m,), A (m, n))."""
        pm, data = self.pm, self.data
        tau = self.ps.applied_forces(q, v, self.model.drive_forces(t))
        if not self.refs:
            z = np.zeros(0)
            return np.array(pin.aba(pm, data, q, v, tau)), z, z, z, np.zeros((0, self.n))
        pin.forwardKinematics(pm, data, q, v, self.zero)
        pin.computeJointJacobians(pm, data, q)
        pin.updateFramePlacements(pm, data)
        phi, phi_dot, a, kappa = evaluate_reference(self.refs, t, q, v, self.point_state)
        gamma = kappa + 2.0 * self.alpha * phi_dot + self.beta ** 2 * phi
        q_ddot = np.array(pin.forwardDynamics(pm, data, q, v, tau, a, gamma))
        return q_ddot, phi, phi_dot, np.array(data.lambda_c).copy(), a


def _run(scenario, t_end, dt, output_dt, ps, constrained, q0, q_dot0):
    stage = _Stage(scenario, ps, constrained)
    model = scenario.model
    n = model.n_coordinates
    step, every = rk4_step_plan(t_end, dt, output_dt)
    n_steps = int(round(t_end / step))
    names = list(model.coordinate_names)
    cnames = [r.name for r in stage.refs]
    y = np.concatenate([np.asarray(q0, float), np.asarray(q_dot0, float)])
    rows, max_cond, max_acc, phi_scale = [], 0.0, 0.0, np.zeros(len(cnames))

    def f(t, y):
        return np.concatenate([y[n:], stage(t, y[:n], y[n:])[0]])

    def record(t, y):
        nonlocal max_cond, max_acc
        q, v = y[:n], y[n:]
        q_ddot, phi, phi_dot, lam, a = stage(t, q, v)
        max_acc = max(max_acc, float(np.abs(q_ddot).max()))
        m = np.array(pin.crba(stage.pm, stage.data, q))
        m = np.triu(m) + np.triu(m, 1).T           # crba fills at least the upper triangle
        max_cond = max(max_cond, float(np.linalg.cond(m)))
        if len(cnames):
            phi_scale[:] = np.maximum(phi_scale, run_gates.phi_term_scale(a, q))
        rows.append([t, *q, *v, *phi, *phi_dot, *lam])

    start = time.perf_counter()
    record(0.0, y)
    for k in range(n_steps):
        t = k * step
        k1 = f(t, y)
        k2 = f(t + 0.5 * step, y + 0.5 * step * k1)
        k3 = f(t + 0.5 * step, y + 0.5 * step * k2)
        k4 = f(t + step, y + step * k3)
        y = y + (step / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        if not np.all(np.isfinite(y)) or np.abs(y).max() > DIVERGENCE_LIMIT:
            raise SimulationError(f"Pinocchio run of {scenario.name} diverged at t = "
                                  f"{(k + 1) * step:.6g} s (dt = {step:g} s)")
        if (k + 1) % every == 0 or k + 1 == n_steps:
            record((k + 1) * step, y)
    cols = ["t", *names, *(f"{c}_dot" for c in names), *cnames,
            *(f"{c}_dot" for c in cnames), *(f"lambda_{c}" for c in cnames)]
    df = pd.DataFrame(rows, columns=cols)
    df.attrs.update(engine=ENGINE, dt=step, steps=n_steps, max_cond_M=max_cond, max_abs_q_ddot=max_acc,
                    phi_scale=dict(zip(cnames, phi_scale.tolist())),
                    wall_time_s=time.perf_counter() - start)
    return df


def programmed_run(scenario, t_end: float, dt: float, output_dt: float,
                   pin_system=None, q0=None, q_dot0=None) -> pd.DataFrame:
    """The scenario's programmed run in Pinocchio, RK4 at gpme's step and stage times.

    t_end, dt, output_dt : s (output_dt a whole number of steps; see rk4_step_plan)
    pin_system           : a PinocchioSystem to use instead of from_gpme(scenario.model)
                           (tests perturb it)
    q0, q_dot0           : (n,) start (default the scenario's)
    Returns t, every coordinate and <name>_dot, the constraint values Phi by name and
    <name>_dot, lambda_<name>; attrs: dt, steps, max_cond_M (largest cond_2 of crba's M
    at the recorded states), max_abs_q_ddot (largest |q_ddot| entry there), phi_scale {name: max_t sum_j |A_kj| (|q_j| + 1), crosscheck.run_gates.phi_term_scale}, wall_time_s.
    """
    ps = pin_system or from_gpme(scenario.model)
    return _run(scenario, t_end, dt, output_dt, ps, True,
                scenario.q0 if q0 is None else q0, scenario.q_dot0 if q_dot0 is None else q_dot0)


def free_run(scenario, t_end: float, dt: float, output_dt: float, pin_system=None,
             model=None) -> pd.DataFrame:
    """The scenario's model without constraints (drives on), RK4 with pin.aba; columns t,
    coordinates and <name>_dot.  model: a variant of scenario.model to run instead (the
    crane's holding springs)."""
    if model is not None:
        scenario = _with_model(scenario, model)
    ps = pin_system or from_gpme(scenario.model)
    return _run(scenario, t_end, dt, output_dt, ps, False, scenario.q0, scenario.q_dot0)


def _with_model(scenario, model):
    return replace(scenario, model=model, constraints=(), system=ProgrammedMotion(model, ()))


def kkt_residual(scenario, t: float, q, q_dot, pin_system=None):
    """(max |a_fd - a_kkt|, max |lambda_fd - lambda_kkt|, cond(M), acceleration scale,
    multiplier scale) at
    one state: pin.forwardDynamics against the KKT system [M -A^T; A 0] [a; lambda] =
    [tau - b; -gamma] solved with numpy from Pinocchio's own crba M and rnea b.  Agreement
    to round-off confirms the sign convention used above."""
    ps = pin_system or from_gpme(scenario.model)
    stage = _Stage(scenario, ps)
    q, q_dot = np.asarray(q, float), np.asarray(q_dot, float)
    a_fd, phi, phi_dot, lam_fd, a = stage(t, q, q_dot)
    kappa = evaluate_reference(stage.refs, t, q, q_dot, stage.point_state)[3]
    gamma = kappa + 2.0 * stage.alpha * phi_dot + stage.beta ** 2 * phi
    data = ps.model.createData()
    m = np.array(pin.crba(ps.model, data, q))
    m = np.triu(m) + np.triu(m, 1).T
    b = np.array(pin.rnea(ps.model, data, q, q_dot, np.zeros_like(q)))
    tau = ps.applied_forces(q, q_dot, scenario.model.drive_forces(t))
    n, k = len(q), len(phi)
    kkt = np.block([[m, -a.T], [a, np.zeros((k, k))]])
    sol = np.linalg.solve(kkt, np.concatenate([tau - b, -gamma]))
    # scales: the accelerations and multipliers can cancel to ~0 (a joint the task holds
    # still), so the errors are taken relative to the size of the terms they come from: the
    # free acceleration M^-1 (tau - b) and the multipliers that would hold the system static
    free = np.linalg.solve(m, tau - b)
    static = np.linalg.lstsq(a.T, -(tau - b), rcond=None)[0] if k else np.zeros(0)
    a_scale = max(float(np.abs(sol[:n]).max()), float(np.abs(free).max()))
    l_scale = max(float(np.abs(sol[n:]).max(initial=0.0)), float(np.abs(static).max(initial=0.0)))
    return (float(np.abs(a_fd - sol[:n]).max()), float(np.abs(lam_fd - sol[n:]).max(initial=0.0)),
            float(np.linalg.cond(m)), a_scale, l_scale)


def run_t_end(scenario, quick: bool) -> float:
    """s, run length of the section: the scenario's quick length capped at QUICK_T_END for
    CI, else its full length capped at run_gates.FULL_RUN_T_END."""
    return min(scenario.quick_t_end, QUICK_T_END) if quick else \
        min(scenario.t_end, run_gates.FULL_RUN_T_END)


def run_step(scenario) -> float:
    """s, the scenario's RK4 step (gpme_io.runs.resolved_step: the one gpme's own run of
    the scenario takes)."""
    return resolved_step(scenario)


def exact_columns(scenario):
    names = list(scenario.model.coordinate_names)
    cons = list(scenario.system.constraint_names)
    return names + [f"{c}_dot" for c in names] + cons + [f"lambda_{c}" for c in cons]


def run_section(scenario, quick: bool, log=None, refined=None, pin_system=None) -> list:
    """Rows (crosscheck.compare dicts) of the exact programmed run of ``scenario`` in
    Pinocchio against gpme, gated by gpme's Richardson error (crosscheck.run_gates), the
    observed-order row, and the sign check of forwardDynamics against a KKT solve at the
    start.  refined: gpme's RefinedRuns when already computed (same t_end, dt, output_dt)."""
    log = log or (lambda msg: None)
    t_end, dt = run_t_end(scenario, quick), run_step(scenario)
    skip = run_gates.over_budget(t_end, dt) if refined is None else None
    if skip:
        log(f"{EXACT} {scenario.name}: {skip}")
        return [compare(ENGINE, scenario.name, f"{EXACT}: not run", f"{t_end:g} s, RK4 dt = "
                        f"{dt:.3g} s", [0.0], [0.0], Tolerance(np.inf, 0.0, f"information: {skip}"),
                        ["-"])]
    spacing = compared_output_dt(t_end, dt)
    if refined is None:
        refined = run_gates.refined_gpme_runs(scenario.system, scenario.q0, scenario.q_dot0,
                                              t_end, dt, spacing)
    df = programmed_run(scenario, t_end, refined.dt, spacing, pin_system)
    case = f"{EXACT}, {t_end:g} s, RK4 dt = {refined.dt:g} s"
    rows = run_gates.run_rows(ENGINE, scenario, refined, df, exact_columns(scenario), EXACT, case)
    rows.append(kkt_row(scenario, pin_system))
    log(f"{EXACT} {scenario.name}: pinocchio {df.attrs['wall_time_s']:.1f} s")
    return rows


def kkt_row(scenario, pin_system=None) -> dict:
    """Row: pin.forwardDynamics against our KKT solve with crba's M at the scenario's start."""
    da, dl, cond, a_max, l_max = kkt_residual(scenario, 0.0, scenario.q0, scenario.q_dot0,
                                              pin_system)
    rel = 8.0 * run_gates.EPS * cond
    tol = Tolerance(rel, 0.0,
                    "two solves of the same KKT system (Pinocchio's forwardDynamics vs numpy on "
                    f"crba's M): forward error ~eps cond(M) each, x2 engines x4 margin = 8 eps "
                    f"cond(M) = {rel:.1e}, relative to max(|q_ddot|, |M^-1 (tau - b)|) and max(|lambda|, "
                    "|static multipliers|); a sign slip "
                    "would be O(1)")
    return compare(ENGINE, scenario.name, "forwardDynamics sign convention vs KKT solve "
                   "(relative)", "t = 0, scenario start",
                   [da / max(a_max, 1e-300), dl / max(l_max, 1e-300)], [0.0, 0.0], tol,
                   ["q_ddot", "lambda"])

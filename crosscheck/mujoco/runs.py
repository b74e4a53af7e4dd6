"""Whole programmed runs of a scenario realised exactly in MuJoCo.

The scenario's model is exported with crosscheck.mujoco.mjcf.mjcf_text (no auxiliary
mechanism; frames are sites) and integrated by MuJoCo's own RK4 (option integrator RK4,
timestep dt).  MuJoCo calls ``mjcb_control`` inside every RK4 stage with that stage's
time and state, after its position and velocity stages (M factorised, qfrc_bias,
qfrc_passive, site poses and cdof_dot ready) and before it forms qacc.  There the
constraint multipliers are computed from MuJoCo's own quantities:

    drive     ctrl = drive(t), qfrc_actuator by mj_fwdActuation (gear, transmission)
    f         = qfrc_passive - qfrc_bias + qfrc_actuator
    J, Jdot   mj_jacSite, mj_jacDot at the site;  v = J qvel,  drift = Jdot qvel
    Phi, Phi_dot, A, kappa   crosscheck.constraint_reference at (p, v, J, drift)
    lambda    = (A M^-1 A^T)^-1 (rhs_c - A M^-1 f),  rhs_c = -kappa - 2 alpha Phi_dot
                - beta^2 Phi,  M^-1 applied by mj_solveM (MuJoCo's L^T D L factor)
    qfrc_applied = A^T lambda

so MuJoCo's qacc = M^-1 (f + A^T lambda) satisfies A qacc = rhs_c exactly: gpme's
Baumgarte-stabilised programmed motion, M q_ddot = h + Q + A^T lambda.  With
``per_stage=False`` the constraint forces are computed once per step at its start and
frozen over the stages (the drive still per stage), which must be worse.

No gpme constraint, kinematics or dynamics code is called here.
"""
import time
from dataclasses import replace

import mujoco
import numpy as np
import pandas as pd

from gpme_core.errors import SimulationError
from gpme_core.gpme import ProgrammedMotion

from ..run_gates import phi_term_scale
from ..constraint_reference import (evaluate_reference, reference_constraints,
                                   reference_frame_names)
from .mjcf import mjcf_text
from .sim import _unstable, chain_map, set_state


def load(model, dt: float):
    """MjModel of ``model`` exported without mechanism, RK4 at timestep dt (s)."""
    return mujoco.MjModel.from_xml_string(mjcf_text(model, dt))


class _ConstraintForces:
    """Computes lambda and sets qfrc_applied = A^T lambda at one (stage) state."""

    def __init__(self, scenario, mj_model):
        model = scenario.model
        self.mj = mj_model
        self.cmap = chain_map(mj_model, model)
        self.refs = reference_constraints(scenario.constraints, model.coordinate_names)
        self.alpha, self.beta = scenario.system.alpha, scenario.system.beta
        nv = mj_model.nv
        self.sites = {f: mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_SITE, f)
                      for f in reference_frame_names(self.refs)}
        missing = [f for f, s in self.sites.items() if s < 0]
        if missing:
            raise SimulationError(f"MuJoCo model has no sites {missing}")
        self.jacp = np.zeros((3, nv))
        self.jdot = np.zeros((3, nv))
        m = len(self.refs)
        self.rhs = np.zeros((m + 1, nv))
        self.sol = np.zeros((m + 1, nv))
        self.last = (np.zeros(m), np.zeros(m), np.zeros(m), np.zeros((m, model.n_coordinates)))

    def point_state(self, d):
        def state(frame):
            sid = self.sites[frame]
            mujoco.mj_jacSite(self.mj, d, self.jacp, None, sid)
            mujoco.mj_jacDot(self.mj, d, self.jdot, None, d.site_xpos[sid],
                             int(self.mj.site_bodyid[sid]))
            v = self.jacp @ d.qvel
            drift = self.jdot @ d.qvel
            return (d.site_xpos[sid].copy(), v, self.jacp[:, self.cmap.dof].copy(), drift)
        return state

    def apply(self, d):
        """Set d.qfrc_applied from the state and forces in ``d``; keeps (Phi, Phi_dot,
        lambda, A) in self.last."""
        dof = self.cmap.dof
        if not self.refs:
            d.qfrc_applied[:] = 0.0
            return
        q, v = d.qpos[self.cmap.qpos], d.qvel[dof]
        phi, phi_dot, a, kappa = evaluate_reference(self.refs, d.time, q, v, self.point_state(d))
        m = len(phi)
        rhs_c = -kappa - 2.0 * self.alpha * phi_dot - self.beta ** 2 * phi
        self.rhs[:] = 0.0
        self.rhs[:m, dof] = a
        self.rhs[m] = d.qfrc_passive - d.qfrc_bias + d.qfrc_actuator
        mujoco.mj_solveM(self.mj, d, self.sol, self.rhs)       # rows: M^-1 A^T, M^-1 f
        minv_at = self.sol[:m, dof].T                            # (n, m)
        s = a @ minv_at
        lam = np.linalg.solve(s, rhs_c - a @ self.sol[m, dof])
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[dof] = a.T @ lam
        self.last = (phi, phi_dot, lam, a)


def _drive(model, mj_model):
    act = [mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"drive_{d.joint}")
           for d in model.drives]
    funcs = [d.function for d in model.drives]

    def set_ctrl(d):
        for a, f in zip(act, funcs):
            d.ctrl[a] = f(d.time)
    return set_ctrl


def programmed_run(scenario, t_end: float, dt: float, output_dt: float, mj_model=None,
                   per_stage: bool = True, q0=None, q_dot0=None) -> pd.DataFrame:
    """The scenario's programmed run in MuJoCo, its RK4 at timestep dt, constraint forces
    set in mjcb_control at every stage (``per_stage``) or once per step.

    t_end, dt, output_dt : s; output_dt a whole number of steps, t_end of output_dt
    mj_model             : an MjModel to use instead of load(scenario.model, dt) (tests
                           perturb it); its timestep must be dt
    q0, q_dot0           : (n,) start (default the scenario's)
    Returns t, coordinates, <name>_dot, Phi by name, <name>_dot, lambda_<name>; attrs: dt,
    steps, max_cond_M (cond_2 of mj_fullM at the records), max_abs_q_ddot (of qacc),
    phi_scale {name: max_t sum_j |A_kj| (|q_j| + 1), crosscheck.run_gates.phi_term_scale}, wall_time_s, stages (callback calls).
    """
    model = scenario.model
    mj = mj_model or load(model, dt)
    if abs(mj.opt.timestep - dt) > 1e-15 * dt or mj.opt.integrator != mujoco.mjtIntegrator.mjINT_RK4:
        raise SimulationError(f"MuJoCo model must integrate with RK4 at timestep {dt!r} s")
    steps = int(round(t_end / dt))
    every = int(round(output_dt / dt))
    if steps < 1 or every < 1 or abs(every * dt - output_dt) > 1e-9 * output_dt or steps % every:
        raise SimulationError(f"t_end = {t_end!r} s must be a whole number of output_dt = "
                              f"{output_dt!r} s, itself a whole number of steps {dt!r} s")
    data = mujoco.MjData(mj)
    forces = _ConstraintForces(scenario, mj)
    set_ctrl = _drive(model, mj)
    cmap = forces.cmap
    names = list(model.coordinate_names)
    cnames = [r.name for r in forces.refs]
    counter = {"stages": 0}

    def control(m, d):
        set_ctrl(d)
        if per_stage:
            counter["stages"] += 1
            mujoco.mj_fwdActuation(m, d)       # qfrc_actuator of the ctrl just set
            forces.apply(d)

    dense = np.zeros((mj.nv, mj.nv))
    rows, max_cond, max_acc = [], 0.0, 0.0
    phi_scale = np.zeros(len(cnames))

    def record():
        nonlocal max_cond, max_acc
        if not per_stage:
            mujoco.mj_fwdActuation(mj, data)
            forces.apply(data)
            mujoco.mj_forward(mj, data)
        phi, phi_dot, lam, a = forces.last
        q, v = data.qpos[cmap.qpos], data.qvel[cmap.dof]
        mujoco.mj_fullM(mj, data, dense)
        max_cond = max(max_cond, float(np.linalg.cond(dense)))
        max_acc = max(max_acc, float(np.abs(data.qacc[cmap.dof]).max()))
        if len(cnames):
            phi_scale[:] = np.maximum(phi_scale, phi_term_scale(a, q))
        rows.append([data.time, *q, *v, *phi, *phi_dot, *lam])

    set_state(mj, data, cmap, scenario.q0 if q0 is None else q0,
              scenario.q_dot0 if q_dot0 is None else q_dot0, 0.0)
    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    previous = mujoco.get_mjcb_control()
    mujoco.set_mjcb_control(control)
    start = time.perf_counter()
    try:
        mujoco.mj_forward(mj, data)
        record()
        for _ in range(steps // every):
            if per_stage:
                mujoco.mj_step(mj, data, nstep=every)
            else:
                for _ in range(every):
                    mujoco.mj_forward(mj, data)
                    mujoco.mj_fwdActuation(mj, data)
                    forces.apply(data)                  # frozen over this step's stages
                    mujoco.mj_step(mj, data)
            if not np.all(np.isfinite(data.qpos)) or _unstable(data):
                raise SimulationError(f"MuJoCo run of {scenario.name} diverged before t = "
                                      f"{data.time:.6g} s (dt = {dt:g} s)")
            mujoco.mj_forward(mj, data)        # derived quantities of the new state
            record()
    finally:
        mujoco.set_mjcb_control(previous)
    cols = ["t", *names, *(f"{c}_dot" for c in names), *cnames,
            *(f"{c}_dot" for c in cnames), *(f"lambda_{c}" for c in cnames)]
    df = pd.DataFrame(rows, columns=cols)
    df.attrs.update(engine="mujoco", dt=dt, steps=steps, max_cond_M=max_cond,
                    max_abs_q_ddot=max_acc, phi_scale=dict(zip(cnames, phi_scale.tolist())),
                    wall_time_s=time.perf_counter() - start, stages=counter["stages"])
    return df


def free_run(scenario, t_end: float, dt: float, output_dt: float, model=None,
             mj_model=None) -> pd.DataFrame:
    """The scenario's model (or the variant ``model``, e.g. the crane with holding
    springs) without constraints, drives on, MuJoCo's RK4 at dt; same columns and attrs
    as :func:`programmed_run` without the constraint columns."""
    model = model or scenario.model
    free = replace(scenario, model=model, constraints=(), system=ProgrammedMotion(model, ()))
    return programmed_run(free, t_end, dt, output_dt, mj_model or load(model, dt))

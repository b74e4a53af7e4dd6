"""The same constrained-acceleration evaluation and the same 10 s run in three engines.

* gpme      : the compiled right-hand side (gpme_core.compiled.CompiledSystem.accelerator:
              kinematics, trace-form terms, constraint rows and the reduced solve in one
              compiled call) and the Python path ProgrammedMotion.solve (the reference);
              runs through gpme_core.integrate.simulate
* pinocchio : Pinocchio called from Python: forward kinematics with a = 0, the frame
              Jacobian and classical acceleration of E, the constraint rows formed from
              them with gpme's constraint functions (phi, grad, Hessian: plain numpy on
              3-vectors), then pin.forwardDynamics(q, v, tau, A, gamma) (KKT, internally
              CRBA + nonlinear effects + Cholesky), same Baumgarte terms
* mujoco    : mj_forward / mj_step on the MJCF with the auxiliary constraint mechanism
"""
import time

import mujoco
import numpy as np
import pandas as pd
import pinocchio as pin

from crosscheck.mujoco import mechanism as mech
from crosscheck.mujoco.mjcf import mjcf_text
from crosscheck.mujoco.sim import simulate_mujoco, set_state, chain_map
from crosscheck.pinocchio.model import from_gpme
from gpme_core.errors import SimulationError
from gpme_core.integrate import rk4_step_plan

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class PinocchioConstrained:
    """q_ddot(t, q, q_dot) of a gpme ProgrammedMotion computed with Pinocchio."""

    def __init__(self, system):
        self.system = system
        self.ps = from_gpme(system.model)
        self.pm = self.ps.model
        self.data = self.pm.createData()
        frames = {b.spec.frame for b in system.bound}
        (frame,) = frames
        self.fid = self.ps.frames[frame]
        self.specs = [b.spec for b in system.bound]
        self.zero = np.zeros(self.pm.nv)
        self.m = len(self.specs)

    def accelerations(self, t, q, qd):
        pm, data, fid = self.pm, self.data, self.fid
        pin.forwardKinematics(pm, data, q, qd, self.zero)
        pin.updateFramePlacement(pm, data, fid)
        p = data.oMf[fid].translation
        v = pin.getFrameVelocity(pm, data, fid, LWA).linear
        drift = pin.getFrameClassicalAcceleration(pm, data, fid, LWA).linear
        jac = pin.computeFrameJacobian(pm, data, q, fid, LWA)[:3]
        a = np.empty((self.m, pm.nv))
        gamma = np.empty(self.m)
        s = self.system
        for k, spec in enumerate(self.specs):
            f, grad, hess, f_t, grad_t, f_tt = spec.local_terms(p, t)
            a[k] = grad @ jac
            phi_dot = grad @ v + f_t
            kappa = grad @ drift + v @ hess @ v + 2.0 * grad_t @ v + f_tt
            gamma[k] = kappa + 2.0 * s.alpha * phi_dot + s.beta ** 2 * f
        tau = self.ps.applied_forces(q, qd, s.model.drive_forces(t))
        return pin.forwardDynamics(pm, data, q, qd, tau, a, gamma)

    def mass_matrix(self, q):
        """(n, n) kg, kg m, kg m^2: the joint-space mass matrix from Pinocchio's CRBA (which
        fills the upper triangle only; mirrored here)."""
        upper = np.triu(pin.crba(self.pm, self.data, np.asarray(q, dtype=float)))
        return upper + np.triu(upper, 1).T


def rk4_run(accelerations, t_end, q0, qd0, dt, output_dt=1e-2):
    """Classical RK4 of q_ddot = accelerations(t, q, q_dot).

    Returns (times (k,), q history (k, n), wall time s) recorded every output_dt."""
    h, every = rk4_step_plan(t_end, dt, output_dt)
    n_steps = int(round(t_end / h))
    q, qd = np.array(q0, float), np.array(qd0, float)
    times, history = [0.0], [q.copy()]
    start = time.perf_counter()
    for k in range(n_steps):
        t = k * h
        a1 = accelerations(t, q, qd)
        q2, v2 = q + 0.5 * h * qd, qd + 0.5 * h * a1
        a2 = accelerations(t + 0.5 * h, q2, v2)
        q3, v3 = q + 0.5 * h * v2, qd + 0.5 * h * a2
        a3 = accelerations(t + 0.5 * h, q3, v3)
        q4, v4 = q + h * v3, qd + h * a3
        a4 = accelerations(t + h, q4, v4)
        q = q + h / 6.0 * (qd + 2 * v2 + 2 * v3 + v4)
        qd = qd + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
        if not np.all(np.isfinite(qd)):
            raise SimulationError(f"RK4 run diverged at t = {t + h:.6g} s (dt = {h:g} s)")
        if (k + 1) % every == 0:
            times.append((k + 1) * h)
            history.append(q.copy())
    return np.array(times), np.array(history), time.perf_counter() - start


def pinocchio_run(system, t_end, q0, qd0, dt, output_dt=1e-2):
    """RK4 run of :class:`PinocchioConstrained` (Python loop).

    Returns a DataFrame with columns t (s) and every coordinate of system.model (SI,
    recorded every output_dt), attrs["wall_time_s"] the loop's wall time (s)."""
    accelerations = PinocchioConstrained(system).accelerations
    times, qs, wall = rk4_run(accelerations, t_end, q0, qd0, dt, output_dt)
    run = pd.DataFrame(qs, columns=list(system.model.coordinate_names))
    run.insert(0, "t", times)
    run.attrs["wall_time_s"] = wall
    return run


def mujoco_programmed(system, dt, timeconst=None):
    """(MjModel, MjData, programme) of the crane with the auxiliary mechanism."""
    specs = system.constraint_specs
    settings = mech.MechanismSettings(timeconst=timeconst or dt)
    mj = mujoco.MjModel.from_xml_string(mjcf_text(system.model, dt, specs, settings))
    return mj, mujoco.MjData(mj), mech.read_programme(system.model, specs)


def mujoco_forward_setup(system, q, qd, dt=1e-4):
    """(callable doing one mj_forward, MjModel) at the consistent state (q, qd)."""
    mj, data, programme = mujoco_programmed(system, dt)
    p_e, v_e = mech.frame_motion(system.model, programme.frame, q, qd)
    aux = mech.auxiliary_state(programme, p_e, v_e, 0.0)
    set_state(mj, data, chain_map(mj, system.model), q, qd, 0.0, aux)
    return (lambda: mujoco.mj_forward(mj, data)), mj


def mujoco_run(system, t_end, q0, qd0, dt, output_dt):
    """A MuJoCo RK4 run of the programmed crane; returns its history DataFrame."""
    mj, _, programme = mujoco_programmed(system, dt)
    p_e, v_e = mech.frame_motion(system.model, programme.frame, q0, qd0)
    aux = mech.auxiliary_state(programme, p_e, v_e, 0.0)
    return simulate_mujoco(mj, system.model, t_end, q0, qd0, output_dt, programme=programme,
                           aux=aux)

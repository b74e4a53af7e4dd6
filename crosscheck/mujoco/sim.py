"""Run an exported MJCF in MuJoCo with the gpme drive applied at every RK4 stage, and
record the chain coordinates, the programmed-constraint values, the crane's energies and
the violations of MuJoCo's auxiliary equality constraints as a tidy DataFrame.

The drive torque is set in ``mjcb_control``, which MuJoCo calls inside every stage of
its RK4 step with ``d.time`` at that stage, so the drive is sampled exactly where gpme's
RK4 samples it (setting ctrl once per step at the step start costs ~3e-3 rad in psi2).
"""
import time
from dataclasses import dataclass

import mujoco
import numpy as np
import pandas as pd

from gpme_core.errors import ModelError, SimulationError

from . import mechanism as mech
from .mjcf import body_groups


@dataclass(frozen=True)
class ChainMap:
    """Where gpme's coordinates live in a MuJoCo model built by crosscheck.mujoco.mjcf.

    qpos (n,), dof (n,) : addresses of the chain joints, ordered as the gpme coordinates
    bodies (b,)         : MuJoCo body ids of the chain (auxiliary bodies excluded)
    aux_qpos, aux_dof   : addresses of the auxiliary joints (empty without mechanism)
    """

    qpos: np.ndarray
    dof: np.ndarray
    bodies: np.ndarray
    aux_qpos: np.ndarray
    aux_dof: np.ndarray


def chain_map(mj_model, model):
    """:class:`ChainMap`; ModelError if a gpme coordinate has no MuJoCo joint."""
    missing = [nm for nm in model.coordinate_names
               if mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, nm) < 0]
    if missing:
        raise ModelError(f"MuJoCo model has no joints named {missing}")
    jid = [mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, nm) for nm in model.coordinate_names]
    aux = [mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, nm) for nm in mech.AUX_JOINTS]
    aux = [a for a in aux if a >= 0]
    bodies = [mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_BODY, model.links[g[-1]].name)
              for g in body_groups(model)]
    return ChainMap(mj_model.jnt_qposadr[jid].copy(), mj_model.jnt_dofadr[jid].copy(),
                    np.array(bodies), mj_model.jnt_qposadr[aux].copy(),
                    mj_model.jnt_dofadr[aux].copy())


def drive_callback(model, mj_model):
    """mjcb_control function setting ctrl = gpme drive forces at d.time."""
    act = [mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"drive_{d.joint}")
           for d in model.drives]
    funcs = [d.function for d in model.drives]

    def control(m, d):
        t = d.time
        for a, f in zip(act, funcs):
            d.ctrl[a] = f(t)
    return control


def set_state(mj_model, data, cmap, q, q_dot, t=0.0, aux=None):
    """Put gpme (q, q_dot) (n,) and optional auxiliary (qpos, qvel) into ``data``."""
    mujoco.mj_resetData(mj_model, data)
    data.time = t
    data.qpos[cmap.qpos] = q
    data.qvel[cmap.dof] = q_dot
    if aux is not None:
        data.qpos[cmap.aux_qpos] = aux[0]
        data.qvel[cmap.aux_dof] = aux[1]
    mujoco.mj_forward(mj_model, data)


def crane_energies(mj_model, data, cmap, dense):
    """(E_kin, E_pot) J of the chain only: 1/2 v^T M v over the chain dofs, and gravity
    (-m g . x_com, zero at the world origin as gpme's) plus spring energy of the chain."""
    mujoco.mj_fullM(mj_model, data, dense)
    v = data.qvel[cmap.dof]
    e_kin = 0.5 * float(v @ dense[np.ix_(cmap.dof, cmap.dof)] @ v)
    g = mj_model.opt.gravity
    e_grav = -float(np.sum(mj_model.body_mass[cmap.bodies] * (data.xipos[cmap.bodies] @ g)))
    jid = mj_model.dof_jntid[cmap.dof]
    dq = data.qpos[cmap.qpos] - mj_model.qpos_spring[cmap.qpos]
    e_spring = 0.5 * float(np.sum(mj_model.jnt_stiffness[jid] * dq * dq))
    return e_kin, e_grav + e_spring


def equality_violations(mj_model, data):
    """{name: violation} of every equality (m: norm of a connect's or weld's site gap;
    tendon: length minus its held length; NaN for another kind, which the harness does not
    write)."""
    out = {}
    for e in range(mj_model.neq):
        name = mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_EQUALITY, e)
        out[name] = np.nan
        if int(mj_model.eq_type[e]) in (int(mujoco.mjtEq.mjEQ_CONNECT),
                                        int(mujoco.mjtEq.mjEQ_WELD)):
            s1, s2 = mj_model.eq_obj1id[e], mj_model.eq_obj2id[e]
            out[name] = float(np.linalg.norm(data.site_xpos[s1] - data.site_xpos[s2]))
        elif mj_model.eq_type[e] == mujoco.mjtEq.mjEQ_TENDON:
            tid = mj_model.eq_obj1id[e]
            out[name] = float(data.ten_length[tid] - mj_model.tendon_length0[tid]
                              - mj_model.eq_data[e, 0])
    return out


_INSTABILITY_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL,
                         mujoco.mjtWarning.mjWARN_BADQPOS)


def _unstable(data):
    return any(data.warning[int(w)].number > 0 for w in _INSTABILITY_WARNINGS)


def simulate_mujoco(mj_model, model, t_end, q0, q_dot0, output_dt=1e-3, programme=None,
                    aux=None, t0=0.0):
    """Integrate ``mj_model`` (its own timestep and integrator) from t0 for t_end seconds.

    model       : the gpme Model the MJCF was written from (names, drives)
    q0, q_dot0  : (n,) gpme initial state; aux: optional auxiliary (qpos, qvel) (5,) each
    programme   : optional mujoco_mechanism.EllipticProgramme: record its Phi values
                  evaluated on MuJoCo's own end-effector site
    Returns a DataFrame: t, coordinates, <coordinate>_dot, Phi columns (when programme),
    E_kin, E_pot (chain only), viol_<equality>; attrs: wall_time_s, dt, steps.
    """
    dt = mj_model.opt.timestep
    steps = int(round(t_end / dt))
    every = max(1, int(round(output_dt / dt)))
    if steps < 1 or abs(steps * dt - t_end) > 1e-9 * max(t_end, 1.0) or steps % every:
        raise ModelError(f"t_end = {t_end!r} s must be a whole number of output_dt = {output_dt!r} "
                         f"s, itself a whole number of MuJoCo timesteps {dt!r} s")
    data = mujoco.MjData(mj_model)
    cmap = chain_map(mj_model, model)
    dense = np.zeros((mj_model.nv, mj_model.nv))
    names = list(model.coordinate_names)
    site_e = -1
    if programme is not None:
        site_e = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_SITE, programme.frame)
    rows = []

    def record():
        q, v = data.qpos[cmap.qpos], data.qvel[cmap.dof]
        row = [data.time, *q, *v]
        if site_e >= 0:
            p = data.site_xpos[site_e]
            xc, yc = programme.center
            row += [((p[0] - xc) / programme.a) ** 2 + ((p[1] - yc) / programme.b) ** 2 - 1.0,
                    p[2] - programme.height.value(data.time)]
        row += [*crane_energies(mj_model, data, cmap, dense), *equality_violations(mj_model, data).values()]
        rows.append(row)

    control = drive_callback(model, mj_model)
    set_state(mj_model, data, cmap, q0, q_dot0, t0, aux)
    control(mj_model, data)
    # a diverged run must fail here, not restart from qpos0 as MuJoCo's autoreset would
    mj_model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    previous = mujoco.get_mjcb_control()
    mujoco.set_mjcb_control(control)
    start = time.perf_counter()
    try:
        mujoco.mj_forward(mj_model, data)
        record()
        for _ in range(steps // every):
            mujoco.mj_step(mj_model, data, nstep=every)
            if not np.all(np.isfinite(data.qpos)) or _unstable(data):
                raise SimulationError(f"MuJoCo run of {model.name} diverged before t = "
                                      f"{data.time:.6g} s (dt = {dt:g} s)")
            # data after mj_step holds the previous stage's derived quantities: refresh
            mujoco.mj_forward(mj_model, data)
            record()
    finally:
        mujoco.set_mjcb_control(previous)
    wall = time.perf_counter() - start
    cols = ["t", *names, *(f"{nm}_dot" for nm in names)]
    if site_e >= 0:
        cols += list(programme.names)
    eq_names = [mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_EQUALITY, e) for e in range(mj_model.neq)]
    cols += ["E_kin", "E_pot", *(f"viol_{e}" for e in eq_names)]
    df = pd.DataFrame(rows, columns=cols)
    df.attrs.update(wall_time_s=wall, dt=dt, steps=steps, model=mj_model.names[:0].decode() or model.name)
    return df

"""Comparison 1: the terms of the equations of motion, gpme against MuJoCo, at sampled
states, on the exported MJCF without the auxiliary mechanism.

Sign conventions (docs/crosscheck-mujoco.md): gpme writes M q_ddot = h + Q with
Q = -(g + d + f) + t; MuJoCo writes M q_ddot = qfrc_passive + qfrc_actuator - qfrc_bias.
Hence
    mj_fullM       == M
    qfrc_bias      == -h + g        (velocity-product terms and gravity)
    qfrc_passive   == -(f + d)      (springs K (q - q_ref) and dampers D q_dot)
    qfrc_actuator  == t(t)          (drive through the motor actuator, gear 1)
"""
import mujoco
import numpy as np

from gpme_core import dynamics as dyn

from ..compare import Tolerance, compare
from ..sampling import state_ranges
from .sim import chain_map, drive_callback

ENGINE = "mujoco"
# Both engines evaluate the same sums of products of O(1) numbers in a different order
# (MuJoCo: composite rigid body and recursive Newton-Euler; gpme: traces of 4x4
# products); float64 round-off is 2.2e-16 per operation and the sums have at most a few
# hundred terms, so 1e-12 relative to the largest entry leaves room for the growth while
# any modelling difference (a wrong inertia, axis or sign: >= 1e-6 relative) fails.
ROUND_OFF = Tolerance(1e-13, 1e-12, "round-off: same sums in a different order "
                      "(eps 2.2e-16 x a few hundred terms, with margin)")


def sample_states(model, n_samples, seed, flexible=None, q0=None, t_max=6.0):
    """[(t s, q (n,), q_dot (n,))] drawn with np.random.default_rng(seed) by the rule of
    crosscheck.sampling.state_ranges: coordinates within their joint limits (open ends:
    revolute q0 +- pi rad, prismatic q0 +- 0.2 m; RFEM angles +- 0.02 rad), rates +-1 rad/s
    or m/s (RFEM +-2 rad/s), times in [0, t_max] s (default 6 s: the crane's drive ramp).

    flexible : RFEM coordinate names; None: those of model.flexible_links
    q0       : (n,) centre of the open ranges; None: zeros
    """
    lo, hi, rate = state_ranges(model, flexible, q0)
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(0.0, t_max)), rng.uniform(lo, hi), rng.uniform(-rate, rate))
            for _ in range(n_samples)]


def term_rows(model, mj_model, states, case_prefix="state", label=None, tolerance=ROUND_OFF):
    """Tidy rows comparing M, bias, passive and actuator forces at every state.

    model   : gpme Model; mj_model: its MJCF in MuJoCo (coordinates matched by name,
              crosscheck.mujoco.sim.chain_map); states: [(t s, q (n,), q_dot (n,))]
    label   : the rows' model column (default model.name)
    tolerance: Tolerance of all four quantities (default ROUND_OFF; a model file's
              override with its reason)
    """
    label = model.name if label is None else label
    data = mujoco.MjData(mj_model)
    cmap = chain_map(mj_model, model)
    dense = np.zeros((mj_model.nv, mj_model.nv))
    names = list(model.coordinate_names)
    control = drive_callback(model, mj_model)
    rows = []
    for k, (t, q, q_dot) in enumerate(states):
        mujoco.mj_resetData(mj_model, data)
        data.time = t
        data.qpos[cmap.qpos] = q
        data.qvel[cmap.dof] = q_dot
        control(mj_model, data)
        mujoco.mj_forward(mj_model, data)
        mujoco.mj_fullM(mj_model, data, dense)
        terms = dyn.dynamics_terms(model, t, q, q_dot)
        case = f"{case_prefix} {k}"
        sel = np.ix_(cmap.dof, cmap.dof)
        rows.append(compare(ENGINE, label, "mass matrix M [kg, kg m, kg m^2]", case,
                            terms.M, dense[sel], tolerance, (names, names)))
        rows.append(compare(ENGINE, label, "bias -h + g vs qfrc_bias [N, N m]", case,
                            -terms.h + terms.g, data.qfrc_bias[cmap.dof], tolerance, names))
        rows.append(compare(ENGINE, label, "passive -(f + d) vs qfrc_passive [N, N m]", case,
                            -(terms.f + terms.d), data.qfrc_passive[cmap.dof], tolerance, names))
        rows.append(compare(ENGINE, label, "drive t vs qfrc_actuator [N, N m]", case,
                            terms.t, data.qfrc_actuator[cmap.dof], tolerance, names))
    return rows

"""Runs of the continuum model (Exudyn) and the same quantities from a gpme RFEM run.

Quantities that mean the same in both models (columns of the returned frames):

* ``<joint>``: the coordinate of each joint that is not an sde (rad or m); in the continuum
  measured from the two joint frames (revolute: atan2 of the relative rotation about the
  joint's local z, unwrapped; prismatic: the relative displacement along it);
* ``tip_x|y|z_<beam>``: the beam tip's position in the world frame, m;
* ``defl_x|y|z_<beam>``: the elastic tip deflection, the tip position in the beam's root
  frame B (x along the undeformed beam) minus (L, 0, 0), m: where the tip is relative to
  where a rigid link would put it;
* ``rot_x|y|z_<beam>``: the elastic tip rotation, the rotation vector of R_B^T R_tip, rad;
* ``lambda_<constraint>``: the multipliers of the programmed constraints, gpme's sign
  (M q_ddot = h + Q + A^T lambda); NaN at t = 0, where Exudyn's initial accelerations
  ignore constraints given by user functions, so its first multipliers are not a solution
  (they settle within a few steps: measured on the rigid crane at dt = 1e-4 s, 5e-5 of
  gpme's at the first 0.01 s sample).

Exudyn integrates with its implicit generalized-alpha solver (index 3, constant step,
spectral radius SPECTRAL_RADIUS: a little numerical damping of the unresolved
high-frequency axial and shear modes, whose effect on the resolved motion is measured by
halving the step, crosscheck.continuum.study).
"""

import exudyn as exu
import numpy as np
import pandas as pd

from gpme_core import kinematics
from gpme_core.errors import SimulationError

from ..exudyn.model import quiet_settings, solve_implicit
from .layout import continuum_layout
from .section import continuum_section
from .system import build_system

ENGINE = "exudyn-continuum"
# generalized-alpha's spectral radius at infinity: 1 is the trapezoidal rule, which lets
# the stiff axial modes of a spinning beam grow without bound (measured on the spin-up
# beam at dt = 0.01 s: Newton divergence after 13 s); 0.8 damps them within a few steps
# and changes the resolved modes by O((omega h)^3)
SPECTRAL_RADIUS = 0.8
NEWTON_RELATIVE_TOL = 1e-9
# Newton's absolute goal on the residual (N, N m) sits this far above its round-off floor,
# eps x the stiffest element spring (E A or k G A times N / L, N/m) x the model's size (m):
# measured on the spin-up beam with 16 elements the floor was 1.0e-7 against the estimate
# 2.2e-16 x 4.5e7 N/m x 10 m = 1.0e-7, and Newton stalled there at a goal of 1e-7
ROUND_OFF_MARGIN = 100.0


def newton_absolute_tolerance(layout, elements, size, euler_bernoulli=False) -> float:
    """Newton's absolute residual goal (see ROUND_OFF_MARGIN) for these beams and meshes;
    size: m, the largest distance of the model from the world origin."""
    k = max([max(continuum_section(b.beam, euler_bernoulli).stiffness[:3]) * elements[b.name]
             / b.beam.length
             for b in layout.beams] or [1.0])
    return ROUND_OFF_MARGIN * float(np.finfo(float).eps) * k * max(size, 1.0)


def zero_initial_accelerations(layout) -> bool:
    """True when the run starts from zero accelerations instead of Exudyn's: when a beam end
    is clamped to a massless body (its carrying or tip link held nothing but beam).

    Exudyn's start solves M a0 = f(q0), with no stiffness in it.  A massless body at a beam
    end passes every moment reaching it (a joint spring or drive torque, the reaction of the
    links beyond) to the end node's section rotary inertia alone, a mode far beyond the
    step, so a0 is huge there and grows with the mesh.  Measured on the double pendulum (8
    elements, Euler-Bernoulli limit): its 0.25 N m elbow spring gives Euler-parameter
    accelerations of 6.3e6 /s^2 at the beam root, 30 /s^2 with the spring removed; the first
    step's predictor then throws the stiffened elements far off and Newton diverges at the
    3rd step (the TriFinger's distal spring: at the 2nd).  With a0 = 0 generalized-alpha's
    start is first order (a velocity error O(h), which the step study measures: on the
    pendulum without its spring 1.4e-4 rad in a joint at dt = 7.8e-5 s, against 3.6e-5
    with Exudyn's a0); Exudyn's own a0 is not consistent either where constraints are user
    functions (programmes, point constraints), which it ignores.  Models whose beam ends
    carry inertia keep Exudyn's a0 and generalized-alpha's order 2."""
    return any(layout.bodies[link].mass == 0.0 for b in layout.beams
               for link in (b.carrying_link, b.tip_link))


def rotation_vector(r: np.ndarray) -> np.ndarray:
    """(3,) rotation vector (axis times angle, rad) of a rotation matrix (angle < pi)."""
    c = np.clip(0.5 * (np.trace(r) - 1.0), -1.0, 1.0)
    angle = np.arccos(c)
    w = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    s = np.sin(angle)
    return w if s < 1e-12 else w * angle / s


def tip_quantities(name, length, root_pose, tip_pose) -> dict:
    """The tip columns of one beam from the world poses (4, 4) of B and of the tip frame."""
    rb = root_pose[:3, :3]
    local = rb.T @ (tip_pose[:3, 3] - root_pose[:3, 3])
    local[0] -= length
    rot = rotation_vector(rb.T @ tip_pose[:3, :3])
    out = {}
    for i, ax in enumerate("xyz"):
        out[f"tip_{ax}_{name}"] = float(tip_pose[i, 3])
        out[f"defl_{ax}_{name}"] = float(local[i])
        out[f"rot_{ax}_{name}"] = float(rot[i])
    return out


def _pose(mbs, node) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = np.asarray(mbs.GetNodeOutput(node, exu.OutputVariableType.RotationMatrix),
                           dtype=float).reshape(3, 3)
    t[:3, 3] = mbs.GetNodeOutput(node, exu.OutputVariableType.Position)
    return t


def _joint_value(model, system, k, poses_of) -> float:
    parent, origin, child, r_a, _ = system.joint_frames[k]
    t_p = np.eye(4) if parent < 0 else poses_of(parent)
    t_c = poses_of(child)
    r0 = t_p[:3, :3] @ origin[:3, :3] @ r_a
    p0 = t_p[:3, :3] @ origin[:3, 3] + t_p[:3, 3]
    r1 = t_c[:3, :3] @ r_a
    if model.joints[k].kind == "revolute":
        rel = r0.T @ r1
        return float(np.arctan2(rel[1, 0], rel[0, 0]))
    return float((r0.T @ (t_c[:3, 3] - p0))[2])


def continuum_run(model, q0, q_dot0, t_end: float, dt: float, output_dt: float, specs=(),
                  elements=8, gravity=None, spectral_radius: float = SPECTRAL_RADIUS,
                  euler_bernoulli: bool = False) -> pd.DataFrame:
    """The continuum model's run from q0, q_dot0 (sde entries ignored: the beams start
    straight), step dt (s) to t_end (s), recorded every output_dt (s, a whole number of
    steps).  Returns the columns of the module docstring plus ``t``; attrs: engine, dt,
    elements, wall_time_s, notes.  SimulationError names Exudyn's message on failure."""
    layout = continuum_layout(model)
    system = build_system(model, layout, q0, q_dot0, specs, elements, gravity, euler_bernoulli)
    mbs = system.mbs
    steps, every = int(round(t_end / dt)), int(round(output_dt / dt))
    if steps < 1 or every < 1 or abs(steps * dt - t_end) > 1e-9 * max(t_end, 1.0) or \
            abs(every * dt - output_dt) > 1e-9 * max(output_dt, 1.0):
        raise ValueError(f"t_end = {t_end!r} s and output_dt = {output_dt!r} s must be whole "
                         f"numbers of steps dt = {dt!r} s")
    joint_names = [model.joints[k].name for k in layout.joints]
    q0 = np.asarray(q0, dtype=float)
    last = {k: float(q0[k]) for k in layout.joints}
    records = {}

    def record(t):
        poses = {}

        def poses_of(link):
            if link not in poses:
                poses[link] = _pose(mbs, system.body_nodes[link])
            return poses[link]
        row = {"t": t}
        for k, name in zip(layout.joints, joint_names):
            v = _joint_value(model, system, k, poses_of)
            if model.joints[k].kind == "revolute":       # unwrap against the last sample
                v += 2.0 * np.pi * np.round((last[k] - v) / (2.0 * np.pi))
            last[k] = v
            row[name] = v
        for beam in layout.beams:
            root = poses_of(beam.carrying_link) @ beam.root_frame
            tip = _pose(mbs, system.beam_nodes[beam.name][-1])
            row.update(tip_quantities(beam.name, beam.beam.length, root, tip))
        ae = np.asarray(mbs.systemData.GetAECoordinates())
        if t == 0.0:                 # Exudyn's start ignores constraints by user functions:
            ae = np.full(ae.shape, np.nan)          # no multipliers at t = 0
        for name, (obj, axis) in system.joint_programmes.items():
            # the generic joint's AE coordinate along its free axis is the constraint torque
            # (force) on the child, gpme's lambda of q_k - f(t) itself (measured on the
            # spin-up hub: the same value, 2.0 relative apart with the other sign)
            row[f"lambda_{name}"] = float(ae[mbs.systemData.GetObjectLTGAE(obj)[axis]])
        for obj, names in system.constraint_objects:
            idx = mbs.systemData.GetObjectLTGAE(obj)
            for i, name in enumerate(names):
                row[f"lambda_{name}"] = -float(ae[idx[i]])
        records[int(round(t / output_dt))] = row

    def post_step(mbs_, t):
        k = int(round(t / dt))
        if k % every == 0 and abs(t - k * dt) < 1e-6 * dt:
            record(k * dt)
        return True

    mbs.SetPostStepUserFunction(post_step)
    mbs.Assemble()
    record(0.0)
    settings = quiet_settings(t_end, steps)
    ti = settings.timeIntegration
    ti.generalizedAlpha.spectralRadius = float(spectral_radius)
    ti.newton.relativeTolerance = NEWTON_RELATIVE_TOL
    size = max(float(np.abs(mbs.GetNodeOutput(nd, exu.OutputVariableType.Position)).max())
               for nodes in system.beam_nodes.values() for nd in nodes) if system.beam_nodes else 1.0
    ti.newton.absoluteTolerance = newton_absolute_tolerance(layout, system.elements, size,
                                                            euler_bernoulli)
    ti.adaptiveStep = False
    zero_start = zero_initial_accelerations(layout)
    ti.generalizedAlpha.computeInitialAccelerations = not zero_start
    ti.generalizedAlpha.resetAccelerations = zero_start
    # sparse LU: a beam mesh gives a banded system; the dense default grows as N^3
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    ok, message, wall, _ = solve_implicit(mbs, settings)
    if not ok or len(records) != steps // every + 1:
        reached = max(records) * output_dt if records else 0.0
        raise SimulationError(f"continuum run of {model.name} failed (dt = {dt:g} s, elements "
                              f"{system.elements}; last recorded t = {reached:g} s): "
                              f"{(message or 'no message').strip()[:400]}")
    df = pd.DataFrame([records[i] for i in sorted(records)])
    df.attrs.update(engine=ENGINE, dt=dt, elements=dict(system.elements), wall_time_s=wall,
                    euler_bernoulli=bool(euler_bernoulli),
                    zero_initial_accelerations=zero_start, notes=list(system.notes))
    return df


def rfem_quantities(model, t, q, lam=None, constraint_names=()) -> dict:
    """The same columns from a gpme state (t s, q (n,)), with gpme's own link frames
    (gpme_core.kinematics): what is being tested, on gpme's side."""
    layout = continuum_layout(model)
    frames = kinematics.link_transforms(model, np.asarray(q, dtype=float))
    row = {"t": float(t)}
    for k in layout.joints:
        row[model.joints[k].name] = float(q[k])
    for beam in layout.beams:
        root = frames[beam.carrying_link] @ beam.root_frame
        tip = frames[beam.tip_link] @ beam.tip_frame
        row.update(tip_quantities(beam.name, beam.beam.length, root, tip))
    if lam is not None:
        for name, v in zip(constraint_names, lam):
            row[f"lambda_{name}"] = float(v)
    return row

"""A Pinocchio model of a gpme model, built three ways, with the map between their coordinates.

Three builders, from the least to the most independent of gpme:

* :func:`from_gpme` builds a ``pin.Model`` joint by joint from a gpme Model: joint k
  becomes Pinocchio joint k + 1 (0 is the universe), with placement ``Joint.origin``, a
  revolute/prismatic joint about/along ``Joint.axis`` (RX/RY/RZ, PX/PY/PZ when the axis
  is a coordinate axis, the unaligned joint otherwise, as Pinocchio's URDF parser does),
  the link inertia appended at the joint frame, and every gpme frame as an OP_FRAME;
* :func:`from_urdf` reads the URDF that gpme_io.urdf.write_urdf wrote, with Pinocchio's
  own parser (inertias, origins, axes, damping from <dynamics>) and the gpme side file
  beside it (stiffness, spring references, gravity, which Pinocchio does not hold);
* :func:`from_original_urdf` reads the *user's* URDF (the whole tree) with Pinocchio's
  parser and locks every joint that is not one of the gpme model's coordinates with
  Pinocchio's own ``buildReducedModel`` at the frozen values: the reduction of the tree
  to the chain (which gpme's reader does by merging inertias) is done by Pinocchio.

All return a :class:`PinocchioSystem`, which maps gpme's coordinate order to Pinocchio's
configuration (q, nq entries) and velocity (v, nv = n entries) vectors: a continuous
(unbounded revolute) joint has nq = 2 in Pinocchio, (cos q, sin q), and nv = 1.  It also
carries the generalized springs and dampers of the Pinocchio side, so that the applied
joint forces passed to Pinocchio (tau = -K (q - q_ref) - D q_dot + drives) are formed
from this side's data.  Pinocchio's joint frame after the motion is the gpme link frame
(same convention: T_parent_child = origin @ motion(q)).
"""
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from gpme_core.errors import ModelFileError
from gpme_core.point_springs import PointSpring
from gpme_io.urdf import load_side_file, side_file_path

_AXES = {(1.0, 0.0, 0.0): "X", (0.0, 1.0, 0.0): "Y", (0.0, 0.0, 1.0): "Z"}


@dataclass(frozen=True)
class PinocchioSystem:
    """A pin.Model matched to a gpme model's coordinates, links and frames.

    model           : pin.Model with nv = n (n = gpme coordinates)
    link_frames     : (n,) Pinocchio frame ids of the gpme links, in gpme link order
    frames          : {gpme frame name: Pinocchio frame id}
    stiffness       : (n,) N/m or N m/rad of the Pinocchio side, gpme coordinate order
    spring_reference: (n,) m or rad
    damping         : (n,) N s/m or N m s/rad (pin.Model.damping), gpme coordinate order
    source          : "gpme" (built directly), "urdf" (our URDF, Pinocchio's parser) or
                      "original urdf" (the user's URDF, reduced by Pinocchio)
    q_index         : (n,) Pinocchio idx_q of each gpme coordinate
    v_index         : (n,) Pinocchio idx_v of each gpme coordinate
    continuous      : (n,) True where Pinocchio holds (cos q, sin q) (nq = 2)
    locked          : {URDF joint name: value (rad or m)} joints locked by buildReducedModel
    notes           : what this side takes from where, one line each (for the report)
    point_springs   : gpme_core.point_springs.PointSpring data (frame names, anchors,
                      stiffness, free length, damping) whose forces this side computes from
                      Pinocchio's own frame placements, velocities and Jacobians
    """

    model: object
    link_frames: tuple
    frames: Mapping[str, int]
    stiffness: NDArray[np.float64]
    spring_reference: NDArray[np.float64]
    damping: NDArray[np.float64]
    source: str
    q_index: NDArray[np.int64]
    v_index: NDArray[np.int64]
    continuous: NDArray[np.bool_]
    locked: Mapping[str, float] = field(default_factory=dict)
    notes: tuple = ()
    point_springs: tuple = ()

    def q_pin(self, q: NDArray) -> NDArray:
        """(nq,) Pinocchio configuration of the gpme coordinates q (n,) (rad, m)."""
        q = np.asarray(q, dtype=float)
        out = pin.neutral(self.model)
        if not self.continuous.any():         # every coordinate one entry of q_pin
            out[self.q_index] = q
            return out
        plain = ~self.continuous
        out[self.q_index[plain]] = q[plain]
        out[self.q_index[self.continuous]] = np.cos(q[self.continuous])
        out[self.q_index[self.continuous] + 1] = np.sin(q[self.continuous])
        return out

    def to_pin(self, x: NDArray) -> NDArray:
        """(nv, ...) a gpme-ordered velocity-like vector (or matrix rows) in Pinocchio order."""
        x = np.asarray(x, dtype=float)
        out = np.zeros((self.model.nv,) + x.shape[1:])
        out[self.v_index] = x
        return out

    def to_gpme(self, x: NDArray) -> NDArray:
        """(n,) a Pinocchio velocity-ordered vector in gpme coordinate order."""
        return np.asarray(x, dtype=float)[self.v_index]

    def columns_to_gpme(self, a: NDArray) -> NDArray:
        """(..., n) columns of a Pinocchio Jacobian (..., nv) in gpme coordinate order."""
        return np.asarray(a, dtype=float)[..., self.v_index]

    def applied_forces(self, q, q_dot, drives):
        """(n,) tau = -K (q - q_ref) - D q_dot + drives + the point springs' J^T F, N or
        N m, gpme order: the joint forces that Pinocchio's M a + b = tau takes (gpme's Q
        without gravity, which Pinocchio adds)."""
        tau = -self.stiffness * (q - self.spring_reference) - self.damping * q_dot + drives
        return tau + self.point_spring_forces(q, q_dot) if self.point_springs else tau

    def point_spring_forces(self, q, q_dot):
        """(n,) generalized forces of the point springs, gpme order: F = -(k (L - L0) +
        c L_dot) e on the spring's frame (e from its anchor to it), -F on an anchor frame,
        mapped by Pinocchio's frame Jacobians (LOCAL_WORLD_ALIGNED, linear rows)."""
        pm = self.model
        data = pm.createData()
        q_pin, v_pin = self.q_pin(q), self.to_pin(q_dot)
        pin.forwardKinematics(pm, data, q_pin, v_pin)
        pin.computeJointJacobians(pm, data, q_pin)
        pin.updateFramePlacements(pm, data)
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

        def point(frame):
            fid = self.frames[frame]
            jac = np.asarray(pin.getFrameJacobian(pm, data, fid, lwa)).reshape(6, pm.nv)[:3]
            return (data.oMf[fid].translation.copy(),
                    pin.getFrameVelocity(pm, data, fid, lwa).linear.copy(),
                    self.columns_to_gpme(jac))

        out = np.zeros(len(self.v_index))
        for s in self.point_springs:
            p_a, v_a, j_a = point(s.frame)
            if isinstance(s.anchor, str):
                p_b, v_b, j_b = point(s.anchor)
            else:
                p_b, v_b, j_b = np.asarray(s.anchor, float), np.zeros(3), 0.0
            d = p_a - p_b
            length = float(np.linalg.norm(d))
            e = d / length
            force = -(s.stiffness * (length - s.free_length)
                      + s.damping * float(e @ (v_a - v_b))) * e
            out += force @ (j_a - j_b)
        return out


def _identity_map(n):
    idx = np.arange(n)
    return idx, idx.copy(), np.zeros(n, dtype=bool)


def _joint_model(kind, axis):
    key = tuple(float(a) for a in axis)
    letter = _AXES.get(key)
    if kind == "revolute":
        return getattr(pin, f"JointModelR{letter}")() if letter else \
            pin.JointModelRevoluteUnaligned(np.array(axis, dtype=float))
    return getattr(pin, f"JointModelP{letter}")() if letter else \
        pin.JointModelPrismaticUnaligned(np.array(axis, dtype=float))


def from_gpme(model) -> PinocchioSystem:
    """:class:`PinocchioSystem` built joint by joint from the gpme ``model``."""
    pm = pin.Model()
    pm.name = model.name
    link_frames = []
    for k, (joint, link) in enumerate(zip(model.joints, model.links)):
        parent = int(model.parents[k])             # -1 the world: Pinocchio's joint 0
        jid = pm.addJoint(parent + 1, _joint_model(joint.kind, joint.axis),
                          pin.SE3(joint.origin), joint.name)
        inertia = pin.Inertia.Zero() if link.inertia is None else pin.Inertia(
            link.inertia.mass, link.inertia.com_array, link.inertia.inertia_array)
        pm.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        parent_frame = 0 if parent < 0 else link_frames[parent]    # 0: the universe frame
        link_frames.append(pm.addBodyFrame(link.name, jid, pin.SE3.Identity(), parent_frame))
    pm.damping = model.damping.copy()
    frames = {}
    for name, fr in model.frames.items():
        jid = fr.link_index + 1
        frames[name] = pm.addFrame(pin.Frame(name, jid, link_frames[fr.link_index],
                                             pin.SE3(fr.transform), pin.FrameType.OP_FRAME))
    pm.gravity = pin.Motion(np.asarray(model.gravity, dtype=float), np.zeros(3))
    return PinocchioSystem(pm, tuple(link_frames), frames, model.stiffness.copy(),
                           model.spring_reference.copy(), np.array(pm.damping), "gpme",
                           *_identity_map(model.n_coordinates),
                           notes=("pin.Model built joint by joint from the gpme model",),
                           point_springs=tuple(model.point_springs))


def from_urdf(urdf_path, coordinate_names, link_names, frame_names,
              side_file="auto") -> PinocchioSystem:
    """:class:`PinocchioSystem` from Pinocchio's URDF parser and the gpme side file.

    coordinate_names, link_names, frame_names: the gpme model's, to match the URDF joint,
    link and frame names against (ModelFileError listing every mismatch).
    """
    pm = pin.buildModelFromUrdf(str(urdf_path))
    side_path = side_file_path(urdf_path) if side_file == "auto" else side_file
    side = load_side_file(side_path) if side_path is not None else {}
    problems = []
    names = list(pm.names)[1:]
    if pm.nq != pm.nv or sorted(names) != sorted(coordinate_names):
        problems.append(f"Pinocchio read joints {names} (nq={pm.nq}, nv={pm.nv}) from "
                        f"{urdf_path}, expected {list(coordinate_names)} with nq = nv")
    missing = [f for f in list(link_names) + list(frame_names) if not pm.existFrame(f)]
    if missing:
        problems.append(f"Pinocchio has no frames {missing} in {urdf_path}")
    if problems:
        raise ModelFileError(problems)
    springs = side.get("joints", {})
    stiffness = np.array([springs.get(n, {}).get("stiffness", 0.0) for n in coordinate_names])
    reference = np.array([springs.get(n, {}).get("spring_reference", 0.0)
                          for n in coordinate_names])
    pm.gravity = pin.Motion(np.array(side.get("gravity", (0.0, 0.0, -9.81)), dtype=float),
                            np.zeros(3))
    # by name: Pinocchio's parser numbers the joints of a tree depth first, which need not
    # be the gpme order (parents first, branches in the order the model lists them)
    ids = [pm.getJointId(name) for name in coordinate_names]
    q_index = np.array([pm.joints[j].idx_q for j in ids], dtype=int)
    v_index = np.array([pm.joints[j].idx_v for j in ids], dtype=int)
    return PinocchioSystem(pm, tuple(_frame_id(pm, n) for n in link_names),
                           {f: _frame_id(pm, f) for f in frame_names}, stiffness, reference,
                           np.array(pm.damping)[v_index], "urdf", q_index, v_index,
                           np.zeros(len(ids), dtype=bool),
                           point_springs=tuple(
                               PointSpring(r["name"], r["frame"],
                                           r["anchor"] if isinstance(r["anchor"], str)
                                           else tuple(r["anchor"]), r["stiffness"],
                                           r["free_length"], r.get("damping", 0.0))
                               for r in side.get("point_springs", [])),
                           notes=(f"Pinocchio's URDF parser on {Path(urdf_path).name}; springs "
                                  "and gravity from its side file",))


def _frame_id(pm, name):
    """Pinocchio frame id of link ``name``: its BODY frame (a URDF joint may share the name
    of its child link; the joint frame then comes first in pm.frames)."""
    if pm.existFrame(name, pin.FrameType.BODY):
        return pm.getFrameId(name, pin.FrameType.BODY)
    return pm.getFrameId(name)


def _is_continuous(joint):
    return joint.nq == 2 and joint.nv == 1


def _lock_value(joint, value, name, problems):
    """Pinocchio configuration entries (nq,) of a locked joint at ``value``."""
    if joint.nq == 1 and joint.nv == 1:
        return [float(value)]
    if _is_continuous(joint):
        return [np.cos(value), np.sin(value)]
    problems.append(f"joint {name!r} ({joint.shortname()}, nq = {joint.nq}) cannot be frozen "
                    f"at the single value {value!r}; only revolute, continuous and prismatic "
                    "joints have one")
    return None


def from_original_urdf(urdf_path, coordinate_names: Sequence[str], link_names: Sequence[str],
                       frame_names: Sequence[str], frozen: Mapping[str, float], gravity,
                       stiffness, spring_reference, damping,
                       point_springs=(), auxiliary_frames=None) -> PinocchioSystem:
    """:class:`PinocchioSystem` of the user's URDF, reduced to the gpme chain by Pinocchio.

    urdf_path        : the user's URDF (whole tree); Pinocchio's parser reads it
    coordinate_names : the gpme coordinates = the URDF joints kept moving (the chain)
    link_names, frame_names : gpme link and frame names = URDF link names
    frozen           : {URDF joint: value (rad or m)}; every other joint off the chain is
                       locked at 0 (Pinocchio's neutral configuration for it)
    gravity          : (3,) m/s^2, world frame (a URDF has none)
    point_springs    : the model's point springs (a URDF has none), evaluated here from
                       Pinocchio's frames
    auxiliary_frames : {name: (frame, (4, 4) offset)} frames the URDF does not have, added
                       on ``frame`` at that offset (the points one metre along an axis of
                       crosscheck.constraint_reference)
    stiffness, spring_reference, damping : (n,) gpme order; a URDF has no springs, and a
                       model file may override the URDF's <dynamics damping>, so these come
                       from the model (the only terms not read by Pinocchio here); the
                       joints whose damping differs from the URDF's as Pinocchio read it
                       are listed in the notes.

    ModelFileError lists every
    mismatch (a coordinate, link or frame Pinocchio does not have, nv != n, a frozen joint
    that is on the chain or not in the file).
    """
    full = pin.buildModelFromUrdf(str(urdf_path))
    problems = []
    names = list(full.names)[1:]
    chain = list(coordinate_names)
    absent = [c for c in chain if c not in names]
    if absent:
        problems.append(f"Pinocchio finds no joints {absent} in {urdf_path}; it has {names}")
    on_chain = sorted(set(frozen) & set(chain))
    if on_chain:
        problems.append(f"joints {on_chain} are both frozen and gpme coordinates")
    unknown = sorted(set(frozen) - set(names))
    if unknown:
        problems.append(f"frozen joints {unknown} are not joints of {urdf_path}")
    q_ref = pin.neutral(full)
    locked, lock_ids = {}, []
    for name in names:
        if name in chain:
            continue
        jid = full.getJointId(name)
        joint = full.joints[jid]
        value = float(frozen.get(name, 0.0))
        entries = _lock_value(joint, value, name, problems)
        if entries is not None:
            q_ref[joint.idx_q:joint.idx_q + joint.nq] = entries
        locked[name] = value
        lock_ids.append(jid)
    if problems:
        raise ModelFileError([f"original URDF {urdf_path}: {p}" for p in problems])
    pm = pin.buildReducedModel(full, lock_ids, q_ref) if lock_ids else full
    for name, (base, offset) in (auxiliary_frames or {}).items():
        if pm.existFrame(base) and not pm.existFrame(name):
            base_id = pm.getFrameId(base)
            frame = pm.frames[base_id]
            pm.addFrame(pin.Frame(name, frame.parentJoint, base_id,
                                  frame.placement * pin.SE3(np.asarray(offset, dtype=float)),
                                  pin.FrameType.OP_FRAME))
    q_index, v_index, continuous = [], [], []
    for name in chain:
        joint = pm.joints[pm.getJointId(name)]
        if joint.nv != 1:
            problems.append(f"joint {name!r} is a {joint.shortname()} with nv = {joint.nv}; "
                            "a gpme coordinate needs nv = 1")
        q_index.append(joint.idx_q)
        v_index.append(joint.idx_v)
        continuous.append(_is_continuous(joint))
    if pm.nv != len(chain):
        problems.append(f"after locking {sorted(locked)}, Pinocchio has nv = {pm.nv} "
                        f"(nq = {pm.nq}) but gpme has n = {len(chain)} coordinates")
    missing = [f for f in list(link_names) + list(frame_names) if not pm.existFrame(f)]
    if missing:
        problems.append(f"Pinocchio has no frames {missing}")
    if problems:
        raise ModelFileError([f"original URDF {urdf_path}: {p}" for p in problems])
    pm.gravity = pin.Motion(np.asarray(gravity, dtype=float), np.zeros(3))
    v_index = np.array(v_index, dtype=int)
    n_cont = int(np.sum(continuous))
    notes = [f"Pinocchio's URDF parser on the user's {Path(urdf_path).name} (nq = {full.nq}, "
             f"nv = {full.nv}); buildReducedModel locked {len(locked)} joint(s): "
             + (", ".join(f"{k} = {v:g}" for k, v in locked.items()) or "none")
             + f"; reduced nq = {pm.nq}, nv = {pm.nv}",
             "springs, dampers and gravity from the model (a URDF has no springs or gravity, "
             "and a model file may override its damping)"]
    urdf_damping = np.array(pm.damping)[v_index]
    differ = [f"{c} {d:g} (URDF {u:g})" for c, d, u in zip(chain, damping, urdf_damping)
              if d != u]
    if differ:
        notes.append("damping set by the model file, not the URDF: " + ", ".join(differ))
    if n_cont:
        notes.append(f"{n_cont} continuous joint(s) held as (cos q, sin q) in Pinocchio")
    return PinocchioSystem(pm, tuple(_frame_id(pm, n) for n in link_names),
                           {f: _frame_id(pm, f) for f in frame_names},
                           np.asarray(stiffness, dtype=float).copy(),
                           np.asarray(spring_reference, dtype=float).copy(),
                           np.asarray(damping, dtype=float).copy(), "original urdf",
                           np.array(q_index, dtype=int), v_index,
                           np.array(continuous, dtype=bool), locked, tuple(notes),
                           tuple(point_springs))

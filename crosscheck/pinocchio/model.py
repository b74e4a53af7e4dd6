"""A Pinocchio model of a gpme model, built directly or from its URDF, and frame lookups.

Two builders, so that both the gpme -> Pinocchio mapping and the URDF path are checked:

* :func:`from_gpme`  builds a ``pin.Model`` joint by joint from a gpme Model: joint k
  becomes Pinocchio joint k + 1 (0 is the universe), with placement ``Joint.origin``, a
  revolute/prismatic joint about/along ``Joint.axis`` (RX/RY/RZ, PX/PY/PZ when the axis
  is a coordinate axis, the unaligned joint otherwise, as Pinocchio's URDF parser does),
  the link inertia appended at the joint frame, and every gpme frame as an OP_FRAME;
* :func:`from_urdf`  reads a URDF with Pinocchio's own parser (inertias, origins, axes,
  damping from <dynamics>) and the gpme side file beside it (stiffness, spring
  references, gravity, which Pinocchio does not hold).

Both return a :class:`PinocchioSystem` that also carries the generalized springs and
dampers of the Pinocchio side, so that the applied joint forces passed to Pinocchio
(tau = -K (q - q_ref) - D q_dot + drives) are formed from this side's own data.
Pinocchio's joint frame after the motion is the gpme link frame (same convention:
T_parent_child = origin @ motion(q)).
"""
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gpme_core.errors import ModelFileError

from gpme_io.urdf import load_side_file, side_file_path

_AXES = {(1.0, 0.0, 0.0): "X", (0.0, 1.0, 0.0): "Y", (0.0, 0.0, 1.0): "Z"}


@dataclass(frozen=True)
class PinocchioSystem:
    """A pin.Model matched to a gpme model's coordinates, links and frames.

    model           : pin.Model, nq = nv = n, joint k + 1 <-> gpme coordinate k
    link_frames     : (n,) Pinocchio frame ids of the gpme links (the joint frames)
    frames          : {gpme frame name: Pinocchio frame id}
    stiffness       : (n,) N/m or N m/rad of the Pinocchio side (side file or gpme model)
    spring_reference: (n,) m or rad
    damping         : (n,) N s/m or N m s/rad (pin.Model.damping)
    source          : "gpme" (built directly) or "urdf" (Pinocchio's URDF parser)
    """

    model: object
    link_frames: tuple
    frames: dict
    stiffness: np.ndarray
    spring_reference: np.ndarray
    damping: np.ndarray
    source: str

    def applied_forces(self, q, q_dot, drives):
        """(n,) tau = -K (q - q_ref) - D q_dot + drives, N or N m: the joint forces that
        Pinocchio's M a + b = tau takes (gpme's Q without gravity, which Pinocchio adds)."""
        return -self.stiffness * (q - self.spring_reference) - self.damping * q_dot + drives


def _joint_model(kind, axis):
    key = tuple(float(a) for a in axis)
    letter = _AXES.get(key)
    if kind == "revolute":
        return getattr(pin, f"JointModelR{letter}")() if letter else \
            pin.JointModelRevoluteUnaligned(np.array(axis, dtype=float))
    return getattr(pin, f"JointModelP{letter}")() if letter else \
        pin.JointModelPrismaticUnaligned(np.array(axis, dtype=float))


def from_gpme(model):
    """:class:`PinocchioSystem` built joint by joint from the gpme ``model``."""
    pm = pin.Model()
    pm.name = model.name
    link_frames = []
    frame_id = 0                                    # the universe frame
    for k, (joint, link) in enumerate(zip(model.joints, model.links)):
        jid = pm.addJoint(k, _joint_model(joint.kind, joint.axis), pin.SE3(joint.origin),
                          joint.name)
        inertia = pin.Inertia.Zero() if link.inertia is None else pin.Inertia(
            link.inertia.mass, link.inertia.com_array, link.inertia.inertia_array)
        pm.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        frame_id = pm.addBodyFrame(link.name, jid, pin.SE3.Identity(), frame_id)
        link_frames.append(frame_id)
    pm.damping = model.damping.copy()
    frames = {}
    for name, fr in model.frames.items():
        jid = fr.link_index + 1
        frames[name] = pm.addFrame(pin.Frame(name, jid, link_frames[fr.link_index],
                                             pin.SE3(fr.transform), pin.FrameType.OP_FRAME))
    pm.gravity = pin.Motion(np.asarray(model.gravity, dtype=float), np.zeros(3))
    return PinocchioSystem(pm, tuple(link_frames), frames, model.stiffness.copy(),
                           model.spring_reference.copy(), np.array(pm.damping), "gpme")


def from_urdf(urdf_path, coordinate_names, link_names, frame_names, side_file="auto"):
    """:class:`PinocchioSystem` from Pinocchio's URDF parser and the gpme side file.

    coordinate_names, link_names, frame_names: the gpme model's, to match the URDF joint,
    link and frame names against (ModelFileError listing every mismatch).
    """
    pm = pin.buildModelFromUrdf(str(urdf_path))
    side_path = side_file_path(urdf_path) if side_file == "auto" else side_file
    side = load_side_file(side_path) if side_path is not None else {}
    problems = []
    names = list(pm.names)[1:]
    if pm.nq != pm.nv or names != list(coordinate_names):
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
    return PinocchioSystem(pm, tuple(pm.getFrameId(n) for n in link_names),
                           {f: pm.getFrameId(f) for f in frame_names}, stiffness, reference,
                           np.array(pm.damping), "urdf")

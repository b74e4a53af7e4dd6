"""A Drake MultibodyPlant of a gpme model, read by Drake's own URDF parser, with the map
between their coordinates.

:func:`from_urdf` reads the URDF that ``gpme_io.urdf.write_urdf`` wrote (inertias, joint
origins and axes, and the joint dampers of ``<dynamics damping>``, all through Drake's
``Parser``) into a continuous-time ``MultibodyPlant(time_step=0.0)``, and adds from the gpme
side file beside it (``<stem>.gpme.json``: what a URDF cannot hold):

* one Drake force element per joint spring, ``RevoluteSpring(joint, nominal_angle,
  stiffness)`` or ``PrismaticSpring(joint, nominal_position, stiffness)``: generalized force
  -K (q - q_ref) on the joint (N m or N);
* the gravity vector (m/s^2, world frame) of the plant's ``UniformGravityFieldElement``.

Joint damping stays where Drake's parser put it (``Joint.default_damping()``), and is checked
against the gpme model's damping when it is given (``expected_damping``): a parser that
silently dropped it would otherwise pass the terms it does not enter.  Drive forces are not
part of the plant: callers feed them to ``get_applied_generalized_force_input_port()``
(:meth:`DrakeSystem.to_drake` orders them).

Coordinates are matched by joint name: gpme coordinate k is the Drake joint of the same name,
at ``position_start()`` / ``velocity_start()``.  Drake must hold exactly the gpme coordinates,
one position and one velocity each (revolute, continuous and prismatic URDF joints; fixed
joints become welds): nq = nv = n.  A URDF whose root link is not ``world`` would get a
floating base from Drake (nq = 7 more); its root is welded to the world at the identity
instead, as gpme's reader and Pinocchio's ``buildModelFromUrdf`` treat it.  Anything else
(a floating or planar joint, a joint gpme does not have, a missing link) is a
``ModelFileError`` that lists every mismatch.

Frames: every gpme link and frame is a URDF link of the same name (gpme_io.urdf_writer), so a
Drake body; its body frame is the gpme frame.  No gpme kinematics or dynamics code is used
here: only data (the URDF text and the side file) and names.
"""
import logging
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version as dist_version
from pathlib import Path
from types import MappingProxyType
from typing import Mapping, Optional, Sequence

import numpy as np
import pydrake
from numpy.typing import NDArray
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (BodyIndex, JointIndex, LinearSpringDamper, PrismaticJoint,
                                   PrismaticSpring, RevoluteJoint, RevoluteSpring)

from gpme_core.errors import ModelFileError
from gpme_io.file_names import named_path
from gpme_io.urdf import load_side_file, side_file_path, write_urdf

log = logging.getLogger("gpme.crosscheck.drake")
WORLD = "world"
# Damping Drake read must equal the gpme model's up to the URDF's decimal round trip:
# write_urdf writes Python's shortest round-trip repr, so the values are equal bit for bit;
# 4 eps relative leaves room for a writer that rounds once.
DAMPING_RTOL = 4.0 * np.finfo(float).eps


def drake_version() -> str:
    """Version of the installed Drake (the ``drake`` distribution), e.g. "1.51.1"."""
    version = getattr(pydrake, "__version__", None)
    if version:
        return str(version)
    try:
        return dist_version("drake")
    except PackageNotFoundError:
        return "unknown"


@dataclass(frozen=True)
class DrakeSystem:
    """A finalized continuous-time MultibodyPlant matched to a gpme model's coordinates.

    plant           : pydrake MultibodyPlant (time_step 0), nq = nv = n
    coordinates     : (n,) gpme coordinate names, gpme order
    q_index         : (n,) Drake position index of each gpme coordinate
    v_index         : (n,) Drake velocity index of each gpme coordinate
    bodies          : {gpme link or frame name: Drake RigidBody}
    stiffness       : (n,) N/m or N m/rad of the springs added (side file), gpme order
    spring_reference: (n,) m or rad
    damping         : (n,) N s/m or N m s/rad, what Drake's parser read, gpme order
    gravity         : (3,) m/s^2, world frame, what the plant was given
    urdf            : the URDF Drake read
    welded_root     : name of the root link welded to the world, or None (root was "world")
    notes           : what this side takes from where, one line each (for the report)
    """

    plant: MultibodyPlant
    coordinates: tuple
    q_index: NDArray[np.int64]
    v_index: NDArray[np.int64]
    bodies: Mapping[str, object]
    stiffness: NDArray[np.float64]
    spring_reference: NDArray[np.float64]
    damping: NDArray[np.float64]
    gravity: NDArray[np.float64]
    urdf: Path
    welded_root: Optional[str] = None
    notes: tuple = field(default_factory=tuple)

    @property
    def n(self) -> int:
        return len(self.coordinates)

    def q_drake(self, q: NDArray) -> NDArray:
        """(nq,) Drake positions of the gpme coordinates q (n,) (rad, m)."""
        out = np.zeros(self.plant.num_positions())
        out[self.q_index] = np.asarray(q, dtype=float)
        return out

    def to_drake(self, x: NDArray) -> NDArray:
        """(nv, ...) a gpme-ordered velocity-like vector (or matrix rows) in Drake's v order."""
        x = np.asarray(x, dtype=float)
        out = np.zeros((self.plant.num_velocities(),) + x.shape[1:])
        out[self.v_index] = x
        return out

    def to_gpme(self, x: NDArray) -> NDArray:
        """(n, ...) a Drake velocity-ordered vector (or matrix rows) in gpme order."""
        return np.asarray(x, dtype=float)[self.v_index]

    def matrix_to_gpme(self, a: NDArray) -> NDArray:
        """(n, n) a Drake (nv, nv) matrix in gpme coordinate order (rows and columns)."""
        return np.asarray(a, dtype=float)[np.ix_(self.v_index, self.v_index)]

    def columns_to_gpme(self, a: NDArray) -> NDArray:
        """(..., n) columns of a Drake Jacobian (..., nv) in gpme coordinate order."""
        return np.asarray(a, dtype=float)[..., self.v_index]


def _joints(plant):
    return [plant.get_joint(JointIndex(i)) for i in range(plant.num_joints())]


def urdf_root(urdf_path: Path) -> Optional[str]:
    """Name of the URDF's root link (the one link that is no joint's child), or None when
    there is not exactly one (Drake's parser reports that itself)."""
    try:
        robot = ET.parse(urdf_path).getroot()
    except (ET.ParseError, OSError):
        return None
    links = [lk.get("name") for lk in robot.findall("link")]
    children = {c.get("link") for j in robot.findall("joint") for c in j.findall("child")}
    roots = [lk for lk in links if lk not in children]
    return roots[0] if len(roots) == 1 else None


def _free_bodies(plant) -> list:
    """Bodies other than the world with no inboard joint (Drake floats them at Finalize)."""
    world = plant.world_body().index()
    children = {j.child_body().index() for j in _joints(plant)}
    return [plant.get_body(BodyIndex(i)) for i in range(plant.num_bodies())
            if BodyIndex(i) != world and BodyIndex(i) not in children]


def _weld_root(plant, root: Optional[str], problems) -> Optional[str]:
    """Weld the URDF's root link to the world at the identity when it is not "world" (Drake
    would float it; gpme and Pinocchio fix it); any other body Drake left free (the child of
    a joint type it does not support, e.g. floating) is a problem.  Returns the welded
    root's name or None."""
    welded = None
    for body in _free_bodies(plant):
        if body.name() == root and root != WORLD:
            plant.WeldFrames(plant.world_frame(), body.body_frame())
            welded = body.name()
        else:
            problems.append(f"Drake left link {body.name()!r} free (a floating base: nq 7, "
                            "nv 6): its joint is of a type Drake's parser does not support "
                            "(e.g. floating), or it is a second root; a gpme coordinate is one "
                            "revolute, continuous or prismatic joint")
    return welded


class _Warnings(logging.Handler):
    """Collects the warnings Drake's parser logs (through Python's "drake" logger)."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())


def from_urdf(urdf_path, coordinate_names: Sequence[str], body_names: Sequence[str],
              side_file="auto", expected_damping: Optional[Sequence[float]] = None,
              gravity: Optional[Sequence[float]] = None) -> DrakeSystem:
    """:class:`DrakeSystem` from Drake's URDF parser and the gpme side file.

    urdf_path        : the URDF (gpme_io.urdf.write_urdf's, or any URDF of the same chain)
    coordinate_names : (n,) the gpme model's coordinates, matched to Drake joints by name
    body_names       : gpme link and frame names, matched to Drake bodies by name
    side_file        : "auto" (``<stem>.gpme.json`` beside the URDF), a path, or None (no
                       springs; gravity from ``gravity`` or (0, 0, -9.81) m/s^2)
    expected_damping : (n,) N s/m or N m s/rad the gpme model has; Drake's parsed damping
                       must equal it (else ModelFileError naming each joint)
    gravity          : (3,) m/s^2 overriding the side file's
    Raises ModelFileError listing every problem (Drake's parser error, nq/nv mismatch,
    missing joints or bodies, a spring Drake refuses).
    """
    urdf_path = Path(urdf_path)
    coordinate_names = list(coordinate_names)
    side_path = side_file_path(urdf_path) if side_file == "auto" else side_file
    side = load_side_file(side_path) if side_path is not None else {}
    plant = MultibodyPlant(time_step=0.0)
    warnings = _Warnings()
    drake_log = logging.getLogger("drake")
    drake_log.addHandler(warnings)
    try:
        Parser(plant).AddModels(str(urdf_path))
    except Exception as exc:        # Drake raises RuntimeError/ValueError for what it rejects
        raise ModelFileError(f"Drake's URDF parser cannot read {urdf_path}: {exc}") from None
    finally:
        drake_log.removeHandler(warnings)
    problems = []
    welded = _weld_root(plant, urdf_root(urdf_path), problems)
    joints = {j.name(): j for j in _joints(plant)}
    dof_joints = [j for j in _joints(plant) if j.num_velocities() or j.num_positions()]
    unknown = [f"{j.name()} ({j.type_name()}, nq = {j.num_positions()}, nv = "
               f"{j.num_velocities()})" for j in dof_joints if j.name() not in coordinate_names]
    if unknown:
        problems.append(f"Drake has joints that are not gpme coordinates: {unknown}")
    missing = [c for c in coordinate_names if c not in joints]
    if missing:
        problems.append(f"Drake has no joints {missing} (gpme coordinates)")
    wrong = [f"{c} ({joints[c].type_name()}, nq = {joints[c].num_positions()}, nv = "
             f"{joints[c].num_velocities()})" for c in coordinate_names if c in joints
             and not isinstance(joints[c], (RevoluteJoint, PrismaticJoint))]
    if wrong:
        problems.append(f"joints {wrong} are not revolute or prismatic: a gpme coordinate is "
                        "one revolute (or continuous) or prismatic joint, nq = nv = 1")
    absent = [b for b in body_names if not plant.HasBodyNamed(b)]
    if absent:
        problems.append(f"Drake has no bodies (URDF links) {absent}; every gpme link and "
                        "frame is a URDF link of its name")
    springs = side.get("joints", {})
    stiffness = np.array([float(springs.get(c, {}).get("stiffness", 0.0))
                          for c in coordinate_names])
    reference = np.array([float(springs.get(c, {}).get("spring_reference", 0.0))
                          for c in coordinate_names])
    if problems:
        raise ModelFileError([f"{urdf_path}: {p}" for p in problems] +
                             [f"Drake's parser warned: {w}" for w in warnings.messages])
    for c, k, ref in zip(coordinate_names, stiffness, reference):
        if k == 0.0:
            continue
        joint = joints[c]
        spring = RevoluteSpring if isinstance(joint, RevoluteJoint) else PrismaticSpring
        try:
            plant.AddForceElement(spring(joint, ref, k))
        except Exception as exc:
            problems.append(f"joint {c!r}: Drake refuses the spring stiffness {k!r}, "
                            f"reference {ref!r}: {exc} (stiffness must be >= 0)")
    for rec in side.get("point_springs", []):
        # a spring between two frames (URDF links of their names, Drake bodies) or a frame
        # and a world point: Drake's own LinearSpringDamper (its free length must be > 0)
        ends = []
        for end in (rec["frame"], rec["anchor"]):
            if isinstance(end, str):
                if not plant.HasBodyNamed(end):
                    problems.append(f"point spring {rec['name']!r}: Drake has no body {end!r}")
                    break
                ends += [plant.GetBodyByName(end), np.zeros(3)]
            else:
                ends += [plant.world_body(), np.asarray(end, dtype=float)]
        else:
            try:
                plant.AddForceElement(LinearSpringDamper(
                    ends[0], ends[1], ends[2], ends[3], float(rec["free_length"]),
                    float(rec["stiffness"]), float(rec.get("damping", 0.0))))
            except Exception as exc:
                problems.append(f"point spring {rec['name']!r}: Drake refuses it: {exc}")
    g = np.array(side.get("gravity", (0.0, 0.0, -9.81)) if gravity is None else gravity,
                 dtype=float)
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        problems.append(f"gravity must be 3 finite numbers (m/s^2), got {g.tolist()}")
    if problems:
        raise ModelFileError([f"{urdf_path}: {p}" for p in problems])
    plant.mutable_gravity_field().set_gravity_vector(g)
    plant.Finalize()
    nq, nv, n = plant.num_positions(), plant.num_velocities(), len(coordinate_names)
    if not nq == nv == n:
        raise ModelFileError(f"{urdf_path}: Drake's plant has nq = {nq}, nv = {nv}; the gpme "
                             f"model has n = {n} coordinates {coordinate_names} (nq = nv = n "
                             "required)")
    damping = np.array([float(joints[c].default_damping()) for c in coordinate_names])
    if expected_damping is not None:
        expected = np.asarray(expected_damping, dtype=float)
        bad = [f"{c}: Drake read {float(d)!r}, gpme has {float(e)!r}" for c, d, e in
               zip(coordinate_names, damping, expected)
               if abs(d - e) > DAMPING_RTOL * abs(e)]
        if bad:
            raise ModelFileError(f"{urdf_path}: the joint damping Drake's parser read from "
                                 f"<dynamics damping> differs from the gpme model's: "
                                 f"{'; '.join(bad)} (N s/m or N m s/rad)")
    q_index = np.array([joints[c].position_start() for c in coordinate_names], dtype=int)
    v_index = np.array([joints[c].velocity_start() for c in coordinate_names], dtype=int)
    bodies = {b: plant.GetBodyByName(b) for b in body_names}
    notes = [f"Drake's URDF parser on {urdf_path.name} into a continuous MultibodyPlant; "
             "joint dampers from <dynamics damping> (Drake's joint damping), springs as "
             "RevoluteSpring/PrismaticSpring force elements and gravity from the side file"]
    if welded:
        notes.append(f"root link {welded!r} welded to the world (Drake would float it)")
    notes += [f"Drake's parser warned: {w}" for w in warnings.messages]
    return DrakeSystem(plant, tuple(coordinate_names), _read_only(q_index),
                       _read_only(v_index), MappingProxyType(bodies), _read_only(stiffness),
                       _read_only(reference), _read_only(damping), _read_only(g), urdf_path,
                       welded, tuple(notes))


def _read_only(a: NDArray) -> NDArray:
    a.setflags(write=False)
    return a


def for_model(model, urdf_dir, name: Optional[str] = None) -> DrakeSystem:
    """The gpme ``model`` written by gpme_io.urdf.write_urdf to ``urdf_dir/<name>.urdf``
    (default the model's name) and read back by :func:`from_urdf`, its damping checked
    against the model's."""
    path = named_path(urdf_dir, name or model.name, ".urdf")
    path.parent.mkdir(parents=True, exist_ok=True)
    write_urdf(model, path)
    bodies = [lk.name for lk in model.links] + list(model.frames)
    return from_urdf(path, model.coordinate_names, bodies, expected_damping=model.damping)

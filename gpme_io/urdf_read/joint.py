"""A URDF <joint> -> :class:`_Joint`: type, ends, origin, axis, limits, damping, mimic.

Each joint is checked on its own (is its parent a link of the file, is its axis a
direction, are its limits ordered); whether the joints form a tree is gpme_io.urdf_read.tree's
job.  Elements gpme has no use for (friction, effort limits, safety controllers,
calibration, extension tags) are named in the notes.
"""
from dataclasses import dataclass
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from gpme_core import transforms as tf
from gpme_core.model import MIN_AXIS_LENGTH, PRISMATIC, REVOLUTE

from ..urdf_writer import UNLIMITED
from .attributes import _UNIT_TOL, _floats, _origin_transform

# URDF joint type -> gpme joint kind, for the types gpme can make a coordinate of
_MOVING = {"revolute": REVOLUTE, "continuous": REVOLUTE, "prismatic": PRISMATIC}
# URDF joint types gpme reads only off the chain, frozen at their origin: type -> what it is
_UNSUPPORTED = {"floating": "6-dof floating joint", "planar": "planar joint"}
_KNOWN_TYPES = tuple(_MOVING) + ("fixed",) + tuple(_UNSUPPORTED)
# children of a <joint> that URDF defines (others are extension tags, noted)
_JOINT_CHILDREN = ("origin", "parent", "child", "axis", "limit", "dynamics", "mimic",
                   "safety_controller", "calibration")


@dataclass
class _Joint:
    """One URDF joint as read.

    origin    : (4, 4) parent link frame -> joint frame
    axis      : (3,) unit vector in the joint frame
    damping   : N m s/rad or N s/m
    limits    : (lower, upper) rad or m, inf = none
    limit_raw : (lower, upper) as written, or None
    mimic     : (joint, multiplier, offset), or None
    """

    name: str
    type: str                 # URDF type
    parent: Optional[str]
    child: Optional[str]
    origin: NDArray[np.float64]
    axis: NDArray[np.float64]
    damping: float
    limits: tuple             # (lower, upper) rad or m, inf = none
    limit_raw: Optional[tuple]
    mimic: Optional[tuple]    # (joint, multiplier, offset)

    @property
    def moving(self) -> bool:
        return self.type != "fixed"

    def motion(self, value: float) -> NDArray[np.float64]:
        """(4, 4) joint frame -> child frame at coordinate ``value``."""
        if self.type in ("revolute", "continuous"):
            return tf.revolute_motion(self.axis, value)
        if self.type == "prismatic":
            return tf.prismatic_motion(self.axis, value)
        return np.eye(4)


def _read_limits(el, jtype, label, problems, notes):
    """(lower, upper) rad or m of a <limit> and whether lower == upper was read as none."""
    lim = el.find("limit")
    if lim is None:
        return (-np.inf, np.inf), None
    for key in ("effort", "velocity"):
        v = lim.get(key)
        if v is not None:
            x = _floats(v, 1, f"{label} <limit {key}>", problems, (np.inf,), infinite=True)[0]
            if abs(x) < UNLIMITED:
                notes.add("effort", el.get("name"))
    if jtype == "continuous":
        return (-np.inf, np.inf), None
    # URDF: lower and upper default to 0
    lo = float(_floats(lim.get("lower"), 1, f"{label} <limit lower>", problems, (0.0,),
                       infinite=True)[0])
    hi = float(_floats(lim.get("upper"), 1, f"{label} <limit upper>", problems, (0.0,),
                       infinite=True)[0])
    if lo > hi:
        problems.append(f"{label}: <limit lower={lo!r} upper={hi!r}> must have lower <= upper "
                        "(lower == upper is read as no range)")
        return (-np.inf, np.inf), (lo, hi)
    if lo == hi:
        notes.add("equal_limits", el.get("name"))
        return (-np.inf, np.inf), (lo, hi)
    return (-np.inf if lo <= -UNLIMITED else lo, np.inf if hi >= UNLIMITED else hi), (lo, hi)


def _end(el, end):
    """The ``end`` ("parent" or "child") link named by a <joint> element, or None."""
    e = el.find(end)
    return None if e is None else e.get("link")


def _read_joint(el, link_names, problems, notes) -> Optional[_Joint]:
    """The _Joint of a <joint> element, or None (no name or an unknown type: the problem
    is appended; a joint with other problems is returned with them appended)."""
    name = el.get("name")
    if not name or not name.strip():
        problems.append(f"a <joint> without a name attribute (type {el.get('type')!r}, "
                        f"child link {_end(el, 'child')!r}): every joint needs name=...")
        return None
    label = f"joint {name!r}"
    jtype = el.get("type")
    if jtype not in _KNOWN_TYPES:
        problems.append(f"{label}: unknown type {jtype!r}; URDF types: "
                        f"{', '.join(_KNOWN_TYPES)}" if jtype is not None else
                        f"{label}: missing type=...; URDF types: {', '.join(_KNOWN_TYPES)}")
        return None
    ends = {}
    for end in ("parent", "child"):
        e = el.find(end)
        ends[end] = None if e is None else e.get("link")
        if ends[end] is None:
            problems.append(f"{label}: missing <{end} link=...>")
        elif ends[end] not in link_names:
            problems.append(f"{label}: {end} link {ends[end]!r} is not a <link> of the file")
    origin = _origin_transform(el, label, problems)
    axis = np.array((1.0, 0.0, 0.0))
    limits, raw = (-np.inf, np.inf), None
    for child in el:
        if child.tag not in _JOINT_CHILDREN and isinstance(child.tag, str):
            notes.add("tags", f"<{child.tag}> in joint {name!r}")
    if jtype in _MOVING:
        limits, raw = _read_limits(el, jtype, label, problems, notes)
        axis = _read_axis(el, label, problems, notes)
    damping = _read_dynamics(el, label, problems, notes)
    if el.find("safety_controller") is not None:
        notes.add("safety", name)
    if el.find("calibration") is not None:
        notes.add("calibration", name)
    mimic = _read_mimic(el, jtype, label, problems, notes)
    return _Joint(name, jtype, ends["parent"], ends["child"], origin, axis, damping, limits,
                  raw, mimic)


def _read_axis(el, label, problems, notes) -> NDArray[np.float64]:
    """(3,) unit axis of a moving joint's <axis xyz> in the joint frame (default +x; a
    zero or degenerate axis is a problem and read as +x; another length is normalised and
    noted)."""
    name = el.get("name")
    axis = np.array((1.0, 0.0, 0.0))
    ax = el.find("axis")
    if ax is not None:
        axis = _floats(ax.get("xyz"), 3, f"{label} <axis xyz>", problems, (1, 0, 0))
    scale = float(np.max(np.abs(axis)))
    length = scale * float(np.linalg.norm(axis / scale)) if scale > 0 else 0.0
    if length < MIN_AXIS_LENGTH:
        why = "must not be zero" if scale == 0.0 else (
            f"is degenerate: its length {length:.3g} is below {MIN_AXIS_LENGTH:g} (no "
            "direction: normalising it would multiply its round-off by 1/|axis|)")
        problems.append(f"{label}: <axis xyz> {why}, got {ax.get('xyz')!r} (a unit "
                        "vector in the joint frame, e.g. '0 0 1'; other lengths are "
                        "normalised)")
        return np.array((1.0, 0.0, 0.0))
    axis = axis / scale
    norm = float(np.linalg.norm(axis))
    if abs(norm * scale - 1.0) > _UNIT_TOL:
        notes.add("axis", name)
    return axis / norm


def _read_dynamics(el, label, problems, notes) -> float:
    """Damping of a <dynamics> (N m s/rad or N s/m, 0 if absent or negative: a negative
    one is a problem); friction other than 0 is noted as ignored."""
    dyn = el.find("dynamics")
    if dyn is None:
        return 0.0
    damping = float(_floats(dyn.get("damping", "0"), 1, f"{label} <dynamics damping>",
                            problems, (0,))[0])
    friction = float(_floats(dyn.get("friction", "0"), 1, f"{label} <dynamics friction>",
                             problems, (0,))[0])
    if damping < 0:
        problems.append(f"{label}: <dynamics damping> must be >= 0 (N m s/rad or N s/m), "
                        f"got {damping!r}")
        damping = 0.0                 # reported here, not again by the built model
    if friction != 0.0:
        notes.add("friction", el.get("name"))
    return damping


def _read_mimic(el, jtype, label, problems, notes) -> Optional[tuple]:
    """(joint, multiplier, offset) of a <mimic>, or None (absent, on a fixed joint: noted,
    or without joint=...: a problem)."""
    mim = el.find("mimic")
    if mim is None:
        return None
    if jtype == "fixed":
        notes.add("mimic_fixed", el.get("name"))
        return None
    if not mim.get("joint"):
        problems.append(f"{label}: <mimic> without joint=...")
        return None
    mult = float(_floats(mim.get("multiplier"), 1, f"{label} <mimic multiplier>",
                         problems, (1.0,))[0])
    off = float(_floats(mim.get("offset"), 1, f"{label} <mimic offset>", problems,
                        (0.0,))[0])
    return (mim.get("joint"), mult, off)

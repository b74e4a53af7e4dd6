"""Read a URDF (any tree, through a chosen chain) into a gpme Model.

:func:`load_urdf` reads the descriptions people have: trees with grippers and sensors,
extension tags, friction and actuator limits.  What it does, in order (docs/urdf.md):

* **Chain.**  ``chain=(root, tip)``: the revolute, continuous (both -> gpme revolute)
  and prismatic joints on the path from link ``root`` to link ``tip`` are the gpme
  coordinates, in path order.  ``root`` defaults to the URDF's root link; ``tip`` may be
  omitted when the moving joints below ``root`` lie on one path.  gpme's world frame is
  the URDF root link's frame: everything fixed to it (links above ``root``, branches that
  do not move) is dropped, and the pose of ``root`` goes into the first joint's origin.
* **Frozen joints.**  Every other moving joint is frozen at ``frozen[name]`` (rad or m,
  default 0.0): it becomes a fixed joint with origin @ motion(value).  A mimic joint off
  the chain without a value follows the joint it mimics: multiplier * value + offset.
  Joints above ``root`` must be frozen explicitly (they would move the whole chain).
* **Merging.**  Every link hanging on a chain link through fixed or frozen joints adds its
  inertia to that chain link and becomes a named frame of the model.
* **Flexible links.**  ``flexible={link: FlexibleLink(...)}`` replaces the link's
  <inertial> by an RFEM beam (gpme_core.rfem); see :class:`FlexibleLink` for the beam's
  axis, length and section frame.  ``{link: (BeamProperties, n)}`` (beam along +x) still
  works.
* **Ignored, and said so.**  <dynamics friction>, effort and velocity limits,
  <safety_controller>, <calibration>, <transmission>, <gazebo>, <mujoco> and other
  extension tags, <mimic> on fixed joints, <visual> and <collision>, inertials on links
  that do not move: each class is named once in :attr:`UrdfReadResult.notes`.  A <limit>
  with lower == upper (URDF's default 0 = 0 when a <limit> gives only effort and
  velocity) is read as no range (unlimited) and noted.

Every problem, from every stage (XML, side file, inertials, joints, chain, frozen values,
flexible specs, the built model), comes in one :class:`gpme_core.errors.ModelFileError`.
"""
import math
import xml.etree.ElementTree as ET
from collections import Counter, deque
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Mapping, Optional, Sequence, Union

import numpy as np
from numpy.typing import NDArray

from gpme_core import transforms as tf
from gpme_core.errors import ModelError, ModelFileError
from gpme_core.inertia import RigidBodyInertia
from gpme_core.model import (MIN_AXIS_LENGTH, PRISMATIC, REVOLUTE, STANDARD_GRAVITY,
                             ChainBuilder, FlexibleLinkInfo, Model, validate_model)
from gpme_core.rfem import MAX_SEGMENTS, BeamProperties, BeamSection

from .input_files import URDF_LIMIT, InputFileError, read_input_file
from .side_file import check_side_file, drive_function, read_side_file, side_file_path
from .urdf_writer import UNLIMITED

_MOVING = {"revolute": REVOLUTE, "continuous": REVOLUTE, "prismatic": PRISMATIC}
_UNSUPPORTED = {"floating": "6-dof floating joint", "planar": "planar joint"}
_KNOWN_TYPES = tuple(_MOVING) + ("fixed",) + tuple(_UNSUPPORTED)
_ROBOT_CHILDREN = ("link", "joint", "material")
_LINK_CHILDREN = ("inertial", "visual", "collision")
_JOINT_CHILDREN = ("origin", "parent", "child", "axis", "limit", "dynamics", "mimic",
                   "safety_controller", "calibration")
# |axis| - 1 accepted for a FlexibleLink axis given as a unit vector (round-off of a
# normalised vector written in decimal is ~1e-16; 1e-9 allows 9-digit text).
_UNIT_TOL = 1e-9
# Below this norm (of a unit vector's component) the default section y axis is taken as
# parallel to the beam and the link z axis is used instead.
_PARALLEL_TOL = 1e-6
# kg m^2: the largest inertia about the root (sum of m |lever|^2 + tr I) the reader
# accepts.  The mass matrix's entries are at most this; its eigenvalue check and the
# integrators square them, and the square must stay below double precision's 1.8e308.
# Real machines are below 1e12 kg m^2; anything near this limit is a unit error or junk.
_MAGNITUDE = 1e150


# ============================================================================ public types
@dataclass(frozen=True)
class FlexibleLink:
    """How to make one URDF link an RFEM beam on reading.

    section           : gpme_core.rfem.BeamSection (area, I_y, I_z, J in the beam frame)
    youngs_modulus    : E, Pa
    shear_modulus     : G, Pa
    density           : rho, kg/m^3
    n_segments        : RFEM segments, int >= 0 (0 = one rigid body with the beam's mass)
    bending_viscosity : eta_E, Pa s (Kelvin-Voigt), default 0
    torsion_viscosity : eta_G, Pa s; None = eta_E G / E
    axis              : (3,) unit vector, link frame; None = towards the next chain joint
    length            : m; None = the next chain joint's distance along ``axis``
    section_y_axis    : (3,) link frame, the direction of the section's y axis (projected
                        orthogonal to the beam); None = the link y axis, or the link z axis
                        when y is parallel to the beam

    The rule: the beam starts at the link frame origin.  Its axis and length are the
    vector p from the link origin to the origin of the next chain joint's frame (in the
    link frame, through any fixed joints in between): axis = p / |p|, length = p . axis,
    unless ``axis`` / ``length`` are given; the chain's tip link has no next joint, so both
    must be given.  The beam frame B has x along the axis, y the normalised component of
    ``section_y_axis`` orthogonal to x, z = x cross y.  The link's <inertial> is replaced
    by the beam's RFEM masses; links fixed to it keep theirs.  Everything hanging on the
    link (the next joint, fixed links, frames) moves to the beam tip with its transform T
    from the link frame replaced by inv(B @ translation(L)) @ T, so that at zero
    deflection the rigid geometry is unchanged.
    """

    section: BeamSection
    youngs_modulus: float
    shear_modulus: float
    density: float
    n_segments: int
    bending_viscosity: float = 0.0
    torsion_viscosity: Optional[float] = None
    axis: Optional[tuple] = None
    length: Optional[float] = None
    section_y_axis: Optional[tuple] = None

    def __post_init__(self):
        for fld in ("axis", "section_y_axis"):
            v = getattr(self, fld)
            if v is not None and not isinstance(v, (str, bytes)) and np.ndim(v) == 1:
                object.__setattr__(self, fld, tuple(np.asarray(v).tolist()))


@dataclass(frozen=True)
class UrdfReadResult:
    """What :func:`load_urdf` made of a URDF.

    model        : the validated gpme Model
    notes        : what was ignored or changed, one line per class of element (friction,
                   limits, extension tags, replaced inertias, merged branches, ...)
    frozen       : {URDF joint name: value (rad or m)} of every joint frozen off the chain
    chain        : (root link, tip link) actually used
    chain_joints : the URDF joints that are the model's coordinates, in order (before any
                   RFEM coordinates are inserted; the model's coordinate_names has those)
    frames       : the model's named frames (every link merged into a chain link)
    """

    model: Model
    notes: tuple
    frozen: Mapping[str, float]
    chain: tuple
    chain_joints: tuple
    frames: tuple


FlexibleSpec = Union[FlexibleLink, tuple]


# ============================================================================ parsing
@dataclass
class _Joint:
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


class _Notes:
    """Names per class of ignored element, formatted once at the end."""

    def __init__(self):
        self._names = {}
        self._free = []

    def add(self, key: str, name: str) -> None:
        names = self._names.setdefault(key, [])
        if name not in names:
            names.append(name)

    def line(self, text: str) -> None:
        self._free.append(text)

    def lines(self) -> tuple:
        out = []
        for key, names in self._names.items():
            n = len(names)
            out.append(_NOTE_TEXT[key].format(n=n, s="" if n == 1 else "s")
                       + ", ".join(names))
        return tuple(out + self._free)


_NOTE_TEXT = {
    "friction": "<dynamics friction> on {n} joint{s} ignored (gpme has no Coulomb friction): ",
    "effort": "effort/velocity <limit> on {n} joint{s} ignored (gpme has no actuator limits): ",
    "equal_limits": "<limit lower == upper> on {n} joint{s} read as no range (unlimited; "
                    "URDF's default lower = upper = 0 when a <limit> gives only effort and "
                    "velocity): ",
    "safety": "<safety_controller> on {n} joint{s} ignored (controller settings, not "
              "dynamics): ",
    "calibration": "<calibration> on {n} joint{s} ignored (encoder reference, not dynamics): ",
    "mimic_fixed": "<mimic> on {n} joint{s} ignored (a fixed joint does not move): ",
    "visual": "<visual>/<collision> on {n} link{s} ignored (geometry; gpme needs only mass "
              "properties): ",
    "tags": "extension elements of {n} kind{s} ignored (not URDF dynamics): ",
    "axis": "<axis xyz> not of unit length on {n} joint{s}, normalised (as URDF readers "
            "do): ",
}


def _floats(text, count, label, problems, default, infinite=False):
    """(count,) floats of an attribute's text (``default`` when absent or invalid: the
    problem, naming the attribute, the text and what would be valid, is appended);
    ``infinite``: +-inf is valid (limits), NaN never is."""
    if text is None:
        return np.array(default, dtype=float)
    try:
        v = np.array([float(s) for s in text.split()], dtype=float)
    except ValueError:
        v = None
    if v is None or v.shape != (count,) or \
            not np.all(~np.isnan(v) if infinite else np.isfinite(v)):
        shown = repr(text) if len(text) <= 80 else f"{text[:80]!r}... ({len(text)} characters)"
        if count == 1:
            what = "number (inf allowed)" if infinite else "finite number"
            problems.append(f"{label}: expected 1 {what}, got {shown}")
        else:
            problems.append(f"{label}: expected {count} finite numbers, got {shown} (write "
                            f"{count} decimal numbers separated by spaces)")
        return np.array(default, dtype=float)
    return v


def _origin_transform(el, label, problems):
    """(4, 4) parent -> child transform of an element's <origin> (identity if absent)."""
    o = el.find("origin")
    if o is None:
        return np.eye(4)
    xyz = _floats(o.get("xyz"), 3, f"{label} <origin xyz>", problems, (0, 0, 0))
    rpy = _floats(o.get("rpy"), 3, f"{label} <origin rpy>", problems, (0, 0, 0))
    return tf.homogeneous(tf.rpy_to_rotation(*rpy), xyz)


def _read_inertial(link_el, problems, link_label):
    """RigidBodyInertia of a <link> in the link frame, or None (no inertial, zero mass and
    zero tensor, or invalid: the problem is appended, starting with ``link_label``)."""
    el = link_el.find("inertial")
    if el is None:
        return None
    label = f"{link_label} <inertial>"
    t = _origin_transform(el, label, problems)
    mass_el, inertia_el = el.find("mass"), el.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    bad = []
    if mass_el is None:
        bad.append(f"{label}: missing <mass value=...>")
    if inertia_el is None:
        bad.append(f"{label}: missing <inertia {' '.join(keys)}>")
    if bad:
        problems.extend(bad)
        return None
    n_before = len(problems)
    if mass_el.get("value") is None:
        problems.append(f"{label}: <mass> without value=... (kg)")
    missing = [k for k in keys if inertia_el.get(k) is None]
    if missing:
        problems.append(f"{label}: <inertia> without {', '.join(missing)} (kg m^2; URDF "
                        f"needs all six: {', '.join(keys)})")
    mass = float(_floats(mass_el.get("value"), 1, f"{label} <mass value>", problems,
                         (np.nan,))[0])
    vals = [_floats(inertia_el.get(k), 1, f"{label} <inertia {k}>", problems, (np.nan,))[0]
            for k in keys]
    if len(problems) > n_before:
        return None
    ixx, ixy, ixz, iyy, iyz, izz = vals
    i_com = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    with np.errstate(over="ignore", invalid="ignore"):
        size = abs(mass) * float(t[:3, 3] @ t[:3, 3]) + float(np.abs(i_com).sum())
    if not size < _MAGNITUDE:
        problems.append(f"{label}: mass {mass!r} kg, centre of mass {t[:3, 3].tolist()} m and "
                        f"inertia {[float(v) for v in vals]} kg m^2 give an inertia of "
                        f"{size:.3g} kg m^2 about the link frame, too large to compute with "
                        f"(at most {_MAGNITUDE:g}; real machines have < 1e12): check the units "
                        "(kg, m, kg m^2)")
        return None
    r = t[:3, :3]
    inertia = RigidBodyInertia(mass, t[:3, 3], r @ i_com @ r.T)
    bad = inertia.problems(label)
    if bad:
        # the tensor as written, not rotated, is what the user can find in the file
        problems.extend(b.replace(str(np.linalg.eigvalsh(r @ i_com @ r.T).tolist()),
                                  str(np.linalg.eigvalsh(i_com).tolist())) for b in bad)
        return None
    if mass == 0.0 and not np.any(i_com):
        return None                   # the usual way of writing "no mass"
    return inertia


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
    e = el.find(end)
    return None if e is None else e.get("link")


def _read_joint(el, link_names, problems, notes):
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
    damping = 0.0
    limits, raw = (-np.inf, np.inf), None
    mimic = None
    for child in el:
        if child.tag not in _JOINT_CHILDREN and isinstance(child.tag, str):
            notes.add("tags", f"<{child.tag}> in joint {name!r}")
    if jtype in _MOVING:
        limits, raw = _read_limits(el, jtype, label, problems, notes)
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
            axis = np.array((1.0, 0.0, 0.0))
        else:
            axis = axis / scale
            norm = float(np.linalg.norm(axis))
            if abs(norm * scale - 1.0) > _UNIT_TOL:
                notes.add("axis", name)
            axis = axis / norm
    dyn = el.find("dynamics")
    if dyn is not None:
        damping = float(_floats(dyn.get("damping", "0"), 1, f"{label} <dynamics damping>",
                                problems, (0,))[0])
        friction = float(_floats(dyn.get("friction", "0"), 1, f"{label} <dynamics friction>",
                                 problems, (0,))[0])
        if damping < 0:
            problems.append(f"{label}: <dynamics damping> must be >= 0 (N m s/rad or N s/m), "
                            f"got {damping!r}")
            damping = 0.0                 # reported here, not again by the built model
        if friction != 0.0:
            notes.add("friction", name)
    if el.find("safety_controller") is not None:
        notes.add("safety", name)
    if el.find("calibration") is not None:
        notes.add("calibration", name)
    mim = el.find("mimic")
    if mim is not None:
        if jtype == "fixed":
            notes.add("mimic_fixed", name)
        elif not mim.get("joint"):
            problems.append(f"{label}: <mimic> without joint=...")
        else:
            mult = float(_floats(mim.get("multiplier"), 1, f"{label} <mimic multiplier>",
                                 problems, (1.0,))[0])
            off = float(_floats(mim.get("offset"), 1, f"{label} <mimic offset>", problems,
                                (0.0,))[0])
            mimic = (mim.get("joint"), mult, off)
    return _Joint(name, jtype, ends["parent"], ends["child"], origin, axis, damping, limits,
                  raw, mimic)


@dataclass
class _Parsed:
    """What the elements of <robot> say, each checked on its own."""

    links: list               # link names, in file order
    inertias: dict            # link -> RigidBodyInertia or None (none, zero, or invalid)
    joints: list              # _Joint of every joint with a name and a known type
    bad_inertia: dict         # link -> [problems of its <inertial>]
    geometry_only: list       # links with <visual>/<collision> but no <inertial>
    left_out: list            # joints not in the tree: no name, unknown type, bad ends


def _parse(robot, problems, notes) -> _Parsed:
    """Every <link> and <joint> of <robot>, their problems appended; the caller decides
    whether an <inertial> problem or a missing <inertial> matters (not on a link fixed to
    the world, whose mass is dropped)."""
    if robot.tag != "robot":
        problems.append(f"the root element must be <robot>, got <{robot.tag}>")
    for child in robot:
        if isinstance(child.tag, str) and child.tag not in _ROBOT_CHILDREN:
            notes.add("tags", f"<{child.tag}>")
    link_els = robot.findall("link")
    link_names = [el.get("name") for el in link_els]
    for k, n in enumerate(link_names):
        if n is None or not n.strip():
            what = "no name attribute" if n is None else f"an empty name {n!r}"
            problems.append(f"<link> #{k + 1} has {what}: every link needs name=...")
            link_names[k] = None
    dup = sorted(n for n, k in Counter(link_names).items() if n is not None and k > 1)
    if dup:
        problems.append(f"link names repeat: {dup}")
    inertias, bad_inertia, geometry_only = {}, {}, []
    for k, (el, name) in enumerate(zip(link_els, link_names), start=1):
        if name is None:                  # reported; its <inertial> is still checked
            _read_inertial(el, problems, f"<link> #{k} (no name)")
            continue
        bad = []
        inertias[name] = _read_inertial(el, bad, f"link {name!r}")
        if bad:
            bad_inertia[name] = bad
        if el.find("visual") is not None or el.find("collision") is not None:
            notes.add("visual", name)
            if el.find("inertial") is None:
                geometry_only.append(name)
        for child in el:
            if isinstance(child.tag, str) and child.tag not in _LINK_CHILDREN:
                notes.add("tags", f"<{child.tag}> in link {name!r}")
    names = {n for n in link_names if n is not None}
    joints, left_out = [], []
    for k, el in enumerate(robot.findall("joint"), start=1):
        j = _read_joint(el, names, problems, notes)
        if j is not None:
            joints.append(j)
        if j is None or j.parent not in names or j.child not in names:
            left_out.append(el.get("name") or f"<joint> #{k} (no name)")
    jnames = [j.name for j in joints]
    dup = sorted(n for n, k in Counter(jnames).items() if k > 1)
    if dup:
        problems.append(f"joint names repeat: {dup}")
    return _Parsed([n for n in link_names if n is not None], inertias, joints, bad_inertia,
                   geometry_only, left_out)


# ============================================================================ the tree
# what a failed stage leaves unchecked, said at the end of its problem
_TREE_SKIPPED = ("; not checked because of it: the chain, frozen joints, the side file "
                 "against the URDF, flexible links and the assembled model (they need one "
                 "tree)")
_CHAIN_SKIPPED = ("; not checked because of it: frozen joints, the side file against the "
                  "URDF, flexible links and the assembled model (they need a chain)")


@dataclass
class _Tree:
    root: str
    children: dict            # link -> [joints]
    parent_joint: dict        # link -> joint


_TREE_RULE = ("a URDF is a tree: every link but the root is the child of exactly one joint, "
              "and no joint leads back to a link above its parent")


def _first_cycle(links, joints) -> Optional[list]:
    """The joints of the first directed cycle of links -> child links (in cycle order, the
    joint that closes it last), or None; an iterative depth-first search that visits each
    link and joint once."""
    out = {n: [] for n in links}
    for j in joints:
        if j.parent in out and j.child in out:
            out[j.parent].append(j)
    state = {}                       # link -> 1 on the current path, 2 finished
    for start in links:
        if start in state:
            continue
        path = []                    # joints from start to the link on top of the stack
        stack = [(start, iter(out[start]))]
        state[start] = 1
        while stack:
            link, todo = stack[-1]
            j = next(todo, None)
            if j is None:
                state[link] = 2
                stack.pop()
                if path:
                    path.pop()
                continue
            if state.get(j.child) == 1:          # back to a link on the path: a cycle
                if j.child == link:
                    return [j]
                first = next(k for k, p in enumerate(path) if p.parent == j.child)
                return path[first:] + [j]
            if j.child not in state:
                state[j.child] = 1
                path.append(j)
                stack.append((j.child, iter(out[j.child])))
    return None


# names listed in a tree problem: a hostile URDF may give thousands (a 50 000-link cycle)
_LISTED = 12


def _listed(names) -> str:
    """['a', 'b', ...] of a list of names; past _LISTED names the first and last few and
    the count."""
    names = list(names)
    if len(names) <= _LISTED:
        return str(names)
    half = _LISTED // 2
    return (str(names[:half])[:-1] + ", ..., " + str(names[-half:])[1:]
            + f" ({len(names)} in all)")


def _cycle_problem(cycle) -> str:
    closing = cycle[-1]
    links = [closing.child] + [j.child for j in cycle]
    if len(links) > _LISTED:
        half = _LISTED // 2
        links = links[:half] + [f"... ({len(cycle) - _LISTED + 1} more links)"] + links[-half:]
    return (f"joint {closing.name!r} (parent {closing.parent!r}, child {closing.child!r}) "
            f"closes a cycle {' -> '.join(links)} through joints "
            f"{_listed(j.name for j in cycle)}")


def _tree(links, joints, problems, left_out=()):
    """The tree of ``links`` through ``joints``, or None with the problems appended: a link
    that is the child of several joints, a cycle of joints (the first found, with its
    joints), no single root, links not reached from the root.  Every check visits each link
    and joint a bounded number of times; nothing walks the joints before they are known to
    form a tree.  ``left_out``: joints not in it (named in the problem)."""
    why = (f" (joints {left_out} are left out of the tree because of their problems above)"
           if left_out else "")
    if not links:
        problems.append("the URDF has no <link> (a <robot> needs at least one <link name=...>)"
                        + _TREE_SKIPPED)
        return None
    children = {n: [] for n in links}
    parents = {}                      # link -> [joints whose child it is]
    for j in joints:
        if j.parent in children and j.child in children:
            children[j.parent].append(j)
            parents.setdefault(j.child, []).append(j)
    found = [f"link {link!r} is the child of {len(js)} joints {_listed(j.name for j in js)}"
             for link, js in parents.items() if len(js) > 1]
    cycle = _first_cycle(links, joints)
    if cycle is not None:
        found.append(_cycle_problem(cycle))
    if found:
        found[-1] += f"; {_TREE_RULE}"
    roots = [n for n in links if n not in parents]
    if len(roots) != 1:
        loop = "; every link is some joint's child, so the joints form a loop" if not roots \
            else ""
        found.append(f"the URDF must have exactly one root link (a link that is no joint's "
                     f"child), found {_listed(roots)}{loop}{why}")
    else:
        reached, todo = {roots[0]}, [roots[0]]
        while todo:
            for j in children[todo.pop()]:
                if j.child not in reached:
                    reached.add(j.child)
                    todo.append(j.child)
        lost = [n for n in links if n not in reached]
        if lost:
            found.append(f"links {_listed(lost)} are not connected to the root link "
                         f"{roots[0]!r} (a cycle of joints?){why}")
    if found:
        found[-1] += _TREE_SKIPPED
        problems.extend(found)
        return None
    return _Tree(roots[0], children, {link: js[0] for link, js in parents.items()})


def _path(tree, top, bottom):
    """Joints from link ``top`` down to link ``bottom`` (None if bottom is not below top);
    at most one step per link, whatever the tree holds."""
    out, link = [], bottom
    for _ in range(len(tree.children) + 1):
        if link == top:
            return out[::-1]
        j = tree.parent_joint.get(link)
        if j is None:
            return None
        out.append(j)
        link = j.parent
    return None


def _subtree_joints(tree, link):
    """Joints below link ``link`` (depth first); each link is entered once."""
    out, stack, seen = [], [link], {link}
    while stack:
        for j in tree.children[stack.pop()]:
            out.append(j)
            if j.child not in seen:
                seen.add(j.child)
                stack.append(j.child)
    return out


def _select_chain(tree, chain, frozen, problems):
    """(root, tip, chain joints) or None; appends the problems of the chain choice."""
    root, tip = tree.root, None
    if chain is not None:
        if isinstance(chain, str) or not isinstance(chain, Sequence) or not 1 <= len(chain) <= 2:
            problems.append(f"chain must be (root link, tip link) or (root link,), got {chain!r}")
            return None
        root = tree.root if chain[0] is None else chain[0]
        tip = chain[1] if len(chain) == 2 else None
        bad = [f"{what} {name!r}" for what, name in (("root", root), ("tip", tip))
               if name is not None and name not in tree.children]
        if bad:
            problems.append(f"chain {', '.join(bad)}: not a link of the file; links: "
                            f"{sorted(tree.children)}")
            return None
    if tip is None:
        candidates = [j for j in _subtree_joints(tree, root) if j.moving and j.name not in frozen]
        if not candidates:
            problems.append(f"no revolute, continuous or prismatic joint below link {root!r} "
                            "(frozen joints do not count)")
            return None
        names = {j.name for j in candidates}
        leaves = [j for j in candidates
                  if not any(k.name in names for k in _subtree_joints(tree, j.child))]
        if len(leaves) > 1:
            ends = [j.child for j in leaves]
            problems.append(f"the moving joints below link {root!r} lie on {len(ends)} "
                            f"branches ending at links {ends}: choose one with "
                            f"chain=({root!r}, <tip link>); the joints off it are frozen "
                            "(frozen={name: value}, default 0)")
            return None
        tip = leaves[0].child
    path = _path(tree, root, tip)
    if path is None:
        problems.append(f"chain tip {tip!r} is not below the chain root {root!r} (the path "
                        f"from the URDF root {tree.root!r} to {tip!r} is "
                        f"{[j.name for j in _path(tree, tree.root, tip)]})")
        return None
    moving = [j for j in path if j.moving]
    if not moving:
        problems.append(f"the chain {root!r} -> {tip!r} has no revolute, continuous or "
                        "prismatic joint")
        return None
    return root, tip, moving


def _frozen_values(tree, joints, chain_joints, above, frozen, problems, notes):
    """{joint: value} of every moving joint off the chain (given, mimicked or 0)."""
    by_name = {j.name: j for j in joints}
    on_chain = {j.name for j in chain_joints}
    values = {}
    for name, v in frozen.items():
        j = by_name.get(name)
        off = sorted(k.name for k in joints if k.moving and k.name not in on_chain)
        if j is None:
            problems.append(f"frozen joint {name!r}: no such joint; moving joints off the "
                            f"chain: {off}")
            continue
        if not j.moving:
            problems.append(f"frozen joint {name!r} is a fixed joint (nothing to freeze)")
            continue
        if name in on_chain:
            problems.append(f"frozen joint {name!r} is on the chain (a gpme coordinate); "
                            "choose another chain or do not freeze it")
            continue
        if j.type in _UNSUPPORTED:
            problems.append(f"frozen joint {name!r}: a {j.type} joint off the chain is frozen "
                            "at its origin; a value cannot be given")
            continue
        try:
            x = float(v)
        except (TypeError, ValueError):
            x = math.nan
        if not math.isfinite(x):
            problems.append(f"frozen joint {name!r}: value must be a finite number (rad or m), "
                            f"got {v!r}")
            continue
        lo, hi = j.limits
        if not lo <= x <= hi:
            unit = "m" if j.type == "prismatic" else "rad"
            problems.append(f"frozen joint {name!r} = {x!r} {unit} is outside its <limit> "
                            f"[{lo!r}, {hi!r}]")
            continue
        values[name] = x
    for j in above:
        if j.moving and j.name not in frozen:
            problems.append(f"joint {j.name!r} ({j.type}) lies above the chain root and would "
                            f"move the whole chain: freeze it with frozen={{{j.name!r}: value}} "
                            "or start the chain higher")
    for j in chain_joints:
        if j.mimic is not None:
            problems.append(f"joint {j.name!r} on the chain mimics {j.mimic[0]!r}: every gpme "
                            "coordinate is independent; choose a chain without it or freeze "
                            "it off the chain")
        if j.type in _UNSUPPORTED:
            problems.append(f"joint {j.name!r} on the chain: type {j.type!r} is not supported "
                            f"({_UNSUPPORTED[j.type]}); gpme coordinates are revolute or "
                            "prismatic")
    defaults, mimicked, outside, unsupported = [], [], [], []
    todo = [j for j in joints if j.moving and j.name not in on_chain and j.name not in values
            and j.name not in frozen]
    for _ in range(len(todo) + 1):          # mimic of a mimic: resolve in passes
        left = []
        for j in todo:
            if j.type in _UNSUPPORTED:
                values[j.name] = 0.0
                unsupported.append(j.name)
            elif j.mimic is None:
                values[j.name] = 0.0
                defaults.append(j.name)
            elif j.mimic[0] in values:
                src, mult, off = j.mimic
                values[j.name] = mult * values[src] + off
                mimicked.append(f"{j.name} = {mult!r} * {src} + {off!r} = {values[j.name]!r}")
            else:
                left.append(j)
        if len(left) == len(todo):
            break
        todo = left
    for j in todo:
        src = j.mimic[0]
        why = ("is on the chain" if src in on_chain else
               "is not a joint of the file" if src not in by_name else "cannot be resolved")
        problems.append(f"joint {j.name!r} off the chain mimics {src!r}, which {why}: give "
                        f"its value with frozen={{{j.name!r}: value}}")
    for name in defaults:
        lo, hi = by_name[name].limits
        if not lo <= 0.0 <= hi:
            outside.append(f"{name} [{lo:g}, {hi:g}]")
    if defaults:
        notes.line(f"{len(defaults)} joints off the chain frozen at the default 0 (rad or m): "
                   + ", ".join(defaults))
    if outside:
        notes.line(f"the default 0 is outside the <limit> of frozen joints "
                   f"{', '.join(outside)}: give their values in frozen= if it matters")
    if mimicked:
        notes.line("mimic joints off the chain frozen where they follow the joint they mimic "
                   "(multiplier * value + offset): " + "; ".join(mimicked))
    if unsupported:
        notes.line("floating/planar joints off the chain frozen at their origin: "
                   + ", ".join(unsupported))
    return values


# ============================================================================ flexible links
def _vector(v, label, problems):
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (3,) or not np.all(np.isfinite(a)):
        problems.append(f"{label}: expected 3 finite numbers, got {v!r}")
        return None
    return a


def _beam_plan(name, spec, t_next, problems):
    """(BeamProperties, n_segments, (4, 4) beam frame in the link frame) or None.

    t_next: (4, 4) link frame -> next chain joint frame at q = 0, None at the chain tip.
    """
    label = f"flexible link {name!r}"
    if isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[0], BeamProperties):
        beam, n = spec
        bad = beam.problems(label)
        if not isinstance(n, (int, np.integer)) or isinstance(n, bool) \
                or not 0 <= n <= MAX_SEGMENTS:
            bad.append(f"{label}: n_segments must be an integer from 0 to {MAX_SEGMENTS}, "
                       f"got {n!r}")
        problems.extend(bad)
        return None if bad else (beam, int(n), np.eye(4))
    if not isinstance(spec, FlexibleLink):
        problems.append(f"{label}: expected a FlexibleLink or (BeamProperties, n_segments), "
                        f"got {spec!r}")
        return None
    bad = []
    if not isinstance(spec.section, BeamSection):
        bad.append(f"{label}: section must be a gpme_core.rfem.BeamSection (solid_circle, "
                   f"tube, rectangle), got {type(spec.section).__name__}")
    n = spec.n_segments
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) \
            or not 0 <= n <= MAX_SEGMENTS:
        bad.append(f"{label}: n_segments must be an integer from 0 to {MAX_SEGMENTS}, "
                   f"got {n!r}")
    p = None if t_next is None else t_next[:3, 3]
    if spec.axis is not None:
        x = _vector(spec.axis, f"{label} axis", bad)
        if x is not None and abs(np.linalg.norm(x) - 1.0) > _UNIT_TOL:
            bad.append(f"{label}: axis must be a unit vector in the link frame, got "
                       f"{x.tolist()} (norm {np.linalg.norm(x)!r})")
            x = None
    elif p is None:
        bad.append(f"{label}: it is the chain tip (no next chain joint): give axis= (unit, "
                   "link frame) and length= (m)")
        x = None
    elif np.linalg.norm(p) == 0.0:
        bad.append(f"{label}: the next chain joint's frame is at the link origin, so the "
                   "beam axis is undefined: give axis= (unit, link frame) and length= (m)")
        x = None
    else:
        x = p / np.linalg.norm(p)
    length = spec.length
    if length is None and x is not None:
        if p is None:
            if spec.axis is not None:
                bad.append(f"{label}: it is the chain tip (no next chain joint): give length= (m)")
        else:
            length = float(p @ x)
            if not length > 0.0:
                bad.append(f"{label}: the next chain joint lies {length!r} m along the given "
                           "axis; give length= (m) or an axis pointing towards it")
    y = None
    if x is not None:
        if spec.section_y_axis is not None:
            s = _vector(spec.section_y_axis, f"{label} section_y_axis", bad)
            if s is not None:
                y = s - (s @ x) * x
                if np.linalg.norm(y) <= _PARALLEL_TOL * np.linalg.norm(s):
                    bad.append(f"{label}: section_y_axis {s.tolist()} is parallel to the beam "
                               f"axis {x.tolist()} (or zero)")
                    y = None
        else:
            y = np.array((0.0, 1.0, 0.0)) - x[1] * x
            if np.linalg.norm(y) <= _PARALLEL_TOL:
                y = np.array((0.0, 0.0, 1.0)) - x[2] * x
    if isinstance(spec.section, BeamSection):
        # material constants and the length, whether or not the geometry is complete
        probe = BeamProperties.from_section(1.0 if length is None else length, spec.section,
                                            spec.youngs_modulus, spec.shear_modulus,
                                            spec.density, spec.bending_viscosity,
                                            spec.torsion_viscosity)
        bad += probe.problems(label)
    problems.extend(bad)
    if bad or x is None or y is None or length is None:
        return None
    y = y / np.linalg.norm(y)
    frame = tf.homogeneous(np.column_stack((x, y, np.cross(x, y))), np.zeros(3))
    beam = BeamProperties.from_section(float(length), spec.section, spec.youngs_modulus,
                                       spec.shear_modulus, spec.density,
                                       spec.bending_viscosity, spec.torsion_viscosity)
    return beam, int(n), frame


# ============================================================================ reading
def load_urdf(path, *, side_file="auto", chain=None, frozen=None, flexible=None,
              massless_links=(), gravity=None, name=None) -> UrdfReadResult:
    """Read the URDF at ``path`` into a gpme Model, through a chosen chain.

    side_file     : "auto" (``<stem>.gpme.json`` beside the URDF if it exists), None (no
                    side file: stiffness 0, gravity standard) or a path.  It restores
                    stiffness, spring references, gravity, drives and RFEM records.
    chain         : (root link, tip link); None = from the URDF root to the single path of
                    moving joints (error listing the branch ends when there are several).
    frozen        : {joint name: value (rad or m)} for joints off the chain; every other
                    moving joint off the chain is frozen at 0 (a mimic joint: multiplier *
                    value + offset of the joint it mimics).  Joints above the chain root
                    must be listed here.
    flexible      : {link name: FlexibleLink(...)} (or the older (BeamProperties, n)
                    along +x); the link's <inertial> is replaced by the RFEM beam.
    massless_links: moving links expected to carry no mass (no note for them, and a link
                    with geometry but no <inertial> is then accepted); a massless chain
                    link is accepted whenever M stays positive definite.
    gravity       : (3,) m/s^2 in the URDF root (= gpme world) frame; None: the side
                    file's, else (0, 0, -9.81).
    name          : model name; None: the side file's, else the URDF robot name.

    Returns an :class:`UrdfReadResult`; raises ModelFileError listing every problem found
    in one read: the XML, the side file (every key and record), the links' inertials, the
    joints, the tree, the chain choice, frozen values, flexible specs, the side file
    against the URDF and the built model.  A stage that cannot run because an earlier one
    failed (no tree, no chain) is named in the problem that stopped it.
    """
    path = Path(path)
    source = str(path)
    problems = []
    try:
        data = read_input_file(path, "URDF", URDF_LIMIT)
    except InputFileError as exc:
        data = None
        problems.append(f"cannot read the URDF: it {exc.reason}; a URDF is an XML file "
                        "<robot name=...> with <link> and <joint> elements")
    side = None
    if side_file == "auto":
        if side_file_path(path).exists():
            side, bad = read_side_file(side_file_path(path))
            problems += bad
    elif side_file is not None:
        side, bad = read_side_file(side_file)
        problems += bad
    return _read_guarded(data, side, problems, chain=chain, frozen=frozen, flexible=flexible,
                         massless_links=massless_links, gravity=gravity, name=name,
                         source=source)


def read_urdf(path, side_file="auto", flexible=None, massless_links=(), gravity=None,
              name=None, *, chain=None, frozen=None) -> Model:
    """The Model of :func:`load_urdf` (same arguments), without the report."""
    return load_urdf(path, side_file=side_file, chain=chain, frozen=frozen, flexible=flexible,
                     massless_links=massless_links, gravity=gravity, name=name).model


def parse_urdf(text, side=None, flexible=None, massless_links=(), gravity=None, name=None,
               source="<urdf>", *, chain=None, frozen=None) -> Model:
    """:func:`read_urdf` on URDF ``text`` (str or bytes) and a side-file dict ``side`` (or
    None)."""
    problems = []
    if side is not None:
        side, problems = check_side_file(side)
    return _read_guarded(text, side, problems, chain=chain, frozen=frozen, flexible=flexible,
                         massless_links=massless_links, gravity=gravity, name=name,
                         source=source).model


def _fail(source, problems):
    raise ModelFileError([p if p.startswith(source) or p.startswith("side file")
                          else f"{source}: {p}" for p in problems])


def _read_guarded(text, side, problems, **kwargs) -> UrdfReadResult:
    """:func:`_read`, with any exception that escaped the checks turned into a
    ModelFileError naming the file, the exception and every problem found before it
    (the checks are meant to catch every malformed input first; this is the net)."""
    source = kwargs["source"]
    try:
        return _read(text, side, problems, **kwargs)
    except ModelFileError:
        raise
    except ModelError as exc:
        _fail(source, problems + list(exc.problems))
    except (ArithmeticError, AttributeError, LookupError, TypeError, ValueError,
            RecursionError) as exc:
        _fail(source, problems + [
            f"reading stopped at an unexpected {type(exc).__name__} ({exc}): a malformed "
            "input gpme's URDF checks do not name yet; the problems above were found "
            "before it (please report the file)"])


def _read(text, side, problems, *, chain, frozen, flexible, massless_links, gravity, name,
          source) -> UrdfReadResult:
    notes = _Notes()
    robot = None
    if text is not None:
        try:
            robot = ET.fromstring(text)
        except ET.ParseError as exc:
            line, column = exc.position
            problems.append(f"not well-formed XML at line {line}, column {column + 1} ("
                            f"{_xml_error(exc)}); nothing else in the URDF could be checked")
    if robot is None:
        _fail(source, problems)
    frozen = dict(frozen or {})
    flexible = dict(flexible or {})
    side = side or {}
    parsed = _parse(robot, problems, notes)
    links, inertias, joints = parsed.links, parsed.inertias, parsed.joints
    bad_inertia, geometry_only = parsed.bad_inertia, parsed.geometry_only
    tree = _tree(links, joints, problems, parsed.left_out)
    picked = _select_chain(tree, chain, frozen, problems) if tree is not None else None
    if picked is None:
        if tree is not None:
            problems[-1] += _CHAIN_SKIPPED
        _fail(source, [p for bad in bad_inertia.values() for p in bad] + problems)
    root, tip, chain_joints = picked
    above = _path(tree, tree.root, root)
    values = _frozen_values(tree, joints, chain_joints, above, frozen, problems, notes)
    chain_index = {j.name: k for k, j in enumerate(chain_joints)}
    chain_names = [j.name for j in chain_joints]

    # owner chain index of every link (-1: fixed to the world) and its pose in that link
    owner, pose, attached = {tree.root: -1}, {tree.root: np.eye(4)}, {}
    chain_origin = {}
    stack, seen = deque([tree.root]), {tree.root}
    while stack:
        link = stack.popleft()
        for j in tree.children[link]:
            if j.child in seen:           # not in a tree (_tree refuses it); defence in depth
                continue
            seen.add(j.child)
            if j.name in chain_index:
                k = chain_index[j.name]
                chain_origin[k] = pose[link] @ j.origin
                owner[j.child], pose[j.child] = k, np.eye(4)
            else:
                owner[j.child] = owner[link]
                pose[j.child] = pose[link] @ j.origin @ j.motion(values.get(j.name, 0.0))
                attached.setdefault(owner[link], []).append(j.child)
            stack.append(j.child)
    chain_links = [j.child for j in chain_joints]
    world_fixed_bad = [lk for lk in bad_inertia if owner.get(lk) == -1]
    for lk, bad in bad_inertia.items():
        if lk not in world_fixed_bad:
            problems.extend(bad)
    if world_fixed_bad:
        notes.line("invalid <inertial> on links fixed to the world ignored (they do not move, "
                   "their mass is dropped): " + "; ".join(
                       p for lk in world_fixed_bad for p in bad_inertia[lk]))
    side_massless = list(side.get("massless_links", []))
    allowed_massless = set(massless_links) | set(side_massless)
    for lk in geometry_only:
        k = owner.get(lk, -1)
        if k >= 0 and lk not in allowed_massless and lk not in flexible:
            problems.append(
                f"link {lk!r} has <visual>/<collision> geometry but no <inertial>, and it "
                f"moves (with joint {chain_joints[k].name!r}): its mass would be read as 0; "
                "give it an <inertial> (mass in kg, inertia in kg m^2 about its centre of "
                "mass), or an explicit zero <inertial> (mass 0, all six moments 0) if it "
                "truly carries no mass")

    dropped = [f"{lk} ({inertias[lk].mass:g} kg)" for lk in owner
               if owner[lk] == -1 and inertias.get(lk) is not None]
    if dropped:
        notes.line("links fixed to the world (they do not move; their mass has no effect on "
                   "the dynamics) dropped: " + ", ".join(dropped))
    frozen_joints = [j for j in joints if j.name in values]
    for k, lk in enumerate(chain_links):
        branch = [j.name for j in frozen_joints if owner.get(j.parent) == k]
        if branch:
            moved = [x for x in attached.get(k, []) if inertias.get(x) is not None]
            notes.line(f"frozen joints {branch} hang on chain link {lk!r}: the links below "
                       f"them merged into it as mass and frames ({len(moved)} with mass)")

    # the side file against the URDF (its own problems were found on reading it)
    side_joints = side.get("joints", {})
    unknown = sorted(set(side_joints) - set(chain_index))
    if unknown:
        problems.append(f"the side file gives springs for joints {unknown} that are not moving "
                        f"joints of the chain {chain_names}")
    side_drives = []
    for rec in side.get("drives", []):
        if rec["joint"] in chain_index:
            side_drives.append(rec)
        else:
            problems.append(f"the side file's drive record on {rec['joint']!r} "
                            f"({rec['function']}): not a moving joint of the chain "
                            f"{chain_names}")
    unknown = [lk for lk in side_massless if lk not in tree.children]
    if unknown:
        problems.append(f"the side file's massless_links {unknown} are not links of the URDF")
    side_flex = {}
    for rec in side.get("flexible_links", []):
        lost = ([f"joint {j!r}" for j in rec["joints"] if j not in chain_index]
                + [f"link {lk!r}" for lk in rec["links"] if lk not in chain_links])
        if lost:
            problems.append(f"the side file's flexible link record {rec['name']!r} names "
                            f"{', '.join(lost)}, not in the chain (joints {chain_names}, "
                            f"links {chain_links})")
        else:
            side_flex[rec["name"]] = rec
    plans = {}
    for lk, spec in flexible.items():
        if lk not in chain_links:
            problems.append(f"flexible link {lk!r}: not a link moved by a joint of the chain "
                            f"(moving links: {chain_links})")
            continue
        if lk in side_flex and side_flex[lk]["n_segments"] > 0:
            problems.append(f"flexible link {lk!r}: already RFEM-discretised with "
                            f"{side_flex[lk]['n_segments']} segments in this file; read the "
                            "rigid model to re-discretise it")
            continue
        k = chain_links.index(lk)
        plans[lk] = _beam_plan(lk, spec, chain_origin.get(k + 1), problems)
    massless = [lk for k, lk in enumerate(chain_links) if lk not in allowed_massless
                and lk not in flexible and inertias.get(lk) is None and lk not in bad_inertia
                and lk not in geometry_only
                and all(inertias.get(x) is None for x in attached.get(k, []))]
    if massless:
        notes.line("chain links without mass (accepted: the mass matrix is checked positive "
                   "definite): " + ", ".join(massless))

    size_problem = _size_problem(tree, owner, inertias)
    if size_problem:
        problems.append(size_problem)
        _fail(source, problems)

    # build (also when earlier problems exist, to report the model's own problems too)
    g = gravity if gravity is not None else side.get("gravity", STANDARD_GRAVITY)
    robot_name = (robot.get("name") or "").strip()
    if not (name or side.get("model") or robot_name):
        notes.line("<robot> without a name: the model is named 'urdf'")
    builder = ChainBuilder(name or side.get("model") or robot_name or "urdf", gravity=g)
    frames = []
    model = None
    try:
        after = np.eye(4)       # correction of the previous link's frame (beam tip)
        for k, j in enumerate(chain_joints):
            spring = side_joints.get(j.name, {})
            builder.add_joint(j.name, _MOVING.get(j.type, REVOLUTE), j.axis,
                              origin=after @ chain_origin[k],
                              stiffness=spring.get("stiffness", 0.0),
                              spring_reference=spring.get("spring_reference", 0.0),
                              damping=j.damping, link=j.child, limits=j.limits)
            after = np.eye(4)
            lk = j.child
            plan = plans.get(lk)
            if lk in flexible and plan is None:
                # the spec has problems (reported): build it rigid so that the model's own
                # problems, if any, are not artefacts of the missing beam
                if inertias.get(lk) is not None:
                    builder.add_body(inertias[lk])
            elif lk in flexible:
                if plan is not None:
                    beam, n, t_beam = plan
                    builder.add_beam(lk, beam, n, frame=t_beam)
                    after = tf.inverse(t_beam @ tf.translation(beam.length))
                    was = inertias.get(lk)
                    notes.line(f"link {lk}: URDF inertial "
                               f"{'none' if was is None else f'{was.mass:g} kg'} replaced by "
                               f"the RFEM beam {beam.mass:.6g} kg ({n} segments, length "
                               f"{beam.length:.6g} m)")
            elif inertias.get(lk) is not None:
                builder.add_body(inertias[lk])
            for x in attached.get(k, []):
                if inertias.get(x) is not None:
                    builder.add_body(inertias[x], origin=after @ pose[x])
                builder.add_frame(x, after @ pose[x])
                frames.append(x)
        for rec in side_drives:
            builder.add_drive(rec["joint"], drive_function(rec))
        model = builder.build()
        model = _with_flexible_records(model, side_flex, flexible)
    except ModelError as exc:
        suffix = (" (found with the invalid <inertial> elements above left out)"
                  if set(bad_inertia) - set(world_fixed_bad) else "")
        problems += [p + suffix for p in exc.problems]
    if problems:
        _fail(source, problems)
    return UrdfReadResult(model, notes.lines(), MappingProxyType(dict(values)), (root, tip),
                          tuple(j.name for j in chain_joints), tuple(frames))


def _size_problem(tree, owner, inertias) -> Optional[str]:
    """The problem when the moving masses at the lengths of the tree give an inertia about
    the root (sum m * L^2 + tr I, L the sum of every joint offset) above _MAGNITUDE."""
    offsets = [(math.hypot(*j.origin[:3, 3]), j.name)
               for js in tree.children.values() for j in js]
    moving = [inertias[lk] for lk, k in owner.items() if k >= 0 and inertias.get(lk) is not None]
    if not offsets or not moving:
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        length = sum(d for d, _ in offsets) + max(math.hypot(*i.com_array) for i in moving)
        mass = sum(float(i.mass) for i in moving)
        size = mass * length * length + sum(float(np.trace(i.inertia_array)) for i in moving)
    if size < _MAGNITUDE:
        return None
    far, joint = max(offsets)
    return (f"the moving links' mass {mass:.3g} kg at up to {length:.3g} m from the root "
            f"(the largest joint offset: joint {joint!r}, {far:.3g} m) give an inertia of "
            f"{size:.3g} kg m^2, too large to compute with (at most {_MAGNITUDE:g}; real "
            "machines have < 1e12): check the units of <origin xyz> (m) and <mass> (kg); "
            "the assembled model was not checked because of it")


def _xml_error(exc: ET.ParseError) -> str:
    """The parser's reason without the position it repeats."""
    text = str(exc)
    return text.split(":")[0] if ": line " in text else text


def _with_flexible_records(model, side_flex, flexible):
    """Add the side file's RFEM records (beams not re-discretised on reading; their joints
    and links checked to be in the chain)."""
    records = list(model.flexible_links)
    link_names = [lk.name for lk in model.links]
    for name, rec in side_flex.items():
        if name in flexible:
            continue
        joints = tuple(model.index(j) for j in rec["joints"])
        links = tuple(link_names.index(lk) for lk in rec["links"])
        records.append(FlexibleLinkInfo(name, BeamProperties(**rec["beam"]), rec["n_segments"],
                                        joints, links))
    if len(records) == len(model.flexible_links):
        return model
    order = {lk.name: k for k, lk in enumerate(model.links)}
    records.sort(key=lambda r: order.get(r.name, -1))
    out = Model(model.joints, model.links, model.frames, model.drives, model.gravity, records,
                model.name)
    validate_model(out)
    return out


def with_link_frames(model: Model, names) -> Model:
    """``model`` with a frame named after each link in ``names`` at that link's own frame
    (identity transform), for the links that have no frame of that name yet: the frames a
    model file gives a constraint on a moving link, which gpme_io.urdf_writer leaves implicit
    in the URDF link itself (ModelError for a name that is not a link)."""
    from gpme_core.model import Frame, validate_model
    index = {lk.name: k for k, lk in enumerate(model.links)}
    missing = [n for n in names if n not in model.frames]
    unknown = [n for n in missing if n not in index]
    if unknown:
        raise ModelError(f"no links named {unknown} to give a frame; the links are "
                         f"{sorted(index)}")
    if not missing:
        return model
    frames = dict(model.frames)
    frames.update({n: Frame(n, index[n], np.eye(4)) for n in missing})
    out = Model(model.joints, model.links, frames, model.drives, model.gravity,
                model.flexible_links, model.name)
    validate_model(out)
    return out

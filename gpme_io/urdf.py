"""URDF writer and reader for gpme models, with the gpme side file.

Writing (:func:`write_urdf`) maps a serial-chain :class:`gpme_core.model.Model` to URDF
one to one (docs/urdf.md has the full table):

* world            -> root link ``world`` (no inertial; MuJoCo makes it its worldbody);
* joint k          -> a ``revolute`` or ``prismatic`` joint named after coordinate k,
                      parent = link k-1 (``world`` for k = 0), child = link k,
                      <origin> = ``Joint.origin`` (xyz m, rpy rad), <axis> = ``Joint.axis``,
                      <dynamics damping> = ``Joint.damping``, <limit lower upper> =
                      ``Joint.limits`` with an infinite end written as -+UNLIMITED (URDF
                      needs finite numbers; the reader maps |limit| >= UNLIMITED back to inf);
* link k           -> a link with <inertial> (com in the link frame, rpy 0, inertia about
                      the com in link axes), or no <inertial> when massless (the two
                      intermediate frames of an RFEM spring-damping element);
* frame ``F``      -> a link ``F`` without inertial on a fixed joint ``F_fixed``;
* stiffness, spring reference, gravity, drives, the massless-link list and the RFEM
  records go to the side file ``<stem>.gpme.json`` beside the URDF (URDF cannot hold them).

A ``<mujoco><compiler .../></mujoco>`` element tells MuJoCo's URDF importer to keep
fixed links as bodies and to bound the mass of the massless links at MUJOCO_BOUND (kg,
kg m^2), which MuJoCo needs to accept a moving body; every other reader ignores it.

Reading (:func:`read_urdf`) accepts that output and any serial-chain URDF with revolute,
continuous (both -> gpme revolute), prismatic and fixed joints.  Links on fixed joints
are merged into their moving parent (their inertia added, their origin kept as a named
frame); links fixed to the world before the first moving joint do not move and are
dropped.  Everything unsupported (floating, planar, mimic joints, friction, branches
with moving joints, a moving link without mass, malformed numbers) is reported in one
:class:`gpme_core.errors.ModelFileError` that names every offending element.  One link
can be made flexible on reading: ``flexible={"link": (BeamProperties, n_segments)}``.
"""
import dataclasses
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from gpme_core import time_functions
from gpme_core import transforms as tf
from gpme_core.errors import ModelError, ModelFileError
from gpme_core.inertia import RigidBodyInertia
from gpme_core.model import (PRISMATIC, REVOLUTE, STANDARD_GRAVITY, ChainBuilder,
                             FlexibleLinkInfo, Model, validate_model)
from gpme_core.rfem import BeamProperties

from gpme_core.atomic import atomic_write_text

ROOT_LINK = "world"
SIDE_SUFFIX = ".gpme.json"
SIDE_FORMAT = "gpme-urdf-side-file"
SIDE_VERSION = 1
# rad or m: the <limit> written for an infinite end of a gpme joint range (URDF needs a
# finite one for revolute and prismatic joints); 1e6 rad is ~160 000 turns, never reached.
# Also written as effort (N, N m) and velocity (m/s, rad/s) limits, which gpme does not have.
UNLIMITED = 1.0e6
# kg and kg m^2: MuJoCo's importer lower bound for the massless links (MuJoCo rejects a
# moving body with mass <= 1e-15).  MuJoCo-only: gpme and Pinocchio read zero mass.
MUJOCO_BOUND = 1e-12
FIXED_SUFFIX = "_fixed"
_URDF_KIND = {REVOLUTE: "revolute", PRISMATIC: "prismatic"}
_READ_KIND = {"revolute": REVOLUTE, "continuous": REVOLUTE, "prismatic": PRISMATIC}
_UNSUPPORTED_KIND = {"floating": "6-dof floating joints", "planar": "planar joints"}


# ============================================================================ writing
def _num(x):
    """Shortest text that reads back as the same float (repr), without '-0.0'."""
    x = float(x)
    return "0" if x == 0.0 else repr(x)


def _vec(v):
    return " ".join(_num(x) for x in v)


def _origin(parent, transform):
    """<origin xyz rpy> of a (4, 4) transform (parent frame -> child frame)."""
    t = np.asarray(transform, dtype=float)
    ET.SubElement(parent, "origin", xyz=_vec(t[:3, 3]), rpy=_vec(tf.rotation_to_rpy(t[:3, :3])))


def _inertial(parent, inertia):
    """<inertial> of a RigidBodyInertia: com frame = link axes moved to the com."""
    el = ET.SubElement(parent, "inertial")
    ET.SubElement(el, "origin", xyz=_vec(inertia.com), rpy="0 0 0")
    ET.SubElement(el, "mass", value=_num(inertia.mass))
    i = inertia.inertia_array
    ET.SubElement(el, "inertia", ixx=_num(i[0, 0]), ixy=_num(i[0, 1]), ixz=_num(i[0, 2]),
                  iyy=_num(i[1, 1]), iyz=_num(i[1, 2]), izz=_num(i[2, 2]))


def side_file_path(urdf_path):
    """Path of the side file beside ``urdf_path``: ``<stem>.gpme.json``."""
    p = Path(urdf_path)
    return p.with_name(p.stem + SIDE_SUFFIX)


def _drive_record(drive):
    fn = drive.function
    if dataclasses.is_dataclass(fn) and getattr(time_functions, type(fn).__name__, None) is type(fn):
        return {"joint": drive.joint, "function": type(fn).__name__,
                "parameters": dataclasses.asdict(fn)}
    return None


def _name_problems(model):
    problems = []
    link_names = [ROOT_LINK] + [lk.name for lk in model.links] + list(model.frames)
    joint_names = list(model.coordinate_names) + [f + FIXED_SUFFIX for f in model.frames]
    for kind, names in (("link", link_names), ("joint", joint_names)):
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            problems.append(f"URDF {kind} names would repeat: {dup} (the root link is "
                            f"{ROOT_LINK!r}, frames become links, frame F gets joint "
                            f"'F{FIXED_SUFFIX}'); rename the links, frames or coordinates")
    return problems


def urdf_documents(model, include_drives=True, urdf_name=None):
    """(URDF text, side-file dict) of ``model``; see the module docstring for the mapping.

    include_drives: store the drives in the side file; each drive function must then be a
    dataclass of gpme_core.time_functions (ModelFileError otherwise).
    """
    problems = _name_problems(model)
    drives = []
    if include_drives:
        for d in model.drives:
            rec = _drive_record(d)
            if rec is None:
                problems.append(f"drive on {d.joint!r}: {d.function!r} is not a dataclass of "
                                "gpme_core.time_functions and cannot be stored; write with "
                                "include_drives=False and add the drive after reading")
            drives.append(rec)
    if problems:
        raise ModelFileError(problems)
    robot = ET.Element("robot", name=model.name)
    robot.append(ET.Comment(
        f" Generated from gpme model {model.name!r} by gpme_io.urdf; do not edit. "
        f"Stiffness, spring references, gravity and drives are in the side file "
        f"{(urdf_name or model.name)}{SIDE_SUFFIX} (docs/urdf.md). "))
    mj = ET.SubElement(robot, "mujoco")
    ET.SubElement(mj, "compiler", discardvisual="false", fusestatic="false",
                  boundmass=_num(MUJOCO_BOUND), boundinertia=_num(MUJOCO_BOUND))
    ET.SubElement(robot, "link", name=ROOT_LINK)
    parent = ROOT_LINK
    for joint, link in zip(model.joints, model.links):
        j = ET.SubElement(robot, "joint", name=joint.name, type=_URDF_KIND[joint.kind])
        ET.SubElement(j, "parent", link=parent)
        ET.SubElement(j, "child", link=link.name)
        _origin(j, joint.origin)
        ET.SubElement(j, "axis", xyz=_vec(joint.axis))
        lower, upper = (float(np.clip(v, -UNLIMITED, UNLIMITED)) for v in joint.limits)
        ET.SubElement(j, "limit", lower=_num(lower), upper=_num(upper),
                      effort=_num(UNLIMITED), velocity=_num(UNLIMITED))
        ET.SubElement(j, "dynamics", damping=_num(joint.damping), friction="0")
        lk = ET.SubElement(robot, "link", name=link.name)
        if link.inertia is not None:
            _inertial(lk, link.inertia)
        parent = link.name
    for name, fr in model.frames.items():
        j = ET.SubElement(robot, "joint", name=name + FIXED_SUFFIX, type="fixed")
        ET.SubElement(j, "parent", link=model.links[fr.link_index].name)
        ET.SubElement(j, "child", link=name)
        _origin(j, fr.transform)
        ET.SubElement(robot, "link", name=name)
    ET.indent(robot, space="  ")
    text = '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"
    side = {
        "format": SIDE_FORMAT, "version": SIDE_VERSION, "model": model.name,
        "gravity": [float(g) for g in model.gravity],
        "joints": {j.name: {"stiffness": float(j.stiffness),
                            "spring_reference": float(j.spring_reference)} for j in model.joints},
        "massless_links": [lk.name for lk in model.links if lk.inertia is None],
        "flexible_links": [
            {"name": f.name, "n_segments": int(f.n_segments), "beam": dataclasses.asdict(f.beam),
             "joints": [model.coordinate_names[k] for k in f.joint_indices],
             "links": [model.links[k].name for k in f.link_indices]}
            for f in model.flexible_links],
        "drives": drives,
    }
    return text, side


def side_file_text(side):
    """The side-file dict as JSON text (floats written exactly, keys in order)."""
    return json.dumps(side, indent=2) + "\n"


def write_urdf(model, path, include_drives=True):
    """Write ``model`` to the URDF ``path`` and its side file beside it (atomically).

    Returns (urdf path, side-file path).
    """
    path = Path(path)
    text, side = urdf_documents(model, include_drives, urdf_name=path.stem)
    side_path = side_file_path(path)
    atomic_write_text(path, text)
    atomic_write_text(side_path, side_file_text(side))
    return path, side_path


# ============================================================================ reading
def _floats(text, count, label, problems, default):
    if text is None:
        return np.array(default, dtype=float)
    try:
        v = np.array([float(s) for s in text.split()], dtype=float)
    except ValueError:
        v = None
    if v is None or v.shape != (count,) or not np.all(np.isfinite(v)):
        problems.append(f"{label}: expected {count} finite numbers, got {text!r}")
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


def _read_inertial(link_el, problems):
    """RigidBodyInertia of a <link> in the link frame, or None (no inertial / zero mass)."""
    name = link_el.get("name")
    el = link_el.find("inertial")
    if el is None:
        return None
    label = f"link {name!r} <inertial>"
    t = _origin_transform(el, label, problems)
    mass_el, inertia_el = el.find("mass"), el.find("inertia")
    if mass_el is None:
        problems.append(f"{label}: missing <mass value=...>")
        return None
    mass = float(_floats(mass_el.get("value"), 1, f"{label} <mass value>", problems,
                         (np.nan,))[0])
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    if inertia_el is None:
        problems.append(f"{label}: missing <inertia {' '.join(keys)}>")
        return None
    vals = [_floats(inertia_el.get(k, "0"), 1, f"{label} <inertia {k}>", problems, (np.nan,))[0]
            for k in keys]
    ixx, ixy, ixz, iyy, iyz, izz = vals
    i_com = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    if mass == 0.0 and not np.any(i_com):
        return None                   # a common way of writing "no mass"
    r = t[:3, :3]
    inertia = RigidBodyInertia(float(mass), t[:3, 3], r @ i_com @ r.T)
    bad = inertia.problems(label)
    if bad:
        problems.extend(bad)
        return None
    return inertia


@dataclasses.dataclass
class _UrdfJoint:
    name: str
    kind: str            # "revolute", "prismatic", "fixed" (gpme kinds or fixed)
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    damping: float
    limits: tuple


def _read_joint(el, link_names, problems):
    name = el.get("name")
    label = f"joint {name!r}"
    if not name:
        problems.append("a <joint> without a name attribute")
        return None
    jtype = el.get("type")
    if jtype in _UNSUPPORTED_KIND:
        problems.append(f"{label}: type {jtype!r} is not supported ({_UNSUPPORTED_KIND[jtype]}); "
                        "gpme models are serial chains of revolute and prismatic joints")
        return None
    if jtype != "fixed" and jtype not in _READ_KIND:
        problems.append(f"{label}: unknown type {jtype!r}; supported: revolute, continuous, "
                        "prismatic, fixed")
        return None
    ends = {}
    for end in ("parent", "child"):
        e = el.find(end)
        ends[end] = None if e is None else e.get("link")
        if ends[end] is None:
            problems.append(f"{label}: missing <{end} link=...>")
        elif ends[end] not in link_names:
            problems.append(f"{label}: {end} link {ends[end]!r} is not a <link> of the file")
    if el.find("mimic") is not None:
        problems.append(f"{label}: <mimic> is not supported (every gpme coordinate is free)")
    origin = _origin_transform(el, label, problems)
    axis = np.array((1.0, 0.0, 0.0))
    damping = 0.0
    limits = (-np.inf, np.inf)
    if jtype in ("revolute", "prismatic"):
        limits = _read_limits(el, label, problems)
    if jtype != "fixed":
        ax = el.find("axis")
        if ax is not None:
            axis = _floats(ax.get("xyz"), 3, f"{label} <axis xyz>", problems, (1, 0, 0))
        norm = np.linalg.norm(axis)
        if norm == 0.0:
            problems.append(f"{label}: <axis xyz> must not be zero")
        else:
            axis = axis / norm
        dyn = el.find("dynamics")
        if dyn is not None:
            damping = float(_floats(dyn.get("damping", "0"), 1, f"{label} <dynamics damping>",
                                    problems, (0,))[0])
            friction = float(_floats(dyn.get("friction", "0"), 1,
                                     f"{label} <dynamics friction>", problems, (0,))[0])
            if damping < 0:
                problems.append(f"{label}: <dynamics damping> must be >= 0, got {damping!r}")
            if friction != 0.0:
                problems.append(f"{label}: <dynamics friction={friction!r}> is not supported "
                                "(gpme has no Coulomb friction); set it to 0")
    kind = "fixed" if jtype == "fixed" else _READ_KIND[jtype]
    return _UrdfJoint(name, kind, ends["parent"], ends["child"], origin, axis, float(damping),
                      limits)


def _read_limits(el, label, problems):
    """(lower, upper) rad or m of a <limit>; a missing end or |value| >= UNLIMITED is inf."""
    lim = el.find("limit")
    if lim is None:
        return (-np.inf, np.inf)
    out = []
    for key, sign in (("lower", -1.0), ("upper", 1.0)):
        v = _floats(lim.get(key), 1, f"{label} <limit {key}>", problems, (sign * np.inf,))[0]
        out.append(sign * np.inf if abs(v) >= UNLIMITED else float(v))
    if not out[0] < out[1]:
        problems.append(f"{label}: <limit lower={out[0]!r} upper={out[1]!r}> must have "
                        "lower < upper")
        return (-np.inf, np.inf)
    return tuple(out)


def load_side_file(path):
    """The validated side-file dict at ``path`` (ModelFileError listing every problem)."""
    path = Path(path)
    try:
        side = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ModelFileError(f"side file {str(path)!r}: cannot read it ({exc})") from None
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"side file {str(path)!r}: not valid JSON ({exc})") from None
    problems = side_file_problems(side, f"side file {str(path)!r}")
    if problems:
        raise ModelFileError(problems)
    return side


def side_file_problems(side, label="side file"):
    """Problems of a side-file dict (empty list when valid)."""
    if not isinstance(side, dict):
        return [f"{label}: expected a JSON object, got {type(side).__name__}"]
    problems = []
    if side.get("format") != SIDE_FORMAT or side.get("version") != SIDE_VERSION:
        problems.append(f"{label}: expected format {SIDE_FORMAT!r} version {SIDE_VERSION}, got "
                        f"{side.get('format')!r} version {side.get('version')!r}")
    g = side.get("gravity", list(STANDARD_GRAVITY))
    if not (isinstance(g, list) and len(g) == 3 and all(isinstance(x, (int, float)) for x in g)):
        problems.append(f"{label}: gravity must be 3 numbers (m/s^2), got {g!r}")
    joints = side.get("joints", {})
    if not isinstance(joints, dict):
        problems.append(f"{label}: joints must be an object name -> {{stiffness, spring_reference}}")
        joints = {}
    for name, rec in joints.items():
        if not isinstance(rec, dict) or set(rec) - {"stiffness", "spring_reference"}:
            problems.append(f"{label}: joint {name!r} must hold only stiffness and "
                            f"spring_reference, got {rec!r}")
            continue
        for key, val in rec.items():
            if not isinstance(val, (int, float)) or not np.isfinite(val) or \
                    (key == "stiffness" and val < 0):
                problems.append(f"{label}: joint {name!r} {key} must be a finite number"
                                f"{' >= 0' if key == 'stiffness' else ''}, got {val!r}")
    for key in ("massless_links", "flexible_links", "drives"):
        if not isinstance(side.get(key, []), list):
            problems.append(f"{label}: {key} must be a list, got {side.get(key)!r}")
    beam_fields = {f.name for f in dataclasses.fields(BeamProperties)}
    for rec in side.get("flexible_links", []) if isinstance(side.get("flexible_links"), list) else []:
        if not isinstance(rec, dict) or set(rec.get("beam", {})) != beam_fields or \
                not isinstance(rec.get("n_segments"), int) or rec.get("n_segments", -1) < 0 or \
                not isinstance(rec.get("joints"), list) or not isinstance(rec.get("links"), list):
            problems.append(f"{label}: flexible link record {rec!r} must have name, n_segments "
                            f"(int >= 0), joints, links and beam with fields {sorted(beam_fields)}")
    for rec in side.get("drives", []) if isinstance(side.get("drives"), list) else []:
        cls = getattr(time_functions, str(rec.get("function")) if isinstance(rec, dict) else "",
                      None)
        if not (isinstance(rec, dict) and isinstance(cls, type) and dataclasses.is_dataclass(cls)
                and issubclass(cls, time_functions.TimeFunction)
                and isinstance(rec.get("parameters"), dict)):
            problems.append(f"{label}: drive record {rec!r} must name a dataclass of "
                            "gpme_core.time_functions in 'function' with its 'parameters'")
    return problems


def _chain(joints, link_names, problems):
    """Order the URDF tree as a serial chain.

    Returns (root link, chain, fixed_of):
    chain    : [(moving joint, T (4, 4) previous moving link (or root) frame -> the joint's
               parent link frame)], identity unless fixed joints sit in between;
    fixed_of : {moving link or root: [(fixed descendant, T (4, 4) link frame -> its frame)]}.
    Appends to ``problems`` (branches, several roots, links not connected to the root).
    """
    children = {n: [] for n in link_names}
    parent_joint = {}
    for j in joints:
        if j.parent in children and j.child in children:
            children[j.parent].append(j)
            if j.child in parent_joint:
                problems.append(f"link {j.child!r} is the child of two joints "
                                f"({parent_joint[j.child].name!r}, {j.name!r})")
            parent_joint[j.child] = j
    roots = [n for n in link_names if n not in parent_joint]
    if len(roots) != 1:
        problems.append(f"the URDF must have exactly one root link (a link that is no joint's "
                        f"child), found {roots}")
        return None, [], {}
    reached, todo = {roots[0]}, [roots[0]]
    while todo:
        for j in children[todo.pop()]:
            if j.child not in reached:
                reached.add(j.child)
                todo.append(j.child)
    lost = [n for n in link_names if n not in reached]
    if lost:
        problems.append(f"links {lost} are not connected to the root link {roots[0]!r} "
                        "(a cycle of joints?)")

    def closure(link):
        """Fixed descendants [(name, T_link_desc)] and moving joints [(joint, T_link_parent)]."""
        fixed, moving, stack = [], [], [(link, np.eye(4))]
        while stack:
            name, t = stack.pop(0)
            for j in children[name]:
                if j.kind == "fixed":
                    t_child = t @ j.origin
                    fixed.append((j.child, t_child))
                    stack.append((j.child, t_child))
                else:
                    moving.append((j, t))
        return fixed, moving

    chain, fixed_of, link, visited = [], {}, roots[0], set()
    while link is not None and link not in visited:
        visited.add(link)
        fixed, moving = closure(link)
        fixed_of[link] = fixed
        if len(moving) > 1:
            problems.append(f"link {link!r} (with the links fixed to it) branches into moving "
                            f"joints {[j.name for j, _ in moving]}; gpme models are serial "
                            "chains: keep one branch (fixed-joint branches are allowed)")
            break
        if not moving:
            break
        chain.append(moving[0])
        link = moving[0][0].child
    if not chain and not problems:
        problems.append("the URDF has no revolute, continuous or prismatic joint")
    return roots[0], chain, fixed_of


def _flexible_problems(flexible, moving_links, side_flex):
    problems = []
    for name, spec in flexible.items():
        try:
            beam, n = spec
        except (TypeError, ValueError):
            problems.append(f"flexible link {name!r}: expected (BeamProperties, n_segments), "
                            f"got {spec!r}")
            continue
        if name not in moving_links:
            problems.append(f"flexible link {name!r}: not a link moved by a joint of the chain "
                            f"(moving links: {moving_links})")
        if not isinstance(beam, BeamProperties):
            problems.append(f"flexible link {name!r}: beam must be a gpme_core.rfem."
                            f"BeamProperties, got {type(beam).__name__}")
        if name in side_flex and side_flex[name]["n_segments"] > 0:
            problems.append(f"flexible link {name!r}: already RFEM-discretised with "
                            f"{side_flex[name]['n_segments']} segments in this file; read the "
                            "rigid model to re-discretise it")
    return problems


def read_urdf(path, side_file="auto", flexible=None, massless_links=(), gravity=None, name=None):
    """A gpme Model from the serial-chain URDF at ``path``.

    side_file     : "auto" (``<stem>.gpme.json`` beside the URDF if it exists), None (no
                    side file: stiffness 0, gravity standard) or a path.  It restores
                    stiffness, spring references, gravity, drives and RFEM records.
    flexible      : {link name: (BeamProperties, n_segments)}; the link's <inertial> is
                    replaced by the RFEM-discretised beam along +x of the link frame, and
                    whatever hangs on the link (next joint, fixed links, frames) is moved
                    to the beam tip: its transform T from the link frame becomes
                    translation(-L) @ T, so the rigid geometry is unchanged at zero deflection.
    massless_links: link names allowed to be moved by a joint without any mass (added
                    to the side file's list); any other massless moving link is an error.
    gravity       : (3,) m/s^2 in the world frame; None: the side file's, else (0, 0, -9.81).
    name          : model name; None: the side file's, else the URDF robot name.

    Raises ModelFileError listing every problem (malformed or unsupported elements, each
    named), including the model problems found when building it.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelFileError(f"{str(path)!r}: cannot read the URDF ({exc})") from None
    side = None
    if side_file == "auto":
        if side_file_path(path).exists():
            side = load_side_file(side_file_path(path))
    elif side_file is not None:
        side = load_side_file(side_file)
    return parse_urdf(text, side, flexible, massless_links, gravity, name, source=str(path))


def parse_urdf(text, side=None, flexible=None, massless_links=(), gravity=None, name=None,
               source="<urdf>"):
    """:func:`read_urdf` on URDF ``text`` and a side-file dict ``side`` (or None)."""
    label = source
    try:
        robot = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelFileError(f"{label}: not well-formed XML ({exc})") from None
    if side is not None:
        bad = side_file_problems(side)
        if bad:
            raise ModelFileError([f"{label}: {p}" for p in bad])
    side = side or {}
    flexible = dict(flexible or {})
    problems = []
    if robot.tag != "robot":
        problems.append(f"the root element must be <robot>, got <{robot.tag}>")
    link_els = robot.findall("link")
    link_names = [el.get("name") for el in link_els]
    if None in link_names:
        problems.append("a <link> without a name attribute")
    dup = sorted({n for n in link_names if n is not None and link_names.count(n) > 1})
    if dup:
        problems.append(f"link names repeat: {dup}")
    inertias = {el.get("name"): _read_inertial(el, problems) for el in link_els}
    joints = [j for j in (_read_joint(el, set(link_names), problems)
                          for el in robot.findall("joint")) if j is not None]
    jnames = [j.name for j in joints]
    dup = sorted({n for n in jnames if jnames.count(n) > 1})
    if dup:
        problems.append(f"joint names repeat: {dup}")
    if problems:
        raise ModelFileError([f"{label}: {p}" for p in problems])
    root, chain, fixed_of = _chain(joints, link_names, problems)

    moving_links = [j.child for j, _ in chain]
    side_flex = {r["name"]: r for r in side.get("flexible_links", [])}
    side_joints = side.get("joints", {})
    problems += _flexible_problems(flexible, moving_links, side_flex)
    unknown = sorted(set(side_joints) - {j.name for j, _ in chain})
    if unknown:
        problems.append(f"the side file gives springs for joints {unknown} that are not moving "
                        "joints of the URDF chain")
    allowed_massless = set(massless_links) | set(side.get("massless_links", []))
    for j, _ in chain:
        mass_here = [inertias[j.child]] + [inertias[f] for f, _ in fixed_of.get(j.child, [])]
        if j.child not in flexible and j.child not in allowed_massless and \
                all(m is None for m in mass_here):
            problems.append(f"link {j.child!r} (moved by joint {j.name!r}) has no <inertial> "
                            "and nothing with mass fixed to it; give it mass properties, or "
                            "list it in massless_links if it is an intermediate frame")
    if problems:
        raise ModelFileError([f"{label}: {p}" for p in problems])

    g = gravity if gravity is not None else side.get("gravity", STANDARD_GRAVITY)
    builder = ChainBuilder(name or side.get("model") or robot.get("name") or "urdf", gravity=g)
    after = np.eye(4)        # previous moving link (or beam tip) frame -> its link frame
    try:
        for j, t_parent in chain:
            spring = side_joints.get(j.name, {})
            builder.add_joint(j.name, j.kind, j.axis, origin=after @ t_parent @ j.origin,
                              stiffness=spring.get("stiffness", 0.0),
                              spring_reference=spring.get("spring_reference", 0.0),
                              damping=j.damping, link=j.child, limits=j.limits)
            after = np.eye(4)
            if j.child in flexible:
                beam, n = flexible[j.child]
                builder.add_beam(j.child, beam, n)
                after = tf.translation(-beam.length)        # beam tip -> link frame
            elif inertias[j.child] is not None:
                builder.add_body(inertias[j.child])
            for fixed, t_fixed in fixed_of.get(j.child, []):
                if inertias[fixed] is not None:
                    builder.add_body(inertias[fixed], origin=after @ t_fixed)
                builder.add_frame(fixed, after @ t_fixed)
        for rec in side.get("drives", []):
            cls = getattr(time_functions, rec["function"])
            builder.add_drive(rec["joint"], cls(**rec["parameters"]))
        model = builder.build()
        model = _with_flexible_records(model, side_flex, flexible)
    except ModelFileError:
        raise
    except (ModelError, TypeError) as exc:
        found = exc.problems if isinstance(exc, ModelError) else [str(exc)]
        raise ModelFileError([f"{label}: {p}" for p in found]) from None
    return model


def _with_flexible_records(model, side_flex, flexible):
    """Add the side file's RFEM records (beams not re-discretised on reading)."""
    records = list(model.flexible_links)
    problems = []
    for name, rec in side_flex.items():
        if name in flexible:
            continue
        try:
            joints = tuple(model.index(j) for j in rec["joints"])
            links = tuple([lk.name for lk in model.links].index(lk) for lk in rec["links"])
        except (ModelError, ValueError):
            problems.append(f"side file flexible link {name!r}: its joints {rec['joints']} or "
                            f"links {rec['links']} are not all in the URDF chain")
            continue
        records.append(FlexibleLinkInfo(name, BeamProperties(**rec["beam"]), rec["n_segments"],
                                        joints, links))
    if problems:
        raise ModelFileError(problems)
    if len(records) == len(model.flexible_links):
        return model
    order = {lk.name: k for k, lk in enumerate(model.links)}
    records.sort(key=lambda r: order.get(r.name, -1))
    out = Model(model.joints, model.links, model.frames, model.drives, model.gravity, records,
                model.name)
    validate_model(out)
    return out

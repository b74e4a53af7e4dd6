"""Write a gpme model as URDF plus the gpme side file.

:func:`write_urdf` maps a :class:`gpme_core.model.Model` (a chain or a tree) to URDF one to one
(docs/urdf.md has the full table):

* world            -> root link ``world`` (no inertial; MuJoCo makes it its worldbody);
* joint k          -> a ``revolute`` or ``prismatic`` joint named after coordinate k,
                      parent = the link of its parent joint (``world`` for a root;
                      link k-1 in a serial chain), child = link k,
                      <origin> = ``Joint.origin`` (xyz m, rpy rad), <axis> = ``Joint.axis``,
                      <dynamics damping> = ``Joint.damping``, <limit lower upper> =
                      ``Joint.limits`` with an infinite end written as -+UNLIMITED (URDF
                      needs finite numbers; the reader maps |limit| >= UNLIMITED back to inf);
* link k           -> a link with <inertial> (com in the link frame, rpy 0, inertia about
                      the com in link axes); a massless link (the two intermediate frames
                      of an RFEM spring-damping element) gets an explicit zero <inertial>
                      (mass 0, zero tensor, origin 0): a link without <inertial> is 1 kg
                      with unit inertia in PyBullet;
* shapes           -> the link's <visual> (with a named <material> colour) and <collision>
                      elements (gpme_core.geometry: RFEM elements as cylinders or boxes of
                      their section, visual only; never mass);
* frame ``F``      -> a link ``F`` with a zero <inertial> on a fixed joint ``F_fixed``;
* stiffness, spring reference, gravity, drives, the massless-link list and the RFEM
  records go to the side file ``<stem>.gpme.json`` beside the URDF (gpme_io.side_file).

A ``<mujoco><compiler .../></mujoco>`` element tells MuJoCo's URDF importer to keep
fixed links as bodies and to bound the mass of the massless links at MUJOCO_BOUND (kg,
kg m^2), which MuJoCo needs to accept a moving body; every other reader ignores it.
"""
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import numpy as np

from gpme_core import transforms as tf
from gpme_io.atomic import atomic_write_text
from gpme_core.errors import ModelFileError
from gpme_core.model import PRISMATIC, REVOLUTE, Model

from .side_file import SIDE_SUFFIX, drive_record, side_document, side_file_path, side_file_text
from .xml_text import xml_char_problem, xml_comment

ROOT_LINK = "world"
# rad or m: the <limit> written for an infinite end of a gpme joint range (URDF needs a
# finite one for revolute and prismatic joints); 1e6 rad is ~160 000 turns, never reached.
# Also written as effort (N, N m) and velocity (m/s, rad/s) limits, which gpme does not have.
UNLIMITED = 1.0e6
# kg and kg m^2: MuJoCo's importer lower bound for the massless links (MuJoCo rejects a
# moving body with mass <= 1e-15).  MuJoCo-only: gpme and Pinocchio read zero mass.
MUJOCO_BOUND = 1e-12
FIXED_SUFFIX = "_fixed"
_URDF_KIND = {REVOLUTE: "revolute", PRISMATIC: "prismatic"}


def _num(x) -> str:
    """Shortest text that reads back as the same float (repr), without '-0.0'."""
    x = float(x)
    return "0" if x == 0.0 else repr(x)


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


def _origin(parent, transform) -> None:
    """<origin xyz rpy> of a (4, 4) transform (parent frame -> child frame)."""
    t = np.asarray(transform, dtype=float)
    ET.SubElement(parent, "origin", xyz=_vec(t[:3, 3]), rpy=_vec(tf.rotation_to_rpy(t[:3, :3])))


def _inertial(parent, inertia) -> None:
    """<inertial> of a RigidBodyInertia (com frame = link axes moved to the com), or the
    explicit zero <inertial> of a massless link when ``inertia`` is None."""
    el = ET.SubElement(parent, "inertial")
    if inertia is None:
        ET.SubElement(el, "origin", xyz="0 0 0", rpy="0 0 0")
        ET.SubElement(el, "mass", value="0")
        ET.SubElement(el, "inertia", ixx="0", ixy="0", ixz="0", iyy="0", iyz="0", izz="0")
        return
    ET.SubElement(el, "origin", xyz=_vec(inertia.com), rpy="0 0 0")
    ET.SubElement(el, "mass", value=_num(inertia.mass))
    i = inertia.inertia_array
    ET.SubElement(el, "inertia", ixx=_num(i[0, 0]), ixy=_num(i[0, 1]), ixz=_num(i[0, 2]),
                  iyy=_num(i[1, 1]), iyz=_num(i[1, 2]), izz=_num(i[2, 2]))


def _shape_geometry(parent, shape) -> None:
    """<geometry> of a gpme_core.geometry.Shape."""
    g = ET.SubElement(parent, "geometry")
    if shape.kind == "box":
        ET.SubElement(g, "box", size=_vec(shape.size))
    elif shape.kind == "cylinder":
        ET.SubElement(g, "cylinder", radius=_num(shape.size[0]), length=_num(shape.size[1]))
    elif shape.kind == "sphere":
        ET.SubElement(g, "sphere", radius=_num(shape.size[0]))
    else:
        ET.SubElement(g, "mesh", filename=shape.mesh, scale=_vec(shape.size))


def _shapes(link_el, shapes) -> None:
    """<visual> and <collision> elements of a link's shapes (a "both" shape gives one of
    each; a visual's colour is a named <material>, the name made of the colour so that
    equal names never carry different colours)."""
    for shape in shapes:
        if shape.is_visual:
            v = ET.SubElement(link_el, "visual")
            _origin(v, shape.origin_array)
            _shape_geometry(v, shape)
            if shape.rgba is not None:
                name = "rgba_" + "".join(f"{round(255 * c):02x}" for c in shape.rgba)
                m = ET.SubElement(v, "material", name=name)
                ET.SubElement(m, "color", rgba=_vec(shape.rgba))
        if shape.is_collision:
            c = ET.SubElement(link_el, "collision")
            _origin(c, shape.origin_array)
            _shape_geometry(c, shape)


def link_own_frame(model: Model, name: str) -> bool:
    """True when frame ``name`` is the frame of the link of the same name (identity
    transform): the URDF link itself is that frame, so no fixed child link is written for it
    (gpme_io.urdf_reader gives every chain link its frame back)."""
    fr = model.frames[name]
    return (model.links[fr.link_index].name == name
            and np.array_equal(fr.transform, np.eye(4)))


def _written_frames(model: Model) -> list:
    return [f for f in model.frames if not link_own_frame(model, f)]


def _name_problems(model: Model) -> list:
    """Names the URDF cannot carry: repeated within links or joints, or holding a character
    XML 1.0 cannot hold (refused, not replaced: the reader must get the same names back)."""
    problems = []
    frames = _written_frames(model)
    link_names = [ROOT_LINK] + [lk.name for lk in model.links] + frames
    joint_names = list(model.coordinate_names) + [f + FIXED_SUFFIX for f in frames]
    named = ([("model name", model.name)] + [("link name", n) for n in link_names[1:]]
             + [("joint name", n) for n in joint_names])
    for label, name in named:
        bad = xml_char_problem(label, str(name))
        if bad:
            problems.append(f"{bad}; rename it (a URDF name is XML text: printable characters, "
                            "tab, newline and carriage return)")
    for kind, names in (("link", link_names), ("joint", joint_names)):
        counts = Counter(names)
        dup = sorted(n for n in counts if counts[n] > 1)
        if dup:
            problems.append(f"URDF {kind} names would repeat: {dup} (the root link is "
                            f"{ROOT_LINK!r}, frames become links, frame F gets joint "
                            f"'F{FIXED_SUFFIX}'); rename the links, frames or coordinates")
    return problems


def urdf_documents(model: Model, include_drives: bool = True, urdf_name=None) -> tuple:
    """(URDF text, side-file dict) of ``model``; see the module docstring for the mapping.

    include_drives: store the drives in the side file; each drive function must then be a
    dataclass of gpme_core.time_functions (ModelFileError otherwise).
    urdf_name     : stem of the URDF file, named in its comment (default the model name).
    """
    problems = _name_problems(model)
    drives = []
    if include_drives:
        for d in model.drives:
            rec = drive_record(d)
            if rec is None:
                problems.append(f"drive on {d.joint!r}: {d.function!r} is neither a dataclass of "
                                "gpme_core.time_functions nor a SympyTimeFunction and cannot be "
                                "stored; write with "
                                "include_drives=False and add the drive after reading")
            drives.append(rec)
    if problems:
        raise ModelFileError(problems)
    robot = ET.Element("robot", name=model.name)
    robot.append(xml_comment(
        f"Generated from gpme model {model.name!r} by gpme_io.urdf_writer; do not edit. "
        f"Stiffness, spring references, gravity and drives are in the side file "
        f"{(urdf_name or model.name)}{SIDE_SUFFIX} (docs/urdf.md)."))
    mj = ET.SubElement(robot, "mujoco")
    ET.SubElement(mj, "compiler", discardvisual="false", fusestatic="false",
                  boundmass=_num(MUJOCO_BOUND), boundinertia=_num(MUJOCO_BOUND))
    ET.SubElement(robot, "link", name=ROOT_LINK)
    by_link = {}
    for shape in model.geometry:
        by_link.setdefault(shape.link_index, []).append(shape)
    for k, (joint, link) in enumerate(zip(model.joints, model.links)):
        j = ET.SubElement(robot, "joint", name=joint.name, type=_URDF_KIND[joint.kind])
        parent = int(model.parents[k])
        ET.SubElement(j, "parent", link=ROOT_LINK if parent < 0 else model.links[parent].name)
        ET.SubElement(j, "child", link=link.name)
        _origin(j, joint.origin)
        ET.SubElement(j, "axis", xyz=_vec(joint.axis))
        lower, upper = (float(np.clip(v, -UNLIMITED, UNLIMITED)) for v in joint.limits)
        ET.SubElement(j, "limit", lower=_num(lower), upper=_num(upper),
                      effort=_num(UNLIMITED), velocity=_num(UNLIMITED))
        ET.SubElement(j, "dynamics", damping=_num(joint.damping), friction="0")
        link_el = ET.SubElement(robot, "link", name=link.name)
        _inertial(link_el, link.inertia)
        _shapes(link_el, by_link.get(k, []))
    for name in _written_frames(model):
        fr = model.frames[name]
        j = ET.SubElement(robot, "joint", name=name + FIXED_SUFFIX, type="fixed")
        ET.SubElement(j, "parent", link=model.links[fr.link_index].name)
        ET.SubElement(j, "child", link=name)
        _origin(j, fr.transform)
        _inertial(ET.SubElement(robot, "link", name=name), None)
    ET.indent(robot, space="  ")
    text = '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"
    return text, side_document(model, drives)


def write_urdf(model: Model, path, include_drives: bool = True) -> tuple:
    """Write ``model`` to the URDF ``path`` and its side file beside it (atomically).

    Returns (urdf path, side-file path).
    """
    path = Path(path)
    text, side = urdf_documents(model, include_drives, urdf_name=path.stem)
    side_path = side_file_path(path)
    atomic_write_text(path, text)
    atomic_write_text(side_path, side_file_text(side))
    return path, side_path

"""URDF text -> the links, inertials and joints its <robot> says, each checked on its own.

Problems are appended to the caller's list (every one found, with the element's name, the
text and what would be valid); what gpme ignores is named in the notes
(gpme_io.urdf_read.notes).  Whether the joints form a tree and which chain is read is
gpme_io.urdf_read.tree's job.
"""
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass
from typing import Optional

from .inertial import _read_inertial
from .joint import _read_joint

# children of <robot> and of <link> that URDF defines (others are extension tags, noted)
_ROBOT_CHILDREN = ("link", "joint", "material")
_LINK_CHILDREN = ("inertial", "visual", "collision")


def _parse_xml(text, problems) -> Optional[ET.Element]:
    """The root element of URDF ``text`` (str or bytes), or None (no text, or not
    well-formed XML: the problem, with its line and column, is appended)."""
    if text is None:
        return None
    try:
        return ET.fromstring(text)
    except ET.ParseError as exc:
        line, column = exc.position
        problems.append(f"not well-formed XML at line {line}, column {column + 1} ("
                        f"{_xml_error(exc)}); nothing else in the URDF could be checked")
        return None


def _xml_error(exc: ET.ParseError) -> str:
    """The parser's reason without the position it repeats."""
    text = str(exc)
    return text.split(":")[0] if ": line " in text else text


@dataclass
class _Parsed:
    """What the elements of <robot> say, each checked on its own."""

    links: list               # link names, in file order
    inertias: dict            # link -> RigidBodyInertia or None (none, zero, or invalid)
    joints: list              # _Joint of every joint with a name and a known type
    bad_inertia: dict         # link -> [problems of its <inertial>]
    geometry_only: list       # links with <visual>/<collision> but no <inertial>
    left_out: list            # joints not in the tree: no name, unknown type, bad ends
    link_elements: dict       # link -> its <link> element (shapes are read from it)


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
                   geometry_only, left_out,
                   {n: el for el, n in zip(link_els, link_names) if n is not None})

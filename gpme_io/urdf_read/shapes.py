"""A link's <visual> and <collision> elements -> shapes (gpme_core.geometry) in the link
frame, kept through a read so that a written URDF shows the robot the user gave.

Mesh file names are resolved as Pinocchio and MuJoCo resolve them: ``package://PKG/rest``
against a folder named PKG among the URDF's parent folders and the ROS_PACKAGE_PATH
folders (example-robot-data's layout: robots/PKG/...), ``file://`` and absolute paths as
they are, a relative path against the URDF's folder; a mesh that cannot be found keeps its
name as written (a note says so: a viewer given the package path can still find it).
Geometry never changes the dynamics, so a malformed shape is left out with a note, never an
error.
"""
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Optional

import numpy as np

from gpme_core.geometry import Shape

from .attributes import _floats, _origin_transform

ROLES = {"visual": "visual", "collision": "collision"}


def link_shapes(link_el: ET.Element, urdf_path: Optional[Path], materials: dict,
                notes) -> list:
    """[(role, kind, size, origin (4, 4) in the link frame, mesh or None, rgba or None)] of
    the link's <visual> and <collision> elements, in file order (``materials``: the
    robot's top-level {name: rgba}); a shape that cannot be read is noted and left out."""
    name = link_el.get("name")
    out = []
    for el in link_el:
        role = ROLES.get(el.tag) if isinstance(el.tag, str) else None
        if role is None:
            continue
        problems = []
        origin = _origin_transform(el, f"link {name!r} <{el.tag}>", problems)
        shape = _geometry(el.find("geometry"), urdf_path, notes, name)
        if shape is None or problems:
            notes.add("bad_shape", f"{name} <{el.tag}>")
            continue
        kind, size, mesh = shape
        rgba = _colour(el.find("material"), materials) if role == "visual" else None
        last = out[-1] if out else None
        if role == "collision" and last is not None and last[0] == "visual" and \
                last[1:3] == (kind, size) and last[4] == mesh and np.array_equal(last[3],
                                                                                 origin):
            out[-1] = ("both",) + last[1:]      # the same shape seen and touched: one record
            continue
        out.append((role, kind, size, origin, mesh, rgba))
    return out


def robot_materials(robot: ET.Element) -> dict:
    """{material name: rgba (4,)} of the robot's top-level <material> elements."""
    out = {}
    for m in robot.findall("material"):
        rgba = _rgba(m)
        if m.get("name") and rgba is not None:
            out[m.get("name")] = rgba
    return out


def _rgba(material: ET.Element):
    color = material.find("color")
    if color is None:
        return None
    values = _floats(color.get("rgba"), 4, "rgba", [], ())
    if len(values) != 4:
        return None
    return tuple(float(np.clip(v, 0.0, 1.0)) for v in values)


def _colour(material: Optional[ET.Element], materials: dict):
    if material is None:
        return None
    return _rgba(material) or materials.get(material.get("name"))


def _geometry(g: Optional[ET.Element], urdf_path, notes, link):
    """(kind, size, mesh) of a <geometry>, or None when it cannot be read."""
    if g is None or len(g) != 1:
        return None
    el = g[0]
    sizes = {"box": ("size", 3), "sphere": ("radius", 1)}
    if el.tag in sizes:
        key, n = sizes[el.tag]
        size = _floats(el.get(key), n, key, [], ())
        return (el.tag, tuple(size), None) if _positive(size) and min(size) > 0 else None
    if el.tag == "cylinder":
        size = [_floats(el.get(k), 1, k, [], (np.nan,))[0] for k in ("radius", "length")]
        return ("cylinder", tuple(size), None) if _positive(size) and min(size) > 0 else None
    if el.tag == "mesh" and el.get("filename"):
        scale = _floats(el.get("scale", "1 1 1"), 3, "scale", [], ())
        if not _positive(scale):
            return None
        return "mesh", tuple(scale), resolve_mesh(el.get("filename"), urdf_path, notes, link)
    return None


def _positive(values) -> bool:
    return len(values) > 0 and bool(np.all(np.isfinite(values)) and
                                    np.all(np.abs(values) > 0))


def resolve_mesh(filename: str, urdf_path: Optional[Path], notes=None, link=None) -> str:
    """The mesh file as an absolute path when it can be found (see the module docstring),
    else ``filename`` as written (noted)."""
    if filename.startswith("file://"):
        return filename[len("file://"):]
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        for base in _package_roots(urdf_path):
            for candidate in (base / package / rest, base / rest if base.name == package
                              else None):
                if candidate is not None and candidate.is_file():
                    return str(candidate.resolve())
        if notes is not None:
            notes.add("unresolved_mesh", f"{link}: {filename}")
        return filename
    path = Path(filename)
    if not path.is_absolute() and urdf_path is not None:
        path = Path(urdf_path).parent / path
    return str(path.resolve()) if path.is_file() else filename


def _package_roots(urdf_path) -> list:
    """Folders to look for ``package://`` names in: the URDF's folder and its parents, then
    the ROS_PACKAGE_PATH entries."""
    roots = []
    if urdf_path is not None:
        here = Path(urdf_path).resolve().parent
        roots += [here, *here.parents]
    roots += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    return roots


def shape_of(link_index: int, shape, origin: np.ndarray) -> Shape:
    """The gpme_core.geometry.Shape of a read ``shape`` (link_shapes' tuple) on link
    ``link_index`` with its frame ``origin`` in that link's frame."""
    role, kind, size, _, mesh, rgba = shape
    return Shape(link_index, kind, size, origin, role, mesh, rgba)

"""What a model looks like: shapes attached to its links, for viewers and simulators.

Geometry never enters the dynamics (the mass properties are the links' inertias alone); it
is carried by the model so that the URDFs and MJCFs written from it can be seen (RViz,
MuJoCo's viewer, PyBullet, Meshcat) and a user's URDF keeps its meshes on the way through.

A :class:`Shape` is one primitive or mesh placed in its link's frame:

  kind   "box"      size (lx, ly, lz) m, centred on the origin
         "cylinder" size (radius, length) m, axis along the origin's z (URDF's convention)
         "sphere"   size (radius,) m
         "mesh"     size (sx, sy, sz) the mesh's scale; ``mesh`` the file, an absolute path
                    or a ``package://`` URI as the source URDF wrote it when it could not be
                    resolved
  origin (4, 4) the shape's frame in the link frame
  role   "visual", "collision" or "both"
  rgba   (4,) colour of a visual, or None
"""
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import transforms as tf

KINDS = {"box": 3, "cylinder": 2, "sphere": 1, "mesh": 3}
ROLES = ("visual", "collision", "both")
# colours of the shapes gpme draws itself (RGBA): RFEM elements steel blue, rigid links grey
ELEMENT_RGBA = (0.27, 0.51, 0.71, 1.0)
RIGID_RGBA = (0.6, 0.6, 0.6, 1.0)


@dataclass(frozen=True)
class Shape:
    """One shape on link ``link_index`` of a model (see the module docstring)."""

    link_index: int
    kind: str
    size: tuple
    origin: tuple = tuple(map(tuple, np.eye(4)))
    role: str = "both"
    mesh: Optional[str] = None
    rgba: Optional[tuple] = None

    def __post_init__(self):
        object.__setattr__(self, "size", tuple(float(s) for s in self.size))
        object.__setattr__(self, "origin", tuple(tuple(float(v) for v in row)
                                                 for row in np.asarray(self.origin, float)))
        if self.rgba is not None:
            object.__setattr__(self, "rgba", tuple(float(c) for c in self.rgba))

    @property
    def origin_array(self) -> np.ndarray:
        """(4, 4) the shape's frame in its link frame."""
        return np.array(self.origin)

    @property
    def is_visual(self) -> bool:
        return self.role in ("visual", "both")

    @property
    def is_collision(self) -> bool:
        return self.role in ("collision", "both")

    def problems(self, label: str) -> list:
        """What is wrong with this shape (empty when valid)."""
        out = []
        if self.kind not in KINDS:
            return [f"{label}: shape kind must be one of {list(KINDS)}, got {self.kind!r}"]
        # a mesh's scale may be negative (a mirrored mesh), never 0
        valid = (lambda s: s != 0) if self.kind == "mesh" else (lambda s: s > 0)
        if len(self.size) != KINDS[self.kind] or not all(np.isfinite(self.size)) or \
                not all(valid(s) for s in self.size):
            what = "non-zero finite scale factors" if self.kind == "mesh" else \
                "positive finite sizes (m)"
            out.append(f"{label}: a {self.kind} needs {KINDS[self.kind]} {what}, got "
                       f"{list(self.size)}")
        if self.kind == "mesh" and not self.mesh:
            out.append(f"{label}: a mesh needs its file name")
        if self.role not in ROLES:
            out.append(f"{label}: role must be one of {ROLES}, got {self.role!r}")
        if not np.all(np.isfinite(self.origin_array)):
            out.append(f"{label}: origin has non-finite entries")
        return out


def member(length, section_y, section_z, round_section, frame=None, start=0.0):
    """(kind, size, origin) of a straight member from x = ``start`` to ``start + length``
    (m) along the x axis of ``frame`` ((4, 4) in the link frame, default identity): a
    cylinder of radius ``section_y`` when ``round_section`` (its axis turned from z onto x),
    else a box of section 2 section_y x 2 section_z (the extreme fibres, m)."""
    base = np.eye(4) if frame is None else np.asarray(frame, dtype=float)
    centre = base @ tf.translation(start + 0.5 * length)
    if round_section:
        return "cylinder", (section_y, length), centre @ tf.rot_y(np.pi / 2)
    return "box", (length, 2 * section_y, 2 * section_z), centre

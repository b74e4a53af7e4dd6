"""A gpme model split into what a continuum model is made of: rigid bodies, joints, beams.

An RFEM link n >= 1 (gpme_core.rfem.discretise_beam) occupies, in the gpme model:

* the carrying link c, whose body includes rigid element 0 (the piece [0, dl/2] of the
  beam, dl = L / n) and whose frame holds the beam frame B (x along the beam);
* 3 n sde joints (psi about z, theta about y, phi about x of the beam frame at sde r) and
  their links, the last of each sde carrying rigid element r;
* the tip link (rigid element n, the piece [L - dl/2, L]), which also carries what the
  model attaches at the beam tip (a URDF's next link merged into it, a slider joint...);
  the tip frame is the tip link's frame moved by dl/2 along x.

The continuum model keeps the joints that are not sde joints, one rigid body per link that
is not inside a beam, and one beam from B on the carrying body to the tip frame on the tip
link's body.  A body's inertia is its link's minus the beam pieces it holds, both as 4x4
pseudo-inertias J = int [r; 1][r; 1]^T dm in the link frame (linear in the mass, so they
subtract).  The piece [0, l] of a beam in its own frame, derived here from the section:
m = rho A l, first moment m (l/2, 0, 0), second moments diag(m l^2/3, rho I_z l, rho I_y l)
(int x^2 dm, int y^2 dm = rho I_z l, int z^2 dm = rho I_y l).

Only model DATA is read (joint origins, axes, parents, link inertias, the flexible-link
records); nothing of gpme's kinematics or dynamics.
"""
from dataclasses import dataclass

import numpy as np

from gpme_core.errors import ModelError

# relative to the link's mass: a residual this small is round-off of the subtraction
# (pseudo-inertias of kg-scale parts agree to ~1e-15 relative), so the body has no mass
RESIDUAL_MASS_TOL = 1e-9


@dataclass(frozen=True)
class RigidPart:
    """A rigid body of the continuum model: the residual of gpme link ``link``.

    mass kg; com (3,) m and inertia (3, 3) kg m^2 about the COM, both in the link frame;
    mass 0 (with zero inertia) when the link held only beam pieces.
    """

    link: int
    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class BeamPart:
    """A flexible link as one continuum beam.

    name, beam (gpme_core.rfem.BeamProperties), n_rfe (the gpme model's segments);
    carrying_link : link index of rigid element 0; root_frame (4, 4): B in its frame;
    tip_link : link index of rigid element n; tip_frame (4, 4): the tip frame in its frame;
    sde_joints : indices of the 3 n sde joints; internal_links : links inside the beam.
    """

    name: str
    beam: object
    n_rfe: int
    carrying_link: int
    root_frame: np.ndarray
    tip_link: int
    tip_frame: np.ndarray
    sde_joints: tuple
    internal_links: tuple


@dataclass(frozen=True)
class ContinuumLayout:
    """bodies {link index: RigidPart}; joints (indices of the kept joints, model order);
    beams (BeamPart,); parents (n,) the model's parent links (-1 world)."""

    bodies: dict
    joints: tuple
    beams: tuple
    parents: np.ndarray

    def beam(self, name: str) -> BeamPart:
        for b in self.beams:
            if b.name == name:
                return b
        raise ModelError(f"no flexible link {name!r}; the model has "
                         f"{[b.name for b in self.beams]}")


def _translation_x(x: float) -> np.ndarray:
    t = np.eye(4)
    t[0, 3] = x
    return t


def piece_pseudo_inertia(beam, length: float) -> np.ndarray:
    """(4, 4) pseudo-inertia of the beam piece [0, length] in its beam frame (docstring)."""
    m = beam.density * beam.area * length
    j = np.zeros((4, 4))
    j[0, 0] = m * length * length / 3.0
    j[1, 1] = beam.density * beam.second_moment_z * length
    j[2, 2] = beam.density * beam.second_moment_y * length
    j[0, 3] = j[3, 0] = 0.5 * m * length
    j[3, 3] = m
    return j


def pseudo_inertia(inertia) -> np.ndarray:
    """(4, 4) pseudo-inertia of a gpme RigidBodyInertia (mass, COM, inertia about the COM)."""
    if inertia is None:
        return np.zeros((4, 4))
    m, c = float(inertia.mass), np.asarray(inertia.com_array, dtype=float)
    i_c = np.asarray(inertia.inertia_array, dtype=float)
    sigma = 0.5 * np.trace(i_c) * np.eye(3) - i_c + m * np.outer(c, c)
    j = np.zeros((4, 4))
    j[:3, :3] = sigma
    j[:3, 3] = j[3, :3] = m * c
    j[3, 3] = m
    return j


def from_pseudo_inertia(j: np.ndarray) -> tuple:
    """(mass, com (3,), inertia about the COM (3, 3)) of a pseudo-inertia."""
    m = float(j[3, 3])
    if m <= 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    c = j[:3, 3] / m
    sigma = j[:3, :3] - m * np.outer(c, c)
    return m, c, np.trace(sigma) * np.eye(3) - sigma


def continuum_layout(model) -> ContinuumLayout:
    """:class:`ContinuumLayout` of a gpme model; ModelError when a flexible link cannot be
    a continuum beam (a branch leaving from inside it)."""
    parents = np.asarray(model.parents, dtype=int)
    beams, sde, internal = [], set(), set()
    removed = {}                               # link -> pseudo-inertia of its beam pieces
    for info in model.flexible_links:
        if info.n_segments == 0:
            continue
        n, joints = int(info.n_segments), tuple(info.joint_indices)
        dl = info.beam.length / n
        carrying = int(parents[joints[0]])
        root = np.asarray(model.origins[joints[0]], dtype=float) @ _translation_x(-0.5 * dl)
        tip_link = int(joints[-1])
        piece = piece_pseudo_inertia(info.beam, 0.5 * dl)
        removed[carrying] = removed.get(carrying, 0.0) + root @ piece @ root.T
        removed[tip_link] = removed.get(tip_link, 0.0) + piece
        beams.append(BeamPart(info.name, info.beam, n, carrying, root, tip_link,
                              _translation_x(0.5 * dl), joints,
                              tuple(k for k in info.link_indices if k != tip_link)))
        sde.update(joints)
        internal.update(k for k in info.link_indices if k != tip_link)
    bodies = {}
    for k, link in enumerate(model.links):
        if k in internal:
            continue
        j_link = pseudo_inertia(link.inertia)
        residual = j_link - removed.get(k, 0.0)
        m_link = float(j_link[3, 3])
        if k in removed and residual[3, 3] <= RESIDUAL_MASS_TOL * max(m_link, 1e-300):
            if residual[3, 3] < -RESIDUAL_MASS_TOL * max(m_link, 1e-300):
                raise ModelError(f"link {link.name!r}: its mass {m_link:.6g} kg is less than "
                                 f"the beam pieces it carries ({float(removed[k][3, 3]):.6g} kg)")
            bodies[k] = RigidPart(k, link.name, 0.0, np.zeros(3), np.zeros((3, 3)))
            continue
        m, c, i_c = from_pseudo_inertia(residual)
        bodies[k] = RigidPart(k, link.name, m, c, i_c)
    kept = []
    for k in range(model.n_coordinates):
        if k in sde:
            continue
        if int(parents[k]) in internal:
            raise ModelError(f"joint {model.joints[k].name!r} leaves from inside flexible link "
                             f"{model.links[int(parents[k])].name!r}; the continuum model attaches "
                             "joints at a beam's root or tip only")
        kept.append(k)
    return ContinuumLayout(bodies, tuple(kept), tuple(beams), parents)

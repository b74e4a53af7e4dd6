"""Rigid-body inertia and the 4x4 pseudo-inertia matrix H of the trace formulation.

For a body with mass m, centre of mass c (body frame) and inertia tensor I_C about
the centre of mass (body axes),

    H = integral over the body of r r^T dm,   r = (x, y, z, 1) in the body frame,

so that  H[:3, :3] = J_C + m c c^T  with  J_C = tr(I_C)/2 * E - I_C,
         H[:3, 3] = H[3, :3] = m c,  H[3, 3] = m.

A constant change of frame X (4, 4), with r_a = X r_b, gives H_a = X H_b X^T.
"""
from dataclasses import dataclass

import numpy as np

from .errors import ModelError

# Relative tolerance of the inertia checks: the eigenvalues of I_C from eigvalsh and from a
# rotation R I R^T (an <inertial rpy>, a frame change) carry round-off of a few eps * max|I|;
# 1e-12 * max|I| is far above that (~1e-15) and far below any physical principal moment
# worth keeping (a real body thinner than 1e-6 of its size in two directions).
_INERTIA_TOL = 1e-12
# m: a moment of inertia below mass * POINT_SIZE^2 is that of a body smaller than a micron,
# indistinguishable from a point mass; such moments are accepted whatever their sign
# (URDFs write point masses as 'ixz="2.4e-35"').
POINT_SIZE = 1e-6


@dataclass(frozen=True)
class RigidBodyInertia:
    """Mass properties of one rigid body.

    mass    : kg, >= 0 (0 with a zero tensor is no body at all; 0 with a non-zero tensor
              is a pure rotational inertia, e.g. a rotor whose mass is counted elsewhere)
    com     : (3,) m, centre of mass in the body frame
    inertia : (3, 3) kg m^2, about the centre of mass, body axes; symmetric positive
              semi-definite (zero for a point mass, one zero moment for a thin rod).  A
              real body also has I1 + I2 >= I3 (the triangle inequality of its principal
              moments); a tensor that breaks it is accepted, as Pinocchio accepts it
              (robot descriptions carry such CAD round-off), and said by
              :meth:`non_physical`: what matters to the dynamics is that the chain's mass
              matrix is positive definite, which the model checks at its start and every
              run's reduced solve along the run.

    Whether a chain of such bodies can move is the mass matrix's business: a point mass on
    the axis of its own revolute joint gives a singular M, which gpme_core.model's
    validation reports naming the coordinates.
    """

    mass: float
    com: tuple = (0.0, 0.0, 0.0)
    inertia: tuple = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))

    def __post_init__(self):
        object.__setattr__(self, "com", tuple(float(c) for c in np.ravel(self.com)))
        inertia = np.asarray(self.inertia, dtype=float)
        object.__setattr__(self, "inertia", tuple(tuple(row) for row in inertia))

    @property
    def com_array(self):
        """(3,) m."""
        return np.array(self.com)

    @property
    def inertia_array(self):
        """(3, 3) kg m^2 about the centre of mass."""
        return np.array(self.inertia)

    def problems(self, label):
        """List of human-readable problems with this inertia (empty when valid)."""
        out = []
        m = self.mass
        if not np.isfinite(m) or m < 0.0:
            out.append(f"{label}: mass must be positive and finite, got {m!r} kg (or exactly "
                       "0 kg for a massless body)")
        c = np.array(self.com)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            out.append(f"{label}: centre of mass must be 3 finite numbers in m, got {self.com!r}")
        inertia = np.array(self.inertia)
        if inertia.shape != (3, 3) or not np.all(np.isfinite(inertia)):
            out.append(f"{label}: inertia must be a finite (3, 3) matrix, got shape {inertia.shape}")
            return out
        if not np.allclose(inertia, inertia.T, rtol=1e-12, atol=1e-15):
            out.append(f"{label}: inertia tensor must be symmetric, got {inertia.tolist()}")
            return out
        eig = np.linalg.eigvalsh(inertia)
        if eig.min() < -_moment_tolerance(eig, m):
            out.append(f"{label}: inertia tensor must be positive definite or semi-definite "
                       f"(no negative principal moment), got principal moments {eig.tolist()} "
                       "kg m^2")
        return out

    def triangle_excess(self):
        """kg m^2: I3 - (I1 + I2) of the principal moments I1 <= I2 <= I3 beyond round-off
        (the inertia checks' tolerance), 0.0 for a tensor a physical body can have."""
        eig = np.linalg.eigvalsh(self.inertia_array)
        excess = float(eig[2] - eig[0] - eig[1])
        return excess if excess > _moment_tolerance(eig, self.mass) else 0.0

    def non_physical(self, label):
        """What is not physical about this (valid) inertia, accepted all the same: the
        principal moments breaking the triangle inequality I1 + I2 >= I3.  [] or one line
        starting with ``label``."""
        if self.problems(label) or self.triangle_excess() == 0.0:
            return []
        eig = np.linalg.eigvalsh(self.inertia_array)
        return [f"{label}: principal moments {[float(f'{e:.4g}') for e in eig]} kg m^2 break "
                f"the triangle inequality I1 + I2 >= I3 of a physical body (I3 exceeds I1 + I2 "
                f"by {self.triangle_excess():.3g} kg m^2); accepted, as Pinocchio accepts it: "
                "the mass matrix is checked positive definite instead"]

    def pseudo_inertia(self):
        """(4, 4) kg m^2 / kg m / kg pseudo-inertia H in the body frame."""
        return pseudo_inertia(self.mass, self.com_array, self.inertia_array)


def _moment_tolerance(moments, mass):
    """kg m^2: what a principal moment may be off by and still count as round-off (or a
    point mass): _INERTIA_TOL of the largest moment, or the moment of a POINT_SIZE body."""
    return max(_INERTIA_TOL * abs(moments).max(), mass * POINT_SIZE ** 2 if mass > 0 else 0.0)


def pseudo_inertia(mass, com, inertia_about_com):
    """(4, 4) pseudo-inertia from mass (kg), com (3,) m and I_C (3, 3) kg m^2."""
    c = np.asarray(com, dtype=float)
    i_c = np.asarray(inertia_about_com, dtype=float)
    h = np.zeros((4, 4))
    h[:3, :3] = 0.5 * np.trace(i_c) * np.eye(3) - i_c + mass * np.outer(c, c)
    h[:3, 3] = mass * c
    h[3, :3] = mass * c
    h[3, 3] = mass
    return h


def inertia_from_pseudo(h):
    """Inverse of :func:`pseudo_inertia`: returns (mass, com (3,), I_C (3, 3)).

    A massless H (H[3, 3] == 0) returns com = 0 and the rotational inertia its 3x3 block
    holds (zero for no body at all).
    """
    mass = h[3, 3]
    if mass <= 0.0:
        j = h[:3, :3]
        i_c = np.trace(j) * np.eye(3) - j
        return 0.0, np.zeros(3), 0.5 * (i_c + i_c.T)
    c = h[:3, 3] / mass
    j_c = h[:3, :3] - mass * np.outer(c, c)
    i_c = np.trace(j_c) * np.eye(3) - j_c
    return mass, c, 0.5 * (i_c + i_c.T)


def transform_pseudo_inertia(x, h):
    """Express H (4, 4) given in frame b in frame a, where r_a = x @ r_b."""
    return x @ h @ x.T


def cuboid(mass, size, com=(0.0, 0.0, 0.0)):
    """Solid box of side lengths size = (lx, ly, lz) m centred on ``com``."""
    lx, ly, lz = size
    k = mass / 12.0
    return RigidBodyInertia(mass, com, np.diag([k * (ly ** 2 + lz ** 2), k * (lx ** 2 + lz ** 2),
                                                k * (lx ** 2 + ly ** 2)]))


def cylinder(mass, radius, length, axis=2, com=(0.0, 0.0, 0.0), inner_radius=0.0):
    """Solid (or hollow, inner_radius > 0) cylinder with its axis along body axis ``axis``."""
    r2 = radius ** 2 + inner_radius ** 2
    axial = 0.5 * mass * r2
    transverse = mass * (3.0 * r2 + length ** 2) / 12.0
    moments = [transverse] * 3
    moments[axis] = axial
    return RigidBodyInertia(mass, com, np.diag(moments))


def check_pseudo_inertia(h, label="H"):
    """Raise ModelError unless h is a (4, 4) pseudo-inertia of a physical body (mass >= 0,
    I_C positive semi-definite; the triangle inequality is RigidBodyInertia.non_physical's)."""
    h = np.asarray(h, dtype=float)
    if h.shape != (4, 4):
        raise ModelError(f"{label}: expected shape (4, 4), got {h.shape}")
    if not h[3, 3] >= 0.0:      # inertia_from_pseudo reads H[3, 3] <= 0 as massless
        raise ModelError(f"{label}: mass H[3, 3] = {h[3, 3]!r} kg must be >= 0 (finite)")
    mass, com, i_c = inertia_from_pseudo(h)
    problems = RigidBodyInertia(mass, com, i_c).problems(label)
    if problems:
        raise ModelError(problems)

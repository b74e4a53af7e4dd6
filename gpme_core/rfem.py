"""Rigid finite element method (RFEM) discretisation of a flexible link.

Method as in Wittbrodt, Adamiec-Wojcik and Wojciech, *Dynamics of Flexible Multibody
Systems: Rigid Finite Element Method*, Springer 2006, ch. 3 (after Kruszewski et al.,
1975):

* primary division: the beam of length L, lying along +x of the link frame it is
  attached to, is cut into n equal segments of length dl = L / n;
* a spring-damping element (sde) is put at the middle of each segment; it has three
  rotational coordinates applied in the order psi about z, theta about y, phi about x
  (R = Rz(psi) Ry(theta) Rx(phi)), i.e. three revolute joints at one point;
* secondary division: the sdes cut the beam into n + 1 rigid finite elements (rfe):
  rfe 0 and rfe n have length dl / 2, the others dl;
* each rfe has the mass and inertia of its piece of beam (density rho, area A, second
  moments I_y = int z^2 dA, I_z = int y^2 dA):
  m = rho A l, centre at l/2 on x, I_xx = rho (I_y + I_z) l,
  I_yy = rho I_y l + m l^2 / 12, I_zz = rho I_z l + m l^2 / 12;
* sde r springs: s_psi = E I_z / dl (bending about z), s_theta = E I_y / dl
  (bending about y), s_phi = G J / dl (torsion); dampers of the same form with the
  material viscosities (Kelvin-Voigt): d_psi = eta_E I_z / dl, d_theta = eta_E I_y / dl,
  d_phi = eta_G J / dl.  They enter V = 1/2 q^T S q and R = 1/2 q_dot^T D q_dot.

n = 0 is the rigid link: one body of length L.
"""
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import transforms as tf
from .errors import ModelError
from .inertia import RigidBodyInertia
from .model import REVOLUTE, FlexibleLinkInfo

# joint axis, coordinate prefix, which stiffness; order psi (z), theta (y), phi (x)
SDE_ROTATIONS = (("psi", (0.0, 0.0, 1.0)), ("theta", (0.0, 1.0, 0.0)), ("phi", (1.0, 0.0, 0.0)))


@dataclass(frozen=True)
class BeamProperties:
    """A straight prismatic beam along +x of the link frame.

    length            : m
    youngs_modulus    : E, Pa
    shear_modulus     : G, Pa
    density           : rho, kg/m^3
    area              : A, m^2
    second_moment_y   : I_y = int z^2 dA, m^4 (bending about y)
    second_moment_z   : I_z = int y^2 dA, m^4 (bending about z)
    torsion_constant  : J, m^4 (Saint-Venant)
    bending_viscosity : eta_E, Pa s (Kelvin-Voigt; 0 = undamped)
    torsion_viscosity : eta_G, Pa s; None means eta_E * G / E
    """

    length: float
    youngs_modulus: float
    shear_modulus: float
    density: float
    area: float
    second_moment_y: float
    second_moment_z: float
    torsion_constant: float
    bending_viscosity: float = 0.0
    torsion_viscosity: Optional[float] = None

    @classmethod
    def solid_circular(cls, length, diameter, youngs_modulus, shear_modulus, density,
                       bending_viscosity=0.0, torsion_viscosity=None):
        """Solid round bar of ``diameter`` m."""
        r = 0.5 * diameter
        i = np.pi * r ** 4 / 4.0
        return cls(length, youngs_modulus, shear_modulus, density, np.pi * r ** 2, i, i,
                   2.0 * i, bending_viscosity, torsion_viscosity)

    @property
    def eta_g(self):
        """Pa s, torsion viscosity."""
        if self.torsion_viscosity is not None:
            return self.torsion_viscosity
        return self.bending_viscosity * self.shear_modulus / self.youngs_modulus

    @property
    def mass(self):
        """kg."""
        return self.density * self.area * self.length

    def problems(self, label):
        out = []
        for fld in ("length", "youngs_modulus", "shear_modulus", "density", "area",
                    "second_moment_y", "second_moment_z", "torsion_constant"):
            v = getattr(self, fld)
            if not np.isfinite(v) or v <= 0:
                out.append(f"{label}: {fld} must be positive and finite, got {v!r}")
        for fld in ("bending_viscosity", "torsion_viscosity"):
            v = getattr(self, fld)
            if v is not None and (not np.isfinite(v) or v < 0):
                out.append(f"{label}: {fld} must be >= 0 (Pa s), got {v!r}")
        return out

    def element_inertia(self, piece_length):
        """RigidBodyInertia of a piece of ``piece_length`` m starting at the frame origin."""
        m = self.density * self.area * piece_length
        iy = self.density * self.second_moment_y * piece_length + m * piece_length ** 2 / 12.0
        iz = self.density * self.second_moment_z * piece_length + m * piece_length ** 2 / 12.0
        ix = self.density * (self.second_moment_y + self.second_moment_z) * piece_length
        return RigidBodyInertia(m, (0.5 * piece_length, 0.0, 0.0), np.diag([ix, iy, iz]))

    def sde_coefficients(self, n_segments):
        """((s_psi, s_theta, s_phi), (d_psi, d_theta, d_phi)) of one sde for n segments."""
        dl = self.length / n_segments
        stiff = (self.youngs_modulus * self.second_moment_z / dl,
                 self.youngs_modulus * self.second_moment_y / dl,
                 self.shear_modulus * self.torsion_constant / dl)
        damp = (self.bending_viscosity * self.second_moment_z / dl,
                self.bending_viscosity * self.second_moment_y / dl,
                self.eta_g * self.torsion_constant / dl)
        return stiff, damp


def sde_coordinate_name(beam_name, r, rotation):
    """Name of rotation ``rotation`` ('psi', 'theta', 'phi') of sde r of beam ``beam_name``."""
    return f"{rotation}_{beam_name}_{r}"


def rfe_link_name(beam_name, r):
    """Name of rigid finite element r of beam ``beam_name``."""
    return f"{beam_name}_rfe{r}"


def discretise_beam(builder, name, beam, n_segments):
    """Add the RFEM discretisation of ``beam`` to ``builder`` on its current link.

    The current link receives rigid element 0; n_segments sdes (3 revolute joints each)
    and rigid elements 1..n follow.  Afterwards the builder's next joint, body or frame
    attaches at the beam tip: x = dl/2 in the frame of rigid element n (x = L on the
    carrying link when n = 0).
    """
    problems = beam.problems(f"beam {name!r}")
    if not isinstance(n_segments, (int, np.integer)) or n_segments < 0:
        problems.append(f"beam {name!r}: number of segments must be an integer >= 0, "
                        f"got {n_segments!r}")
    if builder.n_joints == 0:
        problems.append(f"beam {name!r}: add the joint that carries the beam first")
    if problems:
        raise ModelError(problems)
    n = int(n_segments)
    if n == 0:
        builder.add_body(beam.element_inertia(beam.length))
        builder._set_pending_origin(tf.translation(beam.length))
        builder.record_flexible_link(FlexibleLinkInfo(name, beam, 0, (), ()))
        return
    dl = beam.length / n
    builder.add_body(beam.element_inertia(0.5 * dl))          # rfe 0 on the carrying link
    stiff, damp = beam.sde_coefficients(n)
    joints, links = [], []
    for r in range(1, n + 1):
        offset = tf.translation(0.5 * dl if r == 1 else dl)
        for k, (rot, axis) in enumerate(SDE_ROTATIONS):
            last = k == len(SDE_ROTATIONS) - 1
            link = rfe_link_name(name, r) if last else f"{name}_sde{r}_{rot}"
            idx = builder.add_joint(sde_coordinate_name(name, r, rot), REVOLUTE, axis,
                                    origin=offset if k == 0 else np.eye(4),
                                    stiffness=stiff[k], damping=damp[k], link=link)
            joints.append(idx)
            links.append(idx)
        builder.add_body(beam.element_inertia(dl if r < n else 0.5 * dl))
    builder._set_pending_origin(tf.translation(0.5 * dl))
    builder.record_flexible_link(FlexibleLinkInfo(name, beam, n, tuple(joints), tuple(links)))

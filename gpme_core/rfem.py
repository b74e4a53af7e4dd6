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

The beam may lie along any direction of its link: :meth:`ChainBuilder.add_beam` takes the
beam frame B (x along the beam, y and z the section's principal axes) in the link frame,
and the discretisation above is done in B.

Cross-sections (:class:`BeamSection`): solid circle and circular tube (exact), rectangle
(Saint-Venant torsion constant from Roark's formula, see :meth:`BeamSection.rectangle`),
hollow rectangle (Bredt's closed thin-walled formula, see
:meth:`BeamSection.hollow_rectangle`).  Each carries its extreme fibre distances, which
:meth:`BeamProperties.bending_stress` uses for the peak bending stress at an sde.

A torsion constant that no section can have: Saint-Venant's theory gives J <= I_p =
I_y + I_z for every section, with equality only for circular ones (solid or tube, whose
sections do not warp).  ``problems()`` reports J > I_y + I_z; a J equal to I_y + I_z with
I_y != I_z (a circle's formula on another shape) is legal but warned about
(:class:`gpme_core.errors.SectionWarning`).
"""
import warnings
from dataclasses import dataclass
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import geometry, transforms as tf
from .errors import ModelError, SectionWarning
from .inertia import RigidBodyInertia
from .joint_kinds import REVOLUTE

# joint axis, coordinate prefix, which stiffness; order psi (z), theta (y), phi (x)
SDE_ROTATIONS = (("psi", (0.0, 0.0, 1.0)), ("theta", (0.0, 1.0, 0.0)), ("phi", (1.0, 0.0, 0.0)))


# J <= I_y + I_z "beyond round-off": constants computed in double precision from one
# formula (a circle's J = 2 I) agree to a few ulp; 1e-9 relative leaves room for a value
# written out with 10 significant digits.
POLAR_ROUND_OFF = 1e-9
# most RFEM segments of one beam: 3 coordinates each, so 3000 coordinates, whose mass
# matrix alone is 72 MB and whose RK4 step costs seconds; RFEM's bending-frequency error
# falls as 1/n^2 (+0.19 % at n = 20, docs/rfem.md), ~1e-6 at n = 1000, far below what any
# section or material value is known to.  Checked from the number, before any building
# (100,000 segments used to be refused only after a minute of model building).
MAX_SEGMENTS = 1000


def _positive_problems(label, **values):
    """'label: name must be positive and finite (unit), got v' for each bad value."""
    out = []
    for key, (v, unit) in values.items():
        try:
            ok = bool(np.isfinite(v) and v > 0)
        except TypeError:
            ok = False
        if not ok:
            out.append(f"{label}: {key} must be positive and finite ({unit}), got {v!r}")
    return out


def _is_positive(v) -> bool:
    try:
        return bool(np.isfinite(v) and v > 0)
    except TypeError:
        return False


def _torsion_problems(label, i_y, i_z, j) -> list:
    """'J exceeds the polar moment' when J > (I_y + I_z)(1 + POLAR_ROUND_OFF) (all positive)."""
    if not all(_is_positive(v) for v in (i_y, i_z, j)):
        return []        # reported by _positive_problems
    i_p = i_y + i_z
    if j > i_p * (1.0 + POLAR_ROUND_OFF):
        return [f"{label}: torsion_constant J = {j:.10g} m^4 exceeds the polar moment I_y + I_z "
                f"= {i_p:.10g} m^4 (I_y = {i_y:.10g}, I_z = {i_z:.10g}); by Saint-Venant torsion theory "
                "J <= I_y + I_z for every section, with equality only for a circle or "
                "circular tube (a rectangle has less, e.g. 0.141 a^4 against 0.167 a^4 for a "
                "square of side a)"]
    return []


def solid_rectangle_torsion_constant(second_moment_y: float, second_moment_z: float) -> float:
    """J, m^4, of the solid rectangle that has these second moments (m^4), by Roark's
    formula (see :meth:`BeamSection.rectangle`): w/h = sqrt(I_z/I_y), w h =
    (144 I_y I_z)^(1/4).  Used to say what a non-circular section's J would be."""
    aspect = np.sqrt(second_moment_z / second_moment_y)           # w / h
    area = (144.0 * second_moment_y * second_moment_z) ** 0.25    # w h
    return BeamSection.rectangle(np.sqrt(area * aspect), np.sqrt(area / aspect)).torsion_constant


def _warn_circular_torsion(label, i_y, i_z, j):
    """SectionWarning when J = I_y + I_z (within POLAR_ROUND_OFF) while I_y != I_z."""
    if not all(_is_positive(v) for v in (i_y, i_z, j)):
        return
    i_p = i_y + i_z
    if abs(j - i_p) <= POLAR_ROUND_OFF * i_p and abs(i_y - i_z) > POLAR_ROUND_OFF * i_p:
        j_rect = solid_rectangle_torsion_constant(i_y, i_z)
        warnings.warn(
            f"{label}: torsion_constant J = {j:.10g} m^4 equals I_y + I_z = {i_p:.10g} m^4 while "
            f"I_y = {i_y:.10g} != I_z = {i_z:.10g} m^4: the polar moment is J only for a circular "
            f"section, which has I_y = I_z; a solid rectangle with these I_y, I_z has "
            f"Saint-Venant J = {j_rect:.6g} m^4 (Roark). Use the section's own torsion "
            "constant (BeamSection.rectangle, hollow_rectangle).", SectionWarning, stacklevel=4)


@dataclass(frozen=True)
class BeamSection:
    """Cross-section of a straight prismatic beam, in the beam frame's (y, z) plane.

    area             : A, m^2
    second_moment_y  : I_y = int z^2 dA, m^4 (bending about y, deflection along z)
    second_moment_z  : I_z = int y^2 dA, m^4 (bending about z, deflection along y)
    torsion_constant : J, m^4, Saint-Venant (G J = torsional rigidity); J <= I_y + I_z
    name             : a readable description, e.g. "tube 40 x 2 mm"
    extreme_fibre_y  : c_y, m, largest |y| of the section (the fibre of peak stress under
                       bending about z); None = unknown
    extreme_fibre_z  : c_z, m, largest |z| of the section (bending about y); None = unknown

    Build it with :meth:`solid_circle`, :meth:`tube`, :meth:`rectangle` or
    :meth:`hollow_rectangle` (they validate their inputs), or directly for another shape
    (validated by :meth:`problems`).
    """

    area: float
    second_moment_y: float
    second_moment_z: float
    torsion_constant: float
    name: str = "section"
    extreme_fibre_y: Optional[float] = None
    extreme_fibre_z: Optional[float] = None

    def problems(self, label: str = "section") -> list:
        """Problems of this section (empty when valid): every constant positive and finite,
        J <= I_y + I_z, extreme fibre distances (when given) positive and finite."""
        out = _positive_problems(
            label, area=(self.area, "m^2"), second_moment_y=(self.second_moment_y, "m^4"),
            second_moment_z=(self.second_moment_z, "m^4"),
            torsion_constant=(self.torsion_constant, "m^4"))
        out += _torsion_problems(label, self.second_moment_y, self.second_moment_z,
                                 self.torsion_constant)
        out += _fibre_problems(label, self.extreme_fibre_y, self.extreme_fibre_z)
        return out

    @classmethod
    def solid_circle(cls, diameter: float) -> "BeamSection":
        """Solid round bar of ``diameter`` m: A = pi d^2/4, I_y = I_z = pi d^4/64,
        J = I_y + I_z = pi d^4/32 (exact for a circle)."""
        bad = _positive_problems("solid_circle", diameter=(diameter, "m"))
        if bad:
            raise ModelError(bad)
        r = 0.5 * float(diameter)
        i = np.pi * r ** 4 / 4.0
        return cls(np.pi * r ** 2, i, i, 2.0 * i, f"solid circle d = {diameter:g} m", r, r)

    @classmethod
    def tube(cls, outer_diameter: float, wall_thickness: float) -> "BeamSection":
        """Circular tube: outer diameter and wall thickness in m, 0 < wall < outer radius.

        A = pi (r_o^2 - r_i^2), I_y = I_z = pi (r_o^4 - r_i^4)/4, J = the polar moment
        I_y + I_z (exact for a closed circular tube: its cross-sections do not warp).
        """
        bad = _positive_problems("tube", outer_diameter=(outer_diameter, "m"),
                                 wall_thickness=(wall_thickness, "m"))
        if not bad and not wall_thickness < 0.5 * outer_diameter:
            bad.append(f"tube: wall_thickness {wall_thickness!r} m must be smaller than the "
                       f"outer radius {0.5 * outer_diameter!r} m (use solid_circle for a "
                       "solid bar)")
        if bad:
            raise ModelError(bad)
        r_o = 0.5 * float(outer_diameter)
        r_i = r_o - float(wall_thickness)
        i = np.pi * (r_o ** 4 - r_i ** 4) / 4.0
        return cls(np.pi * (r_o ** 2 - r_i ** 2), i, i, 2.0 * i,
                   f"tube {outer_diameter:g} x {wall_thickness:g} m", r_o, r_o)

    @classmethod
    def rectangle(cls, width_y: float, height_z: float) -> "BeamSection":
        """Solid rectangle, ``width_y`` m along the beam frame's y, ``height_z`` m along z.

        A = w h, I_y = w h^3/12, I_z = h w^3/12.  Saint-Venant torsion constant from
        Roark's formula (Young and Budynas, *Roark's Formulas for Stress and Strain*, 7th
        ed., table 10.7, case 4, written with full side lengths a >= b):

            J = a b^3 [1/3 - 0.21 (b/a) (1 - b^4 / (12 a^4))].

        Against the exact series of Saint-Venant's solution (Timoshenko and Goodier,
        *Theory of Elasticity*, sec. 109) its error is below 0.5 % for every aspect ratio
        (largest, 0.49 %, near a/b = 1.14; 0.18 % for a square; -> 0 for a thin strip);
        tests/test_urdf_reader.py checks this against the series.
        """
        bad = _positive_problems("rectangle", width_y=(width_y, "m"), height_z=(height_z, "m"))
        if bad:
            raise ModelError(bad)
        w, h = float(width_y), float(height_z)
        a, b = max(w, h), min(w, h)
        j = a * b ** 3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b ** 4 / (12.0 * a ** 4)))
        return cls(w * h, w * h ** 3 / 12.0, h * w ** 3 / 12.0, j,
                   f"rectangle {width_y:g} x {height_z:g} m", 0.5 * w, 0.5 * h)

    @classmethod
    def hollow_rectangle(cls, width_y: float, height_z: float,
                         wall_thickness: float) -> "BeamSection":
        """Closed rectangular hollow section (box), outer ``width_y`` m along the beam
        frame's y, outer ``height_z`` m along z, uniform ``wall_thickness`` t m,
        0 < t < min(width_y, height_z) / 2 (sharp corners).

        A = w h - w_i h_i, I_y = (w h^3 - w_i h_i^3)/12, I_z = (h w^3 - h_i w_i^3)/12 with
        w_i = w - 2t, h_i = h - 2t (exact).  Torsion constant from Bredt's formula for a
        closed thin-walled section (Young and Budynas, *Roark's Formulas for Stress and
        Strain*, 7th ed., table 10.7, case 16, hollow rectangle, with both wall
        thicknesses t; Timoshenko and Goodier, *Theory of Elasticity*, sec. 115):

            J = 4 A_m^2 t / p_m = 2 t (w - t)^2 (h - t)^2 / (w + h - 2 t),

        A_m = (w - t)(h - t) the area and p_m = 2 (w + h - 2 t) the perimeter enclosed by
        the wall's mid-line.  Accuracy: thin-wall theory, it *underestimates* J by about
        t / (2 b), b = min(w, h) (the corner material carries shear flow the mid-line model
        misses).  Against a finite-difference solution of Prandtl's stress-function problem
        (tests/test_sections.py): square box 1.1 % low at t/b = 0.025, 2.4 % at 0.05, 5.4 %
        at 0.1, 13 % at 0.2; 2:1 box 1.6 % at t/b = 0.05, 3.5 % at 0.1.  For t/b > 0.1
        prefer a computed J (give the constants directly).
        """
        bad = _positive_problems("hollow_rectangle", width_y=(width_y, "m"),
                                 height_z=(height_z, "m"), wall_thickness=(wall_thickness, "m"))
        if not bad and not wall_thickness < 0.5 * min(width_y, height_z):
            bad.append(f"hollow_rectangle: wall_thickness {wall_thickness!r} m must be smaller "
                       f"than half the smaller side, {0.5 * min(width_y, height_z)!r} m (use "
                       "rectangle for a solid section)")
        if bad:
            raise ModelError(bad)
        w, h, t = float(width_y), float(height_z), float(wall_thickness)
        wi, hi = w - 2.0 * t, h - 2.0 * t
        j = 2.0 * t * (w - t) ** 2 * (h - t) ** 2 / (w + h - 2.0 * t)
        return cls(w * h - wi * hi, (w * h ** 3 - wi * hi ** 3) / 12.0,
                   (h * w ** 3 - hi * wi ** 3) / 12.0, j,
                   f"hollow rectangle {width_y:g} x {height_z:g} x {wall_thickness:g} m",
                   0.5 * w, 0.5 * h)


def _fibre_problems(label, c_y, c_z) -> list:
    out = []
    for key, v in (("extreme_fibre_y", c_y), ("extreme_fibre_z", c_z)):
        if v is not None and not _is_positive(v):
            out.append(f"{label}: {key} must be positive and finite (m) or None (unknown), "
                       f"got {v!r}")
    return out



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
    torsion_constant  : J, m^4 (Saint-Venant), J <= I_y + I_z
    bending_viscosity : eta_E, Pa s (Kelvin-Voigt; 0 = undamped)
    torsion_viscosity : eta_G, Pa s; None means eta_E * G / E
    extreme_fibre_y   : c_y, m, largest |y| of the section (bending about z); None = unknown
    extreme_fibre_z   : c_z, m, largest |z| of the section (bending about y); None = unknown

    :meth:`from_section` and :meth:`solid_circular` fill the extreme fibres; constructing
    it directly with J = I_y + I_z and I_y != I_z warns (:class:`SectionWarning`).
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
    extreme_fibre_y: Optional[float] = None
    extreme_fibre_z: Optional[float] = None

    def __post_init__(self):
        _warn_circular_torsion("beam", self.second_moment_y, self.second_moment_z,
                               self.torsion_constant)

    @classmethod
    def solid_circular(cls, length, diameter, youngs_modulus, shear_modulus, density,
                       bending_viscosity=0.0, torsion_viscosity=None):
        """Solid round bar of ``diameter`` m."""
        r = 0.5 * diameter
        i = np.pi * r ** 4 / 4.0
        return cls(length, youngs_modulus, shear_modulus, density, np.pi * r ** 2, i, i,
                   2.0 * i, bending_viscosity, torsion_viscosity, r, r)

    @classmethod
    def from_section(cls, length: float, section: BeamSection, youngs_modulus: float,
                     shear_modulus: float, density: float, bending_viscosity: float = 0.0,
                     torsion_viscosity: Optional[float] = None) -> "BeamProperties":
        """Beam of ``length`` m with cross-section ``section`` (E, G in Pa, density kg/m^3,
        viscosities Pa s as in the class docstring); the section's extreme fibres too."""
        if not isinstance(section, BeamSection):
            raise ModelError(f"section must be a gpme_core.rfem.BeamSection, got "
                             f"{type(section).__name__}")
        return cls(length, youngs_modulus, shear_modulus, density, section.area,
                   section.second_moment_y, section.second_moment_z, section.torsion_constant,
                   bending_viscosity, torsion_viscosity, section.extreme_fibre_y,
                   section.extreme_fibre_z)

    @property
    def is_circular(self) -> bool:
        """True when the constants are those of a circular section (solid or tube):
        I_y = I_z, J = I_y + I_z (Saint-Venant: only a circular section has J = I_p) and
        c_y = c_z, each to POLAR_ROUND_OFF relative."""
        i_p = self.second_moment_y + self.second_moment_z
        tol = POLAR_ROUND_OFF * i_p
        return (abs(self.second_moment_y - self.second_moment_z) <= tol
                and abs(self.torsion_constant - i_p) <= tol
                and self.extreme_fibre_y is not None and self.extreme_fibre_z is not None
                and abs(self.extreme_fibre_y - self.extreme_fibre_z)
                <= POLAR_ROUND_OFF * max(self.extreme_fibre_y, self.extreme_fibre_z))

    def bending_stress(self, psi: ArrayLike, theta: ArrayLike,
                       n_segments: int) -> NDArray[np.float64]:
        """Peak bending (normal) stress, Pa, at a spring-damping element of this beam
        discretised into ``n_segments`` (>= 1) segments, from its bending angles.

        psi   : rad, the sde's rotation about the section z axis (any shape; numpy arrays
                broadcast), bending in the x-y plane: M_z = (E I_z / dl) psi
        theta : rad, rotation about the section y axis: M_y = (E I_y / dl) theta
        returns sigma >= 0, Pa, same shape as the broadcast of psi and theta

        The moments are those of the sde springs (s_psi = E I_z / dl, s_theta = E I_y / dl,
        dl = L / n_segments), i.e. the bending moment carried through the sde.  Stress:

        * non-circular sections: sigma = |M_y| c_z / I_y + |M_z| c_y / I_z, the stress at a
          corner (|y| = c_y, |z| = c_z); exact for a rectangle or hollow rectangle, whose
          corner is the fibre of peak stress, and an upper bound for any section;
        * circular sections (:attr:`is_circular`): the exact peak on the outer radius c,
          sigma = sqrt(M_y^2 + M_z^2) c / I (the corner sum would overestimate it by up to
          sqrt 2, at psi = theta).

        Axial force, shear and torsion stresses are not included.  Raises ModelError when
        the extreme fibre distances are unknown (None) or n_segments is not an integer >= 1.
        """
        bad = []
        if self.extreme_fibre_y is None or self.extreme_fibre_z is None:
            bad.append("bending_stress: extreme_fibre_y and extreme_fibre_z are unknown "
                       f"(got {self.extreme_fibre_y!r}, {self.extreme_fibre_z!r}); build the "
                       "beam with BeamProperties.from_section or give them (m)")
        if not isinstance(n_segments, (int, np.integer)) or isinstance(n_segments, bool) \
                or n_segments < 1:
            bad.append(f"bending_stress: n_segments must be an integer >= 1 (the stress is "
                       f"at an sde), got {n_segments!r}")
        if bad:
            raise ModelError(bad)
        dl = self.length / int(n_segments)
        m_z = self.youngs_modulus * self.second_moment_z / dl * np.asarray(psi, dtype=float)
        m_y = self.youngs_modulus * self.second_moment_y / dl * np.asarray(theta, dtype=float)
        if self.is_circular:
            return np.hypot(m_y, m_z) * self.extreme_fibre_y / self.second_moment_z
        return (np.abs(m_y) * self.extreme_fibre_z / self.second_moment_y
                + np.abs(m_z) * self.extreme_fibre_y / self.second_moment_z)

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
        """Problems of these properties (empty when valid)."""
        out = _positive_problems(
            label, length=(self.length, "m"), youngs_modulus=(self.youngs_modulus, "Pa"),
            shear_modulus=(self.shear_modulus, "Pa"), density=(self.density, "kg/m^3"),
            area=(self.area, "m^2"), second_moment_y=(self.second_moment_y, "m^4"),
            second_moment_z=(self.second_moment_z, "m^4"),
            torsion_constant=(self.torsion_constant, "m^4"))
        out += _torsion_problems(label, self.second_moment_y, self.second_moment_z,
                                 self.torsion_constant)
        out += _fibre_problems(label, self.extreme_fibre_y, self.extreme_fibre_z)
        for fld in ("bending_viscosity", "torsion_viscosity"):
            v = getattr(self, fld)
            try:
                ok = v is None or bool(np.isfinite(v) and v >= 0)
            except TypeError:
                ok = False
            if not ok:
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


def beam_frame_problems(label: str, frame) -> list:
    """Problems of a beam frame: a (4, 4) rigid transform (proper rotation, last row 0 0 0 1)."""
    t = np.asarray(frame, dtype=float)
    if t.shape != (4, 4):
        return [f"{label}: beam frame must be a (4, 4) transform, got shape {t.shape}"]
    if not np.all(np.isfinite(t)):
        return [f"{label}: beam frame has non-finite entries"]
    out = []
    r = t[:3, :3]
    if not np.allclose(r.T @ r, np.eye(3), rtol=0, atol=1e-9) or np.linalg.det(r) < 0:
        out.append(f"{label}: beam frame rotation is not a proper rotation (R^T R != I or "
                   f"det < 0), got {r.tolist()}")
    if not np.array_equal(t[3], (0.0, 0.0, 0.0, 1.0)):
        out.append(f"{label}: beam frame last row must be (0, 0, 0, 1), got {t[3].tolist()}")
    return out


@dataclass(frozen=True)
class FlexibleLinkInfo:
    """Record of a link discretised by the RFEM (for export and reports)."""

    name: str
    beam: object
    n_segments: int
    joint_indices: tuple
    link_indices: tuple

    def __post_init__(self):
        object.__setattr__(self, "joint_indices", tuple(int(k) for k in self.joint_indices))
        object.__setattr__(self, "link_indices", tuple(int(k) for k in self.link_indices))


def _element_shape(builder, beam, length, frame):
    """The visual shape of a rigid element of ``length`` m from the origin of ``frame``
    along its x axis: a cylinder of the outer radius for a round section (a tube drawn
    solid), a box of the extreme fibres otherwise; none when the section's extreme fibres
    are not known.  Visual only: neighbouring elements touch, and a collision shape would
    make a simulator's contacts between them."""
    c_y, c_z = beam.extreme_fibre_y, beam.extreme_fibre_z
    if c_y is None or c_z is None:
        return
    round_section = c_y == c_z and beam.area <= np.pi * c_y * c_y * (1 + 1e-9)
    kind, size, origin = geometry.member(length, c_y, c_z, round_section, frame)
    builder.add_shape(kind, size, origin, role="visual", rgba=geometry.ELEMENT_RGBA)


def discretise_beam(builder, name, beam, n_segments, frame=None):
    """Add the RFEM discretisation of ``beam`` to ``builder`` on its current link.

    frame : (4, 4) beam frame B in the current link frame (x along the beam from its
            root at B's origin, y and z the section axes of I_z and I_y); None = identity
            (the beam along +x of the link frame).
    The current link receives rigid element 0; n_segments sdes (3 revolute joints each,
    axes z, y, x of B) and rigid elements 1..n follow.  Afterwards the builder's next
    joint, body or frame attaches at the beam tip frame, B moved by L along its x axis
    (x = dl/2 in the frame of rigid element n; B @ translation(L) on the carrying link
    when n = 0).
    """
    problems = beam.problems(f"beam {name!r}")
    if not isinstance(n_segments, (int, np.integer)) or isinstance(n_segments, bool) \
            or not 0 <= n_segments <= MAX_SEGMENTS:
        problems.append(f"beam {name!r}: number of segments must be an integer from 0 to "
                        f"{MAX_SEGMENTS} (gpme_core.rfem.MAX_SEGMENTS), got {n_segments!r}")
    if builder.n_joints == 0:
        problems.append(f"beam {name!r}: add the joint that carries the beam first")
    t_link_beam = np.eye(4) if frame is None else np.asarray(frame, dtype=float)
    problems += beam_frame_problems(f"beam {name!r}", t_link_beam)
    if problems:
        raise ModelError(problems)
    n = int(n_segments)
    pending = builder.pending_origin()                   # link frame -> attachment point
    if n == 0:
        builder.add_body(beam.element_inertia(beam.length), origin=t_link_beam)
        _element_shape(builder, beam, beam.length, t_link_beam)
        builder.set_pending_origin(pending @ t_link_beam @ tf.translation(beam.length))
        builder.record_flexible_link(FlexibleLinkInfo(name, beam, 0, (), ()))
        return
    dl = beam.length / n
    builder.add_body(beam.element_inertia(0.5 * dl), origin=t_link_beam)  # rfe 0
    _element_shape(builder, beam, 0.5 * dl, t_link_beam)
    stiff, damp = beam.sde_coefficients(n)
    joints, links = [], []
    for r in range(1, n + 1):
        offset = t_link_beam @ tf.translation(0.5 * dl) if r == 1 else tf.translation(dl)
        for k, (rot, axis) in enumerate(SDE_ROTATIONS):
            last = k == len(SDE_ROTATIONS) - 1
            link = rfe_link_name(name, r) if last else f"{name}_sde{r}_{rot}"
            idx = builder.add_joint(sde_coordinate_name(name, r, rot), REVOLUTE, axis,
                                    origin=offset if k == 0 else np.eye(4),
                                    stiffness=stiff[k], damping=damp[k], link=link)
            joints.append(idx)
            links.append(idx)
        builder.add_body(beam.element_inertia(dl if r < n else 0.5 * dl))
        _element_shape(builder, beam, dl if r < n else 0.5 * dl, np.eye(4))
    builder.set_pending_origin(tf.translation(0.5 * dl))
    builder.record_flexible_link(FlexibleLinkInfo(name, beam, n, tuple(joints), tuple(links)))

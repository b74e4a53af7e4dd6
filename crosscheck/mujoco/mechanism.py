"""Geometry of the auxiliary mechanism that lets MuJoCo enforce the crane's programmed
constraints itself (docs/mjcf.md has the drawing in words and the reasons).

gpme's constraints on the end-effector E (world frame, SI units):

    Phi_1 = ((x_E - x_c)/a)^2 + ((y_E - y_c)/b)^2 - 1 = 0   (elliptic cylinder, any height)
    Phi_2 = z_E - (z0 + A cos(2 pi t / T)) = 0               (height programme)

MuJoCo realisation (all auxiliary bodies in their own kinematic trees, no contacts):

* crank   : hinge about world y through (x_c + crank_offset, y_c, z0), huge armature, turning
            at omega = 2 pi / T; its pin (site) sits at radius A, straight up at angle 0.
* follower: heavy, gravity-compensated body on a vertical slide; its slide coordinate is
            the height of the ellipse plane above z0.  It carries the two foci (sites).
* yoke    : a light body sliding along world x on the follower; its slot (site) is
            site-connected to the crank pin: a Scotch yoke, so the follower height is
            exactly z0 + A cos(omega t) while the crank turns uniformly.
* puck    : a light body sliding in x and y on the follower, site-connected to E: holds
            z_E at the follower height (Phi_2) and lets E move freely in the plane.
* tendon  : spatial tendon focus_1 - E - focus_2 held at the string length 2 max(a, b) by
            a tendon equality: with the foci at E's height this is exactly Phi_1 = 0.

This module only computes numbers (focus positions, the auxiliary coordinates that match
a crane state); crosscheck.mujoco.mjcf writes them as XML.
"""
from dataclasses import dataclass

import numpy as np

from gpme_core.constraints import CoordinateProgramme, EllipseConstraint
from gpme_core.errors import ModelError
from gpme_core.kinematics import chain_kinematics, point_kinematics
from gpme_core.time_functions import Cosine

# names of the auxiliary joints, in the order they appear in the MJCF (after the crane)
CRANK, FOLLOWER, YOKE, PUCK_X, PUCK_Y = ("aux_crank", "aux_follower", "aux_yoke",
                                         "aux_puck_x", "aux_puck_y")
AUX_JOINTS = (CRANK, FOLLOWER, YOKE, PUCK_X, PUCK_Y)


@dataclass(frozen=True)
class MechanismSettings:
    """Numbers of the auxiliary mechanism (SI units).  Defaults measured in docs/mjcf.md.

    timeconst      : s, solref time constant of the three equality constraints (below
                     2 dt it needs MuJoCo's refsafe disabled, which the writer does)
    dampratio      : solref damping ratio (1 = critical)
    impedance      : solimp dmin = dmax (MuJoCo's largest is 0.9999): the fraction of the
                     reference acceleration imposed; 1 - impedance of the unconstrained
                     acceleration leaks through
    aux_mass       : kg, mass of crank body, yoke and puck (the puck rides with E, so its
                     mass is added to the crane: keep it negligible)
    aux_inertia    : kg m^2, principal moments of those light bodies
    follower_mass  : kg, heavy so that the crane's reactions barely accelerate it
    crank_armature : kg m^2, so that the follower's reactions barely change the crank speed
    crank_offset   : m, crank axis distance along world x from the ellipse centre (only
                     moves it out of the way in a viewer; no effect on the dynamics)
    yoke_timeconst : s, solref time constant of the Scotch-yoke connect; None = timeconst
                     (kept separate so the end-effector constraints can be softened alone)
    """

    timeconst: float = 1e-4
    dampratio: float = 1.0
    impedance: float = 0.9999
    aux_mass: float = 1e-10
    aux_inertia: float = 1e-10
    follower_mass: float = 1e3
    crank_armature: float = 1e12
    crank_offset: float = 1.5
    yoke_timeconst: float = None

    def problems(self):
        """Human-readable problems (empty when valid)."""
        out = []
        for fld in ("timeconst", "dampratio", "aux_mass", "aux_inertia", "follower_mass",
                    "crank_armature"):
            v = getattr(self, fld)
            if not (np.isfinite(v) and v > 0):
                out.append(f"mechanism {fld} must be positive and finite, got {v!r}")
        if not (0.0 < self.impedance <= 0.9999):
            out.append(f"mechanism impedance must be in (0, 0.9999] (MuJoCo's solimp range), "
                       f"got {self.impedance!r}")
        if self.yoke_timeconst is not None and not (np.isfinite(self.yoke_timeconst)
                                                    and self.yoke_timeconst > 0):
            out.append(f"mechanism yoke_timeconst must be positive (s) or None, got "
                       f"{self.yoke_timeconst!r}")
        if not np.isfinite(self.crank_offset):
            out.append(f"mechanism crank_offset must be finite (m), got {self.crank_offset!r}")
        return out


@dataclass(frozen=True)
class EllipticProgramme:
    """The crane's two programmed constraints read from gpme constraint specs.

    a, b        : m, semi-axes along world x and y
    center      : (2,) m, ellipse centre (x_c, y_c) in the world frame
    height      : Cosine, z0 + A cos(2 pi t / T) (m, s)
    frame       : name of the model frame whose origin is constrained (the end-effector)
    names       : (ellipse constraint name, height constraint name)
    """

    a: float
    b: float
    center: tuple
    height: Cosine
    frame: str
    names: tuple

    @property
    def omega(self):
        """rad/s, crank speed 2 pi / T."""
        return self.height.omega

    @property
    def string_length(self):
        """m, focus-E-focus length on the ellipse: twice the major semi-axis."""
        return 2.0 * max(self.a, self.b)

    @property
    def focal_distance(self):
        """m, centre-to-focus distance sqrt(major^2 - minor^2)."""
        return float(np.sqrt(abs(self.b ** 2 - self.a ** 2)))

    def foci_local(self):
        """(2, 3) m, the foci relative to the follower body (at the ellipse centre)."""
        c = self.focal_distance
        axis = np.array([0.0, 1.0, 0.0]) if self.b >= self.a else np.array([1.0, 0.0, 0.0])
        return np.array([-c * axis, c * axis])


def read_programme(model, constraints):
    """EllipticProgramme from gpme constraint specs; ModelError listing every problem.

    Supported: exactly one EllipseConstraint and one CoordinateProgramme on world z with a
    Cosine time function, both on the same model frame.
    """
    constraints = tuple(constraints)
    ellipses = [c for c in constraints if isinstance(c, EllipseConstraint)]
    heights = [c for c in constraints if isinstance(c, CoordinateProgramme)]
    others = [c for c in constraints if not isinstance(c, (EllipseConstraint, CoordinateProgramme))]
    problems = []
    if len(ellipses) != 1:
        problems.append(f"need exactly one EllipseConstraint, got {len(ellipses)}")
    if len(heights) != 1:
        problems.append(f"need exactly one CoordinateProgramme (height), got {len(heights)}")
    for c in others:
        problems.append(f"constraint {getattr(c, 'name', c)!r} of type {type(c).__name__} has no "
                        "MuJoCo mechanism; supported: EllipseConstraint, CoordinateProgramme")
    if len(heights) == 1:
        h = heights[0]
        if h.axis != 2:
            problems.append(f"height programme {h.name!r}: axis must be 2 (world z), got {h.axis}")
        if not isinstance(h.function, Cosine):
            problems.append(f"height programme {h.name!r}: function must be a Cosine (a crank "
                            f"realises it), got {type(h.function).__name__}")
        elif not (h.function.period > 0 and h.function.amplitude > 0):
            problems.append(f"height programme {h.name!r}: need period > 0 s and amplitude > 0 m, "
                            f"got {h.function.period!r}, {h.function.amplitude!r}")
    if len(ellipses) == 1 and len(heights) == 1 and ellipses[0].frame != heights[0].frame:
        problems.append(f"both constraints must act on the same frame, got "
                        f"{ellipses[0].frame!r} and {heights[0].frame!r}")
    for c in ellipses + heights:
        if c.frame not in model.frames:
            problems.append(f"constraint {c.name!r}: no frame {c.frame!r} in the model "
                            f"(have {sorted(model.frames)})")
    if problems:
        raise ModelError(problems)
    e, h = ellipses[0], heights[0]
    return EllipticProgramme(e.a, e.b, tuple(float(v) for v in e.center), h.function, e.frame,
                             (e.name, h.name))


def frame_motion(model, frame, q, q_dot):
    """(position (3,) m, velocity (3,) m/s) of the origin of model frame ``frame`` (world)."""
    fr = model.frame(frame)
    kin = chain_kinematics(model, q)
    pk = point_kinematics(model, kin, np.asarray(q_dot, float), fr.link_index, fr.transform[:3, 3])
    return pk.position, pk.velocity


def auxiliary_state(programme, p_e, v_e, t):
    """Auxiliary (qpos, qvel) (5,) each, ordered as AUX_JOINTS, matching time t (s) and the
    end-effector position p_e (3,) m and velocity v_e (3,) m/s (world frame)."""
    h = programme.height
    theta = h.omega * t
    amp = h.amplitude
    xc, yc = programme.center
    qpos = np.array([theta, amp * np.cos(theta), amp * np.sin(theta), p_e[0] - xc, p_e[1] - yc])
    qvel = np.array([h.omega, -amp * h.omega * np.sin(theta), amp * h.omega * np.cos(theta),
                     v_e[0], v_e[1]])
    return qpos, qvel


def string_length_at(programme, p_e, follower_height):
    """m, focus-E-focus tendon length with E at p_e (3,) and the foci at follower_height."""
    centre = np.array([*programme.center, follower_height])
    return float(sum(np.linalg.norm(p_e - (centre + f)) for f in programme.foci_local()))

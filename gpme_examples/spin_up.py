"""The spin-up of a flexible beam on a hub with a prescribed angle (a classic benchmark).

Problem (Kane, Ryan & Banerjee, J. Guidance 10(2):139-151, 1987; in its geometrically
exact form Simo & Vu-Quoc, CMAME 66:125-161, 1988; data and programme as coded in
AeroBeams.jl test/examples/spinupRobotArm.jl, docs/flexible-beam-benchmark-sources.md):
a beam of length L = 10 m clamped to a hub that turns about the vertical z axis through
the beam's root, no gravity, hub angle

    theta(t) = (Omega_s / T_s) [t^2 / 2 + (T_s / (2 pi))^2 (cos(2 pi t / T_s) - 1)]  t <= T_s
    theta(t) = Omega_s (t - T_s / 2)                                                   t > T_s

with Omega_s = 6 rad/s, T_s = 15 s (C2 at T_s: theta_ddot = (Omega_s/T_s)(1 - cos(2 pi t /
T_s)) is 0 at both ends).  Section data: E A = 2.8e7 N, E I = 1.4e4 N m^2 (both planes),
G J = 1.4e4 N m^2, rho A = 1.2 kg/m, rho I = 6e-4 kg m, i.e. E = 7e10 Pa, rho = 3000 kg/m^3,
A = 4e-4 m^2, I_y = I_z = 2e-7 m^4, J = 4e-7 m^4 (G = 3.5e10 Pa, nu = 0).

Frames: world z up; the hub link turns about world z; the beam lies along the hub frame's
x axis (in-plane bending: about z, deflection along y of the hub frame).  The hub is a
light disc (HUB_INERTIA about z, kg m^2) so the programme's multiplier is the torque that
turns beam and hub.
"""
import numpy as np

from gpme_core.constraints import JointProgramme
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import RigidBodyInertia
from gpme_core.joint_kinds import REVOLUTE
from gpme_core.model import ChainBuilder
from gpme_core.rfem import BeamProperties, BeamSection
from gpme_core.time_functions import TimeFunction

LENGTH = 10.0                    # m
YOUNGS_MODULUS = 7e10            # Pa
SHEAR_MODULUS = 3.5e10           # Pa (nu = 0)
DENSITY = 3000.0                 # kg/m^3
AREA = 4e-4                      # m^2
SECOND_MOMENT = 2e-7             # m^4, both axes
TORSION_CONSTANT = 4e-7          # m^4
SPIN_RATE = 6.0                  # rad/s, Omega_s
SPIN_UP_TIME = 15.0              # s, T_s
HUB_MASS = 1.0                   # kg
HUB_INERTIA = 0.5                # kg m^2 about z (the other two the same: a light disc)


class SpinUpAngle(TimeFunction):
    """theta(t) of the module docstring (rad, s).  ``reference_derivatives`` is the
    published definition written out once more (f, f', f''), for the reference engines."""

    def __init__(self, rate=SPIN_RATE, time=SPIN_UP_TIME):
        self.omega_s, self.t_s = float(rate), float(time)

    def derivatives(self, t):
        w, ts = self.omega_s, self.t_s
        if t <= ts:
            c = ts / (2.0 * np.pi)
            arg = 2.0 * np.pi * t / ts
            return ((w / ts) * (0.5 * t * t + c * c * (np.cos(arg) - 1.0)),
                    (w / ts) * (t - c * np.sin(arg)), (w / ts) * (1.0 - np.cos(arg)))
        return w * (t - 0.5 * ts), w, 0.0

    def value(self, t):
        return float(self.derivatives(t)[0])

    def rate(self, t):
        return float(self.derivatives(t)[1])

    def acceleration(self, t):
        return float(self.derivatives(t)[2])

    def reference_derivatives(self, t):
        return tuple(float(v) for v in self.derivatives(t))


def beam_properties(length=LENGTH) -> BeamProperties:
    """The beam of the module docstring (no material damping)."""
    section = BeamSection(AREA, SECOND_MOMENT, SECOND_MOMENT, TORSION_CONSTANT,
                          name="spin-up beam (A = 4 cm^2, I = 0.2 cm^4)")
    return BeamProperties.from_section(length, section, YOUNGS_MODULUS, SHEAR_MODULUS, DENSITY)


def build_spin_up(n_rfe: int, name=None):
    """The hub and its beam as a gpme Model (n_rfe RFEM segments, >= 1)."""
    b = ChainBuilder(name or f"spin_up_n{n_rfe}", gravity=(0.0, 0.0, 0.0))
    b.add_joint("theta", REVOLUTE, (0, 0, 1), link="hub")
    b.add_body(RigidBodyInertia(HUB_MASS, (0.0, 0.0, 0.0),
                                np.diag([HUB_INERTIA / 2, HUB_INERTIA / 2, HUB_INERTIA])))
    b.add_beam("beam", beam_properties(), n_rfe)
    b.add_frame("tip")
    return b.build()


def spin_up_system(n_rfe: int, rate=SPIN_RATE, time=SPIN_UP_TIME):
    """(ProgrammedMotion, q0, q_dot0): the hub angle programmed, everything at rest."""
    model = build_spin_up(n_rfe)
    system = ProgrammedMotion(model, [JointProgramme("theta", SpinUpAngle(rate, time),
                                                     name="hub_angle")])
    n = model.n_coordinates
    return system, np.zeros(n), np.zeros(n)

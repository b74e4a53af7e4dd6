"""The paper's crane (Fig. 1): compliant support, rotating column, pitching arm (rigid or
RFEM-flexible), telescopic slider, programmed end-effector motion.

All parameters of the example live here; docs/crane.md explains them.  The paper gives
only s_z, d_z, a, b, A, T, t_0 and t_dr,0; every other value is our choice of a light
crane whose flexible arm vibrates visibly.

Frames (right-handed, z up; world frame 0 at the support on the column axis):
  z1   prismatic along world z: the base on the vertical spring-damper support
       (z1 = 0: spring unstretched).  Link ``base``: a plate below the column foot.
  psi2 revolute about the base z axis at the column foot.  Link ``column`` up to
       height ``column_height``.
  psi3 revolute about the horizontal axis at the column top.  The arm frame is the
       column frame moved up by column_height and turned +90 deg about x, so the arm lies
       along its x axis, its z axis is horizontal (column -y) and psi3 > 0 lifts the arm.
  arm  a solid round steel bar along arm x, RFEM-discretised with n_rfe segments
       (coordinates psi_arm_r, theta_arm_r, phi_arm_r; psi bends in the vertical plane).
  z4   prismatic along the x axis of the arm tip frame: the slider rod (length
       slider_length, occupying x in [-slider_length, 0] of its frame) pushed out of the
       tubular arm end; z4 = 0: slider tip at the arm tip.
  E    the end-effector: the slider tip (origin of the slider frame).

Programmed constraints (paper eqs. 4.1, 4.2, 8): Phi_1 = (x_E/a)^2 + (y_E/b)^2 - 1,
Phi_2 = z_E - (z0 + A cos(2 pi t / T)); dependent coordinates psi3 and z4.
"""
from dataclasses import dataclass, replace

import numpy as np

from gpme_core import transforms as tf
from gpme_core.constraints import CoordinateProgramme, EllipseConstraint
from gpme_core.geometry import RIGID_RGBA, member
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid, cylinder
from gpme_core.model import PRISMATIC, REVOLUTE, STANDARD_GRAVITY, ChainBuilder
from gpme_core.rfem import BeamProperties, BeamSection
from gpme_core.statics import static_equilibrium
from gpme_core.time_functions import Cosine, QuinticRamp

# the paper's two runs (section 3, gpme_examples.paper): the flexible arm's RFEM segments,
# run lengths and RK4 steps
DEFAULT_N_RFE = 3
# s, the paper's runs: 10 s of programmed motion (Figs. 2 and 3); a quick (CI) run takes
# the first 2 s.  Defined here once: crane_scenario, `gpme simulate`, `gpme verify`.
T_END = 10.0
QUICK_T_END = 2.0
# RK4 steps: the rigid crane's fastest motion is the 5 Hz support and the 20 1/s
# Baumgarte rate; the flexible arm's RFEM torsion modes (about 5 kHz at n = 3) need
# dt below 8e-5 s (gpme_core.stability.rk4_step); 5e-5 s keeps a 40 % margin.
DEFAULT_DT = {"rigid": 1e-4, "flexible": 5e-5}


@dataclass(frozen=True)
class CraneParameters:
    """Every number of the crane example (SI units)."""

    # support (paper)
    support_stiffness: float = 1e4          # s_z, N/m
    support_damping: float = 2.5            # d_z, N s/m
    # base plate under the column foot
    base_mass: float = 5.0                  # kg
    base_size: tuple = (0.4, 0.4, 0.1)      # m, box centred 0.05 m below the column foot
    # slewing column: a drum carrying the slewing ring and counterweight, heavy enough
    # that the paper's 1 N m slews it at a crane's pace (about 3.5 rad/s after 10 s)
    column_mass: float = 40.0               # kg
    column_height: float = 1.0              # m, foot to arm pivot
    column_radius: float = 0.25             # m, outer
    column_inner_radius: float = 0.2        # m
    # arm: round steel tube 20 x 1.5 mm (a light crane's boom tube)
    arm_length: float = 0.5                 # m, pivot to arm tip
    arm_diameter: float = 0.020             # m, outer
    arm_wall_thickness: float = 0.0015      # m, 0 = solid bar
    arm_yield_strength: float = 355e6       # Pa, structural steel S355 (EN 10025-2)
    steel_youngs_modulus: float = 210e9     # Pa
    steel_shear_modulus: float = 81e9       # Pa
    steel_density: float = 7850.0           # kg/m^3
    arm_viscosity: float = 5e6              # Pa s, Kelvin-Voigt: 0.17 % of critical in the
    #                                         1st bending mode (22 Hz); more overdamps the
    #                                         stiff RFEM torsion modes and force RK4 to tiny dt
    # slider rod
    slider_mass: float = 1.0                # kg
    slider_length: float = 0.5              # m
    slider_radius: float = 0.01             # m
    slider_stroke: tuple = (-0.3, 0.5)      # m, range of z4 (slider tip behind/past arm tip)
    arm_pitch_range: tuple = (-1.4, 1.4)    # rad, range of psi3
    # drive on psi2 (paper eq. 9)
    drive_torque: float = 1.0               # t_dr,0, N m
    drive_ramp_time: float = 5.0            # t_0, s
    # programmed motion (paper section 3)
    ellipse_a: float = 0.375                # m, semi-axis along world x
    ellipse_b: float = 0.750                # m, semi-axis along world y
    z0: float = 1.0                         # m
    amplitude: float = 0.5                  # A, m
    period: float = 2.5                     # T, s
    baumgarte_alpha: float = 20.0           # 1/s
    baumgarte_beta: float = 20.0            # 1/s
    gravity: tuple = STANDARD_GRAVITY       # m/s^2
    # off-manifold initial state (the paper's: end-effector outside the ellipse)
    initial_psi3: float = np.pi / 4         # rad
    initial_z4: float = 0.2                 # m

    def arm_section(self):
        """BeamSection of the arm: a round tube, or a solid bar when arm_wall_thickness = 0."""
        if self.arm_wall_thickness == 0.0:
            return BeamSection.solid_circle(self.arm_diameter)
        return BeamSection.tube(self.arm_diameter, self.arm_wall_thickness)

    def beam(self):
        """BeamProperties of the arm."""
        return BeamProperties.from_section(self.arm_length, self.arm_section(),
                                           self.steel_youngs_modulus, self.steel_shear_modulus,
                                           self.steel_density, self.arm_viscosity)

    def with_changes(self, **changes):
        return replace(self, **changes)


def build_crane(n_rfe=0, params=CraneParameters(), name=None):
    """The crane Model; n_rfe = 0 is the rigid arm, n_rfe >= 1 the RFEM-flexible arm."""
    p = params
    b = ChainBuilder(name or (f"crane_flexible_n{n_rfe}" if n_rfe else "crane_rigid"),
                     gravity=p.gravity)
    b.add_joint("z1", PRISMATIC, (0, 0, 1), stiffness=p.support_stiffness,
                damping=p.support_damping, link="base")
    b.add_body(cuboid(p.base_mass, p.base_size, com=(0.0, 0.0, -0.5 * p.base_size[2])))
    # what the links look like (gpme_core.geometry; never mass): drawn from the same sizes
    b.add_shape("box", p.base_size, tf.translation(0, 0, -0.5 * p.base_size[2]),
                rgba=RIGID_RGBA)
    b.add_joint("psi2", REVOLUTE, (0, 0, 1), link="column")
    b.add_body(cylinder(p.column_mass, p.column_radius, p.column_height, axis=2,
                        com=(0.0, 0.0, 0.5 * p.column_height), inner_radius=p.column_inner_radius))
    # the drum drawn solid at its outer radius (a tube as one cylinder)
    b.add_shape("cylinder", (p.column_radius, p.column_height),
                tf.translation(0, 0, 0.5 * p.column_height), rgba=RIGID_RGBA)
    b.add_joint("psi3", REVOLUTE, (0, 0, 1),
                origin=tf.translation(0, 0, p.column_height) @ tf.rot_x(np.pi / 2), link="arm",
                limits=p.arm_pitch_range)
    b.add_beam("arm", p.beam(), n_rfe)
    b.add_joint("z4", PRISMATIC, (1, 0, 0), link="slider", limits=p.slider_stroke)
    b.add_body(cylinder(p.slider_mass, p.slider_radius, p.slider_length, axis=0,
                        com=(-0.5 * p.slider_length, 0.0, 0.0)))
    # visual only: pulled in, the rod reaches the column's top, and a collision shape
    # there would make a simulator's contacts the crane does not have
    b.add_shape(*member(p.slider_length, p.slider_radius, p.slider_radius, True,
                        start=-p.slider_length), role="visual", rgba=RIGID_RGBA)
    b.add_frame("E")
    b.add_drive("psi2", QuinticRamp(p.drive_torque, p.drive_ramp_time))
    return b.build()


def crane_constraints(params=CraneParameters()):
    """[Phi_1 ellipse (eq. 4.1), Phi_2 height programme (eqs. 4.2, 8)] on frame E."""
    p = params
    return [EllipseConstraint(p.ellipse_a, p.ellipse_b, frame="E", name="Phi_1"),
            CoordinateProgramme(Cosine(p.z0, p.amplitude, p.period), axis=2, frame="E",
                                name="Phi_2")]


def crane_system(n_rfe=0, params=CraneParameters(), baumgarte=None):
    """ProgrammedMotion of the crane with the paper's dependent coordinates psi3, z4."""
    model = build_crane(n_rfe, params)
    bg = baumgarte or (params.baumgarte_alpha, params.baumgarte_beta)
    return ProgrammedMotion(model, crane_constraints(params), dependent=("psi3", "z4"),
                            baumgarte=bg)


def initial_state(model, params=CraneParameters(), static_arm=False):
    """(q0, q_dot0) of the paper's off-manifold start: at rest, support spring unstretched,
    psi2 = 0, arm at ``initial_psi3``, slider at ``initial_z4``, flexible coordinates 0
    (a straight arm), or with ``static_arm`` the arm's RFEM coordinates in their static
    sag under gravity (the other coordinates held)."""
    q = np.zeros(model.n_coordinates)
    q[model.index("psi3")] = params.initial_psi3
    q[model.index("z4")] = params.initial_z4
    if static_arm:
        flex = [nm for nm in model.coordinate_names if "_arm_" in nm]
        q = static_equilibrium(model, q, flex)
    return q, np.zeros(model.n_coordinates)

"""Andrews' squeezing mechanism (the seven-body mechanism): a closed-loop benchmark.

Source of the problem, its parameters, its consistent start and its reference solution:
the Test Set for IVP Solvers (F. Mazzia, C. Magherini, F. Iavernaro, Univ. Bari, release
2.3, 2006; problem "andrews", index-3 formulation, file andrews.F rev. 1.2), after
Hairer & Wanner, Solving Ordinary Differential Equations II, sec. VII.7, and Manning
(1981).  The numbers were read in the test set's Fortran as vendored by the R package
deTestSet (rforge/bvpsolve, pkg/deTestSet/src/Ex_andrews.f); docs/closed-loop-benchmark-
sources.md has the citation trail.  The reference solution at t = 0.03 s was computed by
the test set's authors with PSIDE at rtol = atol = 1e-14 (Cray C90 double precision).

The mechanism is planar (x-y plane, every joint about z, no gravity).  The test set
writes it in seven angles with six loop equations; here it is built as a gpme tree of
four branches from the world closed by three point coincidences, the geometry derived
from the test set's mass matrix and loop equations (docs/benchmarks-closed-loops.md):

    beta    crank about O = (0, 0): centre of mass at ra on its x axis; its tip at rr
    Theta   rod on the crank tip, angle beta + Theta: centre of mass at -da, point F at -d
    gamma   triangle about B = (xb, yb): centre of mass at (sa, sb), point E at (0, -ss),
            spring point D at (sd, -sc)
    delta   body 5 about A = (xa, ya): centre of mass at (ta, tb); joint of body 4 at zt
    Phi     body 4 on body 5, angle delta + Phi: centre of mass at (0, -(e - ea)), point
            G4 at (0, -e)
    epsilon body 7 about A: centre of mass at (ua, ub); joint of body 6 at (0, -u)
    Omega   body 6 on body 7, angle epsilon + Omega: centre of mass at zf - fa, point G6
            at zf

Loops: F = E, F = G4, F = G6 in x and y (the test set's g1..g6, same signs: row =
F - other point).  A spring c0 (free length l0) joins D to the fixed point C = (xc, yc);
the motor torque mom acts on beta.  Only the distances of the centres of mass from their
joints enter the test set's equations (the mechanism has no gravity), so their direction
here is a choice that does not change the motion.  The test set's multipliers satisfy
M q_ddot = f - G^T lambda; gpme's M q_ddot = h + Q + A^T lambda, so with the same rows
lambda_gpme = -lambda_test_set.
"""
import numpy as np

from gpme_core import transforms as tf
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import RigidBodyInertia
from gpme_core.model import REVOLUTE, WORLD, ChainBuilder
from gpme_core.pair_constraints import coincident
from gpme_core.time_functions import Constant

# the test set's 42 parameters (SI: kg, kg m^2, m, N/m, N m)
M1, M2, M3, M4, M5, M6, M7 = 0.04325, 0.00365, 0.02373, 0.00706, 0.07050, 0.00706, 0.05498
I1, I2, I3, I4, I5, I6, I7 = 2.194e-6, 4.410e-7, 5.255e-6, 5.667e-7, 1.169e-5, 5.667e-7, 1.912e-5
XA, YA, XB, YB, XC, YC = -0.06934, -0.00227, -0.03635, 0.03273, 0.014, 0.072
C0, L0, MOM = 4530.0, 0.07785, 0.033
D, DA, E, EA, RR, RA = 28e-3, 115e-4, 2e-2, 1421e-5, 7e-3, 92e-5
SS, SA, SB, SC, SD = 35e-3, 1874e-5, 1043e-5, 18e-3, 2e-2
TA, TB, U, UA, UB = 2308e-5, 916e-5, 4e-2, 1228e-5, 449e-5
ZF, ZT, FA = 2e-2, 4e-2, 1421e-5

# the test set's coordinate order and gpme's names for them
TEST_SET_ORDER = ("beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon")
LOOPS = (("E", "F"), ("G4", "F"), ("G6", "F"))
T_END = 0.03          # s, the reference time

# consistent start (positions rad, at rest), test set order
START = (-0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
         0.222668390165885884674473185609, 0.487364979543842550225598953530,
         -0.222668390165885884674473185609, 1.23054744454982119249735015568)
# reference solution at t = 0.03 s (test set order): positions rad, velocities rad/s,
# multipliers (test set sign: M q_ddot = f - G^T lambda)
REFERENCE_Q = (0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1,
               -0.5347301163226948e0, 0.5244099658805304e0, 0.5347301163226948e0,
               0.1048080741042263e1)
REFERENCE_Q_DOT = (0.1139920302151208e4, -0.1424379294994111e4, 0.1103291221937134e2,
                   0.1929337464421385e2, 0.5735699284790808e0, -0.1929337464421385e2,
                   0.3231791658026955e0)
REFERENCE_LAMBDA = (0.1991753333731910e3, -0.2975531228015052e2, 0.2306654119098399e2,
                    0.3145271365475927e2, 0.2264249232082739e2, 0.1161740700019673e2)
# the reference's stated precision: PSIDE at rtol = atol = 1e-14 (a local tolerance; the
# source gives no global error bound)
REFERENCE_RTOL = 1e-14


def _planar(mass, com, izz):
    """A body of the planar mechanism: mass kg, centre of mass (x, y) m in its link
    frame, moment izz kg m^2 about the z axis through it (x and y moments set equal to
    izz: they do not enter a motion about z, and keep the tensor physical)."""
    return RigidBodyInertia(mass, (com[0], com[1], 0.0), np.diag([izz, izz, izz]))


def build_andrews():
    """The gpme Model of the mechanism (module docstring)."""
    b = ChainBuilder("andrews_squeezer", gravity=(0.0, 0.0, 0.0))
    z = (0.0, 0.0, 1.0)
    b.add_joint("beta", REVOLUTE, z, link="crank")
    b.add_body(_planar(M1, (RA, 0.0), I1))
    b.add_joint("Theta", REVOLUTE, z, origin=tf.translation(RR, 0, 0), link="rod")
    b.add_body(_planar(M2, (-DA, 0.0), I2))
    b.add_frame("F", tf.translation(-D, 0, 0))
    b.add_joint("gamma", REVOLUTE, z, origin=tf.translation(XB, YB, 0), link="triangle",
                parent=WORLD)
    b.add_body(_planar(M3, (SA, SB), I3))
    b.add_frame("E", tf.translation(0, -SS, 0))
    b.add_frame("D", tf.translation(SD, -SC, 0))
    b.add_joint("delta", REVOLUTE, z, origin=tf.translation(XA, YA, 0), link="body5",
                parent=WORLD)
    b.add_body(_planar(M5, (TA, TB), I5))
    b.add_joint("Phi", REVOLUTE, z, origin=tf.translation(ZT, 0, 0), link="body4")
    b.add_body(_planar(M4, (0.0, -(E - EA)), I4))
    b.add_frame("G4", tf.translation(0, -E, 0))
    b.add_joint("epsilon", REVOLUTE, z, origin=tf.translation(XA, YA, 0), link="body7",
                parent=WORLD)
    b.add_body(_planar(M7, (UA, UB), I7))
    b.add_joint("Omega", REVOLUTE, z, origin=tf.translation(0, -U, 0), link="body6")
    b.add_body(_planar(M6, (ZF - FA, 0.0), I6))
    b.add_frame("G6", tf.translation(ZF, 0, 0))
    b.add_point_spring("spring", "D", (XC, YC, 0.0), C0, L0)
    b.add_drive("beta", Constant(MOM))
    return b.build()


def andrews_system(baumgarte=(20.0, 20.0)):
    """ProgrammedMotion of the mechanism closed by its three loops (x and y of each), the
    dependent coordinates chosen by pivoting at the start."""
    model = build_andrews()
    constraints = [row for k, (a, b) in enumerate(LOOPS)
                   for row in coincident(a, b, axes="xy", name=f"loop{k + 1}")]
    system = ProgrammedMotion(model, constraints, baumgarte=baumgarte)
    return system.with_pivoted_dependent(0.0, start_state(model)[0])


def in_gpme_order(model, values):
    """(n,) values given in TEST_SET_ORDER, reordered as model.coordinate_names."""
    by_name = dict(zip(TEST_SET_ORDER, values))
    return np.array([by_name[c] for c in model.coordinate_names])


def start_state(model):
    """(q0, q_dot0) of the test set's consistent start, gpme order."""
    return in_gpme_order(model, START), np.zeros(model.n_coordinates)

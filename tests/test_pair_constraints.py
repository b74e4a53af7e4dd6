"""Constraints between two frames (gpme_core.pair_constraints): their rows against finite
differences in time, the accelerations of closed loops against Pinocchio's
constraintDynamics (its own contact Jacobians and classical accelerations), the names of
redundant loop rows, and the errors for bad input."""
import numpy as np
import pinocchio as pin
import pytest

from conftest import spatial_tree
from crosscheck.pinocchio.model import from_gpme
from gpme_core import transforms as tf
from gpme_core.constraints import evaluate_constraints
from gpme_core.errors import ConstraintError, ModelError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.kinematics import chain_kinematics
from gpme_core.model import PRISMATIC, REVOLUTE, WORLD, ChainBuilder
from gpme_core.pair_constraints import (AxisAlignment, Distance, RelativeCoordinate,
                                        SympyPairConstraint, coincident, weld)
from gpme_core.time_functions import Cosine

pytestmark = pytest.mark.both_computation_paths


def two_arms():
    """Two arms on the world whose tool frames coincide, with equal orientation, at q = 0:
    arm a (a0-a3, tool_a at (1.0, 0, 0.4) m) and arm b (b0-b2, tool_b there too).  Welded
    they form a spatial loop of one degree of freedom; joined at a point, of four."""
    b = ChainBuilder("two_arms")
    b.add_joint("a0", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(2.0, (0.2, 0.2, 0.4), com=(0.0, 0.0, 0.2)))
    b.add_joint("a1", REVOLUTE, (0, 1, 0), origin=tf.translation(0, 0, 0.4))
    b.add_body(cuboid(1.0, (0.5, 0.1, 0.1), com=(0.25, 0.0, 0.0)))
    b.add_joint("a2", REVOLUTE, np.array([0, 1, 1]) / np.sqrt(2),
                origin=tf.translation(0.5, 0, 0))
    b.add_body(cuboid(0.6, (0.3, 0.1, 0.1), com=(0.15, 0.0, 0.0)))
    b.add_joint("a3", PRISMATIC, (1, 0, 0), origin=tf.translation(0.3, 0, 0), damping=0.5)
    b.add_body(cuboid(0.3, (0.2, 0.05, 0.05), com=(0.1, 0.0, 0.0)))
    b.add_frame("tool_a", tf.translation(0.2, 0, 0))
    b.add_joint("b0", REVOLUTE, (0, 0, 1), origin=tf.translation(2.0, 0.3, 0), parent=WORLD)
    b.add_body(cuboid(2.0, (0.2, 0.2, 0.4), com=(0.0, 0.0, 0.2)))
    b.add_joint("b1", REVOLUTE, (1, 0, 0), origin=tf.translation(0, 0, 0.4), stiffness=2.0)
    b.add_body(cuboid(0.8, (0.1, 0.4, 0.1), com=(0.0, -0.1, 0.0)))
    b.add_joint("b2", REVOLUTE, (0, 1, 0), origin=tf.translation(-0.5, 0, 0))
    b.add_body(cuboid(0.8, (0.5, 0.1, 0.1), com=(-0.25, 0.0, 0.0)))
    b.add_frame("tool_b", tf.translation(-0.5, -0.3, 0))
    return b.build()


def every_kind(a="E", b="F"):
    """One constraint of each kind between frames a and b, time dependent where it can be."""
    return [RelativeCoordinate(a, b, "x", Cosine(0.1, 0.2, 3.0), name="rel_x"),
            Distance(a, b, 0.5, name="rod"),
            AxisAlignment(a, "y", b, "z", Cosine(0.0, 0.1, 2.0), name="angle"),
            SympyPairConstraint("(x_b - x_a)**2 + y_b*z_a - 0.1*sin(3*t)", a, b, name="sym")]


# second central difference with h = 1e-4 s: truncation ~ h^2 |Phi''''| / 12 ~ 1e-8 and
# round-off ~ eps |Phi| / h^2 ~ 2e-8 (Phi ~ 1): 1e-6 is a margin of ~30 on both (measured
# 6e-8); the first difference is a hundred times closer
FD_STEP = 1e-4
FD_TOL = {"phi_dot": 1e-7, "phi_ddot": 1e-6}


def test_rows_are_the_time_derivatives_of_phi(rng):
    """Along q(t) = q + q_dot t + q_ddot t^2 / 2: dPhi/dt = Phi_dot and d2Phi/dt2 = A q_ddot +
    kappa for every kind, on two branches of a tree (frames E and F)."""
    tree = spatial_tree()
    system = ProgrammedMotion(tree, every_kind())
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1, 1, tree.n_coordinates) for _ in range(3))
        t0 = rng.uniform(0, 1)

        def rows(s):
            qs = q + qd * s + 0.5 * qdd * s * s
            return evaluate_constraints(tree, system.bound, t0 + s, chain_kinematics(tree, qs),
                                        qd + qdd * s)

        phi, phi_dot, a, kappa = rows(0.0)
        plus, minus = rows(FD_STEP)[0], rows(-FD_STEP)[0]
        np.testing.assert_allclose((plus - minus) / (2 * FD_STEP), phi_dot, rtol=0,
                                   atol=FD_TOL["phi_dot"])
        np.testing.assert_allclose((plus - 2 * phi + minus) / FD_STEP ** 2, a @ qdd + kappa,
                                   rtol=0, atol=FD_TOL["phi_ddot"])


def test_joints_moving_neither_frame_are_not_in_the_row(rng):
    """E hangs on q0-q1-q2, F on q0-q3-q4: q5 and q6 (the other root) move neither."""
    tree = spatial_tree()
    system = ProgrammedMotion(tree, every_kind())
    q, qd = rng.uniform(-1, 1, tree.n_coordinates), rng.uniform(-1, 1, tree.n_coordinates)
    a = system.constraints(0.2, q, qd)[2]
    off = [tree.index("q5"), tree.index("q6")]
    assert not a[:, off].any()
    on = [tree.index(c) for c in ("q1", "q2", "q3", "q4")]     # on one frame's path
    assert np.all(np.abs(a[:, on]).max(axis=1) > 1e-3)


def _pinocchio_accelerations(model, q, q_dot, frame_a, frame_b, contact):
    """q_ddot (n,) from Pinocchio's constraintDynamics with one rigid constraint of type
    ``contact`` between the two gpme frames (no Baumgarte corrector, exact solve)."""
    ps = from_gpme(model)
    pm = ps.model
    data = pm.createData()
    fa, fb = model.frame(frame_a), model.frame(frame_b)
    cm = pin.RigidConstraintModel(contact, pm, fa.link_index + 1, pin.SE3(fa.transform),
                                  fb.link_index + 1, pin.SE3(fb.transform),
                                  pin.ReferenceFrame.LOCAL)
    models = pin.StdVec_RigidConstraintModel()
    models.append(cm)
    datas = pin.StdVec_RigidConstraintData()
    datas.append(cm.createData())
    pin.initConstraintDynamics(pm, data, models, datas)
    tau = ps.applied_forces(q, q_dot, model.drive_forces(0.0))
    settings = pin.ProximalSettings(1e-14, 0.0, 1)      # mu = 0: the exact KKT solve
    a = pin.constraintDynamics(pm, data, ps.q_pin(q), ps.to_pin(q_dot), ps.to_pin(tau),
                               models, datas, settings)
    return ps.to_gpme(a)


# gpme (reduced GPME, Cholesky) and Pinocchio (KKT by its proximal Cholesky) solve the
# same equations: round-off of a solve with cond ~ 1e2..1e3, measured 4e-15 of the largest
# acceleration; 1e-11 keeps a margin of 1e3 for other states
LOOP_RTOL = 1e-11


@pytest.mark.parametrize("kind", ["coincident", "weld"])
def test_closed_loop_accelerations_equal_pinocchio(kind, rng):
    model = two_arms()
    specs, contact = {"coincident": (coincident("tool_a", "tool_b"),
                                     pin.ContactType.CONTACT_3D),
                      "weld": (weld("tool_a", "tool_b"), pin.ContactType.CONTACT_6D)}[kind]
    for _ in range(3):
        q0 = 0.1 * rng.uniform(-1, 1, model.n_coordinates)
        system = ProgrammedMotion(model, specs).with_pivoted_dependent(0.0, q0)
        q, qd = system.consistent_state(0.0, q0, rng.uniform(-1, 1, model.n_coordinates))
        ours = system.solve(0.0, q, qd).q_ddot
        theirs = _pinocchio_accelerations(model, q, qd, "tool_a", "tool_b", contact)
        np.testing.assert_allclose(ours, theirs, rtol=0,
                                   atol=LOOP_RTOL * np.abs(theirs).max())


def test_planar_loop_closed_in_3d_names_the_redundant_row():
    """A planar four-bar (all axes along z) closed by a 3D coincidence: the z row has a
    zero Jacobian (no joint moves the loop out of its plane), and the error says so and
    names it; closed with axes='xy' it runs."""
    b = ChainBuilder("four_bar")
    b.add_joint("crank", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.2, 0.02, 0.02), com=(0.1, 0, 0)))
    b.add_joint("coupler", REVOLUTE, (0, 0, 1), origin=tf.translation(0.2, 0, 0))
    b.add_body(cuboid(1.0, (0.6, 0.02, 0.02), com=(0.3, 0, 0)))
    b.add_frame("coupler_end", tf.translation(0.6, 0, 0))
    b.add_joint("rocker", REVOLUTE, (0, 0, 1), origin=tf.translation(0.5, 0, 0) @ tf.rot_z(1.2),
                parent=WORLD)
    b.add_body(cuboid(1.0, (0.4, 0.02, 0.02), com=(0.2, 0, 0)))
    b.add_frame("rocker_end", tf.translation(0.4, 0, 0))
    model = b.build()
    q = np.zeros(3)
    with pytest.raises(ConstraintError, match=r"'loop_z' has a zero Jacobian row"):
        ProgrammedMotion(model, coincident("coupler_end", "rocker_end", name="loop")) \
            .with_pivoted_dependent(0.0, q)
    planar = ProgrammedMotion(model, coincident("coupler_end", "rocker_end", axes="xy"))
    guess = np.array([1.0, -0.7, -0.1])      # near the closed loop at crank = 1 rad
    planar = planar.with_pivoted_dependent(0.0, guess)
    q, qd = planar.consistent_state(0.0, guess, np.array([2.0, 0.0, 0.0]))
    phi, phi_dot, _, _ = planar.constraints(0.0, q, qd)
    assert np.abs(phi).max() < 1e-12 and np.abs(phi_dot).max() < 1e-12
    assert np.isfinite(planar.solve(0.0, q, qd).q_ddot).all()


def test_bad_pair_constraints_are_refused_with_the_value():
    with pytest.raises(ModelError, match="axis must be 'x', 'y' or 'z'"):
        RelativeCoordinate("E", "F", "w")
    with pytest.raises(ModelError, match="does not depend on the frames' coordinates"):
        SympyPairConstraint("t**2", "E", "F")
    with pytest.raises(ModelError, match="no frame named 'G'"):
        ProgrammedMotion(spatial_tree(), [Distance("E", "G", 0.3)])
    with pytest.raises(ModelError, match="programme must be a number or a TimeFunction"):
        Distance("E", "F", "long")


def test_distance_through_zero_is_a_clear_error():
    tree = spatial_tree()
    system = ProgrammedMotion(tree, [Distance("E", "E", 0.2)])
    q = np.zeros(tree.n_coordinates)
    with pytest.raises(ConstraintError, match="coincide at t = 0 s"):
        system.constraints(0.0, q, q)

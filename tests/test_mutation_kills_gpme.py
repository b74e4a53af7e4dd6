"""Kill tests for gpme_core.gpme (docs/mutation.md): an x-y table (two sliders carrying one
mass) whose reduced GPME solution, multipliers, partition, consistent initial state and
error reports are derived by hand; the numpy reference and the compiled reduced solve
must both reproduce them."""
import numpy as np
import pytest
import sympy as sp

from gpme_core import transforms as tf
from gpme_core.constraints import CoordinateProgramme, EllipseConstraint, SympyPointConstraint
from gpme_core.errors import ConstraintError, ModelError
from gpme_core.gpme import ProgrammedMotion, _rcond
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, ChainBuilder
from gpme_core.time_functions import Sine

pytestmark = pytest.mark.both_computation_paths

MASS, KX, KY, DX, DY, REFX, REFY = 2.0, 3.0, 5.0, 0.4, 0.7, 0.1, -0.2
EX = (0.1, 0.2, 0.0)                      # frame E offset on the carriage, m
F = Sine(0.05, 0.2, 1.5, 0.3)             # programme of x_E (m)
TOL = 1e-12                               # a 2x2 linear solve: round-off only


def table(limits_y=(-np.inf, np.inf)):
    """Slider x (along world x) then slider y carrying a 2 kg box; gravity along -z does not
    act on either slider.  Springs K (q - q_ref), dampers D q_dot on both."""
    b = ChainBuilder("xy_table")
    b.add_joint("x", PRISMATIC, (1, 0, 0), stiffness=KX, spring_reference=REFX, damping=DX)
    b.add_joint("y", PRISMATIC, (0, 1, 0), stiffness=KY, spring_reference=REFY, damping=DY,
                limits=limits_y)
    b.add_body(cuboid(MASS, (0.1, 0.1, 0.1)))
    b.add_frame("E", tf.translation(*EX))
    return b.build()


def f_terms(t):
    w = 2 * np.pi / 1.5
    return (0.05 + 0.2 * np.sin(w * t + 0.3), 0.2 * w * np.cos(w * t + 0.3),
            -0.2 * w * w * np.sin(w * t + 0.3))


@pytest.mark.parametrize("form", ["lagrange", "paper-eq7"])
def test_programmed_slider_accelerations_and_multiplier_by_hand(form):
    """x_E = f(t) with Baumgarte (alpha, beta): x_ddot = f'' - 2 alpha (x_dot - f') -
    beta^2 (x + 0.1 - f); y free: m y_ddot = -K_y (y - y_ref) - D_y y_dot (the paper-eq7
    form counts the damper twice); the multiplier is the force that moves x:
    lambda = m x_ddot - Q_x, Q_x = -K_x (x - x_ref) - D_x x_dot (minus D_x x_dot more in
    the paper-eq7 form)."""
    alpha, beta = 3.0, 4.0
    system = ProgrammedMotion(table(), [CoordinateProgramme(F, axis=0, name="P")],
                              dependent=["x"], baumgarte=(alpha, beta), damping_form=form)
    twice = 2.0 if form == "paper-eq7" else 1.0
    for t, q, qd in ((0.4, (0.3, 0.1), (0.5, -0.8)), (1.1, (-0.2, 0.4), (-1.0, 0.3))):
        q, qd = np.array(q), np.array(qd)
        f, fd, fdd = f_terms(t)
        phi, phi_dot = q[0] + EX[0] - f, qd[0] - fd
        xdd = fdd - 2 * alpha * phi_dot - beta ** 2 * phi
        ydd = (-KY * (q[1] - REFY) - twice * DY * qd[1]) / MASS
        lam = MASS * xdd - (-KX * (q[0] - REFX) - twice * DX * qd[0])
        sol = system.solve(t, q, qd)
        np.testing.assert_allclose(sol.q_ddot, [xdd, ydd], rtol=TOL, atol=TOL)
        np.testing.assert_allclose(sol.multipliers, [lam], rtol=TOL, atol=TOL)
        np.testing.assert_allclose(sol.reaction_forces, [lam, 0.0], rtol=TOL, atol=TOL)
        np.testing.assert_allclose(sol.phi, [phi], rtol=TOL, atol=TOL)
        np.testing.assert_allclose(sol.phi_dot, [phi_dot], rtol=TOL, atol=TOL)
        np.testing.assert_allclose(sol.jacobian, [[1.0, 0.0]], atol=0)
        np.testing.assert_allclose(sol.kappa, [-fdd], rtol=TOL, atol=TOL)
        np.testing.assert_allclose(system.accelerations(t, q, qd), [xdd, ydd], rtol=TOL, atol=TOL)
        if form == "lagrange":
            kq, kl = system.kkt_accelerations(t, q, qd)
            np.testing.assert_allclose(kq, [xdd, ydd], rtol=TOL, atol=TOL)
            np.testing.assert_allclose(kl, [lam], rtol=TOL, atol=TOL)


def test_coupled_constraint_velocity_map_and_reduced_solution():
    """x + 2 y = c(t) on the frame E: A = [1, 2]; with y dependent Gamma = -1/2, with x
    dependent Gamma = -2.  Without Baumgarte, x_ddot + 2 y_ddot = c'' and the independent
    equation N^T (M q_ddot - h - Q) = 0 give, with y dependent (N = [1, -1/2]):
    m x_ddot - Q_x - (m y_ddot - Q_y)/2 = 0."""
    c = SympyPointConstraint(sp.Symbol("x") + 2 * sp.Symbol("y") - 0.1 * sp.Symbol("t") ** 2, name="C")
    q, qd, t = np.array([0.2, -0.1]), np.array([0.3, 0.4]), 0.5
    qx = -KX * (q[0] - REFX) - DX * qd[0]
    qy = -KY * (q[1] - REFY) - DY * qd[1]
    # unknowns x_ddot, y_ddot: [m, -m/2; 1, 2] [xdd, ydd] = [Q_x - Q_y/2, 0.2]
    want = np.linalg.solve([[MASS, -MASS / 2], [1.0, 2.0]], [qx - qy / 2, 0.2])
    for dep, gam in (("y", -0.5), ("x", -2.0)):
        s = ProgrammedMotion(table(), [c], dependent=[dep], baumgarte=(0.0, 0.0))
        g, inv = s.velocity_map(np.array([[1.0, 2.0]]))
        np.testing.assert_allclose(g, [[gam]], rtol=TOL)
        sol = s.solve(t, q, qd)
        np.testing.assert_allclose(sol.q_ddot, want, rtol=1e-12, atol=1e-12)
        # lambda: M q_ddot - (h + Q) = A^T lambda
        np.testing.assert_allclose(sol.reaction_forces, MASS * want - [qx, qy], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(sol.reaction_forces, [sol.multipliers[0], 2 * sol.multipliers[0]], rtol=1e-12)
    auto = ProgrammedMotion(table(), [c], baumgarte=(0.0, 0.0))
    assert auto.dependent is None
    assert auto.pivoted_dependent(t, q, qd) == ("y",)    # the larger Jacobian column
    assert auto.dependent is None                        # asking changed nothing
    auto = auto.with_pivoted_dependent(t, q, qd)
    assert auto.independent == ("x",)
    np.testing.assert_array_equal(auto.dc, [1])
    np.testing.assert_array_equal(auto.ic, [0])


def test_unconstrained_system_solves_m_q_ddot_equal_h_plus_q():
    """No constraints: q_ddot = M^-1 (h + Q) = Q / m for the table; every state is consistent."""
    s = ProgrammedMotion(table())
    assert s.dependent == () and s.pivoted_dependent(0.0, np.zeros(2)) == ()
    q, qd = np.array([0.3, 0.1]), np.array([0.2, -0.5])
    want = np.array([-KX * (q[0] - REFX) - DX * qd[0], -KY * (q[1] - REFY) - DY * qd[1]]) / MASS
    sol = s.solve(0.0, q, qd)
    np.testing.assert_allclose(sol.q_ddot, want, rtol=TOL)
    assert sol.phi.shape == (0,) and sol.jacobian.shape == (0, 2)
    np.testing.assert_array_equal(sol.reaction_forces, 0.0)
    q2, qd2 = s.consistent_state(0.0, q, qd)
    np.testing.assert_array_equal(q2, q)
    np.testing.assert_array_equal(qd2, qd)


def test_consistent_state_on_a_time_dependent_and_a_curved_constraint():
    """Phi = x_E + 2 y_E - 0.1 t^2 with x_E = x + 0.1, y_E = y + 0.2, at t = 0.5 and
    y dependent: y = (0.025 - (x + 0.1))/2 - 0.2; Phi_dot = x_dot + 2 y_dot - 0.2 t = 0 gives
    y_dot = (0.1 - x_dot)/2 (the Phi_t term matters).  An ellipse (x_E/0.5)^2 + (y_E/0.3)^2
    = 1 needs Newton: y_E = 0.3 sqrt(1 - (x_E/0.5)^2) on the branch of the start, and
    y_dot = -(0.3/0.5)^2 x_E x_dot / y_E.  x and x_dot (independent) are kept."""
    c = SympyPointConstraint(sp.Symbol("x") + 2 * sp.Symbol("y") - 0.1 * sp.Symbol("t") ** 2, name="C")
    s = ProgrammedMotion(table(), [c], dependent=["y"])
    q, qd = s.consistent_state(0.5, [0.2, 3.0], [0.3, 9.0])
    assert q[0] == 0.2 and qd[0] == 0.3
    assert q[1] == pytest.approx((0.025 - 0.3) / 2 - 0.2, abs=1e-12)
    assert qd[1] == pytest.approx((0.1 - 0.3) / 2, abs=1e-12)
    e = ProgrammedMotion(table(), [EllipseConstraint(0.5, 0.3, name="E1")], dependent=["y"])
    q, qd = e.consistent_state(0.0, [0.2, 0.1], [0.4, 0.0])
    xe = 0.3
    ye = 0.3 * np.sqrt(1 - (xe / 0.5) ** 2)
    assert q[1] + 0.2 == pytest.approx(ye, abs=1e-10)     # Newton stops at |Phi| < 1e-12
    assert qd[1] == pytest.approx(-(0.3 / 0.5) ** 2 * xe * 0.4 / ye, abs=1e-9)
    # one Newton step from y_E = 0.3 (solution 0.24) reaches y_E = 0.246, |Phi| = 0.032 (quadratic
    # convergence from an error of 0.06): far above 1e-9, so the start must be refused
    with pytest.raises(ConstraintError, match="after 1 Newton steps"):
        e.consistent_state(0.0, [0.2, 0.1], [0.4, 0.0], max_iter=1)


def test_unreachable_and_out_of_limit_targets_are_reported():
    """x_E = 0.3 with y dependent cannot be met (Phi does not depend on y); an ellipse
    point with y_E = 0.24 outside the y stroke (-0.1, 0.01) is out of reach."""
    e = ProgrammedMotion(table(limits_y=(-0.1, 0.01)), [EllipseConstraint(0.5, 0.3, name="E1")], dependent=["y"])
    with pytest.raises(ConstraintError, match="out of reach"):
        e.consistent_state(0.0, [0.2, 0.0], [0.0, 0.0])
    far = ProgrammedMotion(table(), [EllipseConstraint(0.5, 0.3, name="E1")], dependent=["y"])
    with pytest.raises(ConstraintError):
        far.consistent_state(0.0, [0.9, 0.1], [0.0, 0.0])        # |x_E| > a: no solution
    # x_E = 0.6 = 1.2 a: Phi >= 1.44 - 1 = 0.44 whatever y; Newton cannot reach Phi = 0 and
    # the residual (< 1) must still be reported
    with pytest.raises(ConstraintError, match="Newton"):
        far.consistent_state(0.0, [0.5, 0.1], [0.0, 0.0])


def test_singular_partition_and_dependent_constraints_raise():
    """A programme of x_E with y dependent: A_dc = 0, singular on either computation path;
    two copies of one constraint: rank 1 < 2; wrong dependent lists are rejected."""
    s = ProgrammedMotion(table(), [CoordinateProgramme(F, axis=0, name="P")], dependent=["y"])
    # the report names the dependent block (not the reduced matrix) on both paths
    with pytest.raises(ConstraintError, match="dependent block K_dc"):
        s.solve(0.3, np.zeros(2), np.zeros(2))
    with pytest.raises(ConstraintError, match="singular"):
        s.velocity_map(np.array([[1.0, 0.0]]))
    twin = ProgrammedMotion(table(), [CoordinateProgramme(F, axis=0, name="P"),
                                      CoordinateProgramme(F, axis=0, name="Q")])
    with pytest.raises(ConstraintError, match="rank"):
        twin.pivoted_dependent(0.0, np.zeros(2))
    # the rank test is relative to the largest pivot: a regular Jacobian scaled by 0.01 is
    # fine, one with pivots 141 and ~7e-10 (ratio 5e-12 < 1e-10) is rank deficient
    small = ProgrammedMotion(table(), [SympyPointConstraint("0.01*x - 0.001", name="A"),
                                       SympyPointConstraint("0.01*y", name="B")])
    assert sorted(small.pivoted_dependent(0.0, np.zeros(2))) == ["x", "y"]
    near = ProgrammedMotion(table(), [SympyPointConstraint("100*x", name="A"),
                                      SympyPointConstraint("100*x + 1e-9*y", name="B")])
    with pytest.raises(ConstraintError, match="rank"):
        near.pivoted_dependent(0.0, np.zeros(2))
    with pytest.raises(ModelError, match="dependent coordinates not chosen"):
        twin.solve(0.0, np.zeros(2), np.zeros(2))
    for names in (["x", "x"], ["x"], ["x", "y", "y"]):
        with pytest.raises(ModelError, match="distinct dependent"):
            twin.with_dependent(names)
    for kw in ({"baumgarte": (-1.0, 1.0)}, {"baumgarte": (1.0, np.nan)}, {"damping_form": "other"}):
        with pytest.raises(ModelError):
            ProgrammedMotion(table(), [CoordinateProgramme(F, axis=0, name="P")], **kw)
    ProgrammedMotion(table(), [CoordinateProgramme(F, axis=0, name="P")], baumgarte=(0.0, 0.0))


def test_reciprocal_condition_number_in_the_1_norm():
    """rcond = 1 / (||A||_1 ||A^-1||_1): diag(2, 0.5) -> 1/(2 * 2); [[1, 2], [3, 4]]:
    ||A||_1 = 6, A^-1 = [[-2, 1], [1.5, -0.5]], ||A^-1||_1 = 3.5 -> 1/21; zero or
    non-finite -> 0."""
    a = np.diag([2.0, 0.5])
    assert _rcond(a, np.linalg.inv(a)) == pytest.approx(0.25, rel=1e-15)
    b = np.array([[1.0, 2.0], [3.0, 4.0]])
    assert _rcond(b, np.linalg.inv(b)) == pytest.approx(1 / 21, rel=1e-14)
    assert _rcond(np.zeros((2, 2)), np.zeros((2, 2))) == 0.0
    assert _rcond(np.zeros((2, 2)), np.eye(2)) == 0.0    # a zero matrix, whatever "inverse"
    assert _rcond(a, np.full((2, 2), np.inf)) == 0.0

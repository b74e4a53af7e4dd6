"""Point constraints whose gradient depends on time: a moving and a rotating ellipse
(gpme_core.constraints.SympyPointConstraint, expressions in x, y, z, t) on the spatial arm
of tests/conftest.py (fixture ``arm``), checked three ways at seeded random states:

1. Phi_dot = a . q_dot + Phi_t against the central difference in time of
   Phi(q + q_dot s, t + s) at s = 0;
2. Phi_ddot = a . q_ddot + kappa against the central second difference of
   Phi(q + q_dot s + q_ddot s^2/2, t + s), random q_ddot (and a against differences in q);
3. Pinocchio: crosscheck.pinocchio.check.compare_state on a Scenario with these
   constraints, i.e. the constraint terms from crosscheck.constraint_reference (SymPy
   derivatives of the composite Phi(x(t), y(t), z(t), t), independent of gpme's chain-rule
   formula) at Pinocchio's frame position, frame Jacobian and classical acceleration.

Both ellipses make grad(phi) depend on t, so the term 2 grad(phi_t) . p_dot of gpme's kappa
(gpme_core/constraints.py) is nonzero (it is of order |grad_t| |p_dot| ~ 1 here, against
tolerances ~1e-6).  Changing its factor 2 to 1 or 3 by hand fails
test_kappa_is_the_second_time_derivative, test_terms_agree_with_pinocchio and
test_model_file_with_rotating_ellipse_crosschecks (tried, then reverted).  The model file tests/data/modelfiles/rotating_ellipse.toml carries the rotating
ellipse through the model-file reader (test_model_file_with_rotating_ellipse_crosschecks).

Finite-difference tolerances: a central difference with step h has truncation error
O(h^2); it is estimated from two steps, |D(h) - D(h/2)|/3 for D(h/2), doubled for the
O(h^4) term (for the second difference, whose h^2 term is large here, Richardson's
combination is compared, O(h^4), error estimated as |R(h) - R(h/2)|/15), plus a round-off
bound c eps S / h^k (k = 1, 2 for the first and second
difference, S = the size of Phi's terms, c = 1e3 for the ~100 flops of the kinematics and
the expression, each of relative error eps).
"""
from pathlib import Path

import numpy as np
import pytest

from gpme_core.constraints import SympyPointConstraint, bind_constraints, evaluate_constraints
from gpme_core.gpme import ProgrammedMotion
from gpme_core.kinematics import chain_kinematics
from gpme_io.scenario import Scenario

EPS = np.finfo(float).eps
ROUND_OFF_FLOPS = 1e3
DATA = Path(__file__).parent / "data" / "modelfiles"

# centre (m) translating in y at 0.05 m/s and oscillating in x; semi-axes 0.5, 0.3 m
MOVING = "((x - 0.2 - 0.1*sin(1.3*t))/0.5)**2 + ((y + 0.1 - 0.05*t)/0.3)**2 - 1"
# axes rotating at 0.8 rad/s about the vertical through (0.1, -0.05); semi-axes 0.6, 0.35 m
_U = "((x - 0.1)*cos(0.8*t) + (y + 0.05)*sin(0.8*t))"
_V = "(-(x - 0.1)*sin(0.8*t) + (y + 0.05)*cos(0.8*t))"
ROTATING = f"({_U}/0.6)**2 + ({_V}/0.35)**2 - 1"
SPECS = (SympyPointConstraint(MOVING, frame="E", name="Phi_moving"),
         SympyPointConstraint(ROTATING, frame="E", name="Phi_rotating"))


@pytest.fixture(scope="module")
def bound(arm):
    return bind_constraints(arm, SPECS)


def states(model, seed, count=4):
    """(t s, q, q_dot, q_ddot): q in [-1, 1] (rad or m), rates ~1/s: p_dot ~ 1 m/s."""
    rng = np.random.default_rng(seed)
    n = model.n_coordinates
    return [(float(rng.uniform(0, 3)), rng.uniform(-1, 1, n), rng.uniform(-1.5, 1.5, n),
             rng.uniform(-2, 2, n)) for _ in range(count)]


def terms(model, bound, t, q, q_dot):
    """(Phi, Phi_dot, A, kappa) from gpme."""
    return evaluate_constraints(model, bound, t, chain_kinematics(model, q), q_dot)


def phi_of(model, bound, t, q):
    return terms(model, bound, t, q, np.zeros_like(q))[0]


def scale(model, bound, t, q):
    """S: size of Phi's terms (Phi + 1 is a sum of squares bounding each term), >= 1."""
    return max(1.0, float(np.max(np.abs(phi_of(model, bound, t, q) + 1.0))))


def test_phi_dot_is_the_time_derivative_along_the_motion(arm, bound):
    for t, q, qd, _ in states(arm, 101):
        phi, phi_dot, a, _ = terms(arm, bound, t, q, qd)

        def d1(h):
            return (phi_of(arm, bound, t + h, q + qd * h)
                    - phi_of(arm, bound, t - h, q - qd * h)) / (2 * h)
        h = 1e-4
        fd = d1(h / 2)
        tol = 2 * np.abs(d1(h) - fd) / 3 + ROUND_OFF_FLOPS * EPS * scale(arm, bound, t, q) / h
        np.testing.assert_array_less(np.abs(phi_dot - fd), tol)
        # Phi_dot = a . q_dot + Phi_t with Phi_t = dPhi/dt at fixed q (central difference,
        # gated the same way)
        def dt1(h):
            return (phi_of(arm, bound, t + h, q) - phi_of(arm, bound, t - h, q)) / (2 * h)
        phi_t = dt1(h / 2)
        tol = 2 * np.abs(dt1(h) - phi_t) / 3 + ROUND_OFF_FLOPS * EPS * scale(arm, bound, t, q) / h
        np.testing.assert_array_less(np.abs(phi_dot - a @ qd - phi_t), tol)
        assert np.all(np.abs(phi_t) > 1e-3)         # the constraints do move


def test_jacobian_is_the_gradient_in_q(arm, bound):
    h = 1e-6
    for t, q, qd, _ in states(arm, 102, count=2):
        a = terms(arm, bound, t, q, qd)[2]
        fd = np.column_stack([(phi_of(arm, bound, t, q + h * e) - phi_of(arm, bound, t, q - h * e))
                              / (2 * h) for e in np.eye(len(q))])
        # truncation h^2/6 |d3 Phi| ~ 1e-11; round-off 1e3 eps S / h ~ 2e-9 S
        np.testing.assert_allclose(a, fd, rtol=0,
                                   atol=ROUND_OFF_FLOPS * EPS * scale(arm, bound, t, q) / h)


def test_kappa_is_the_second_time_derivative(arm, bound):
    for t, q, qd, qdd in states(arm, 103):
        _, _, a, kappa = terms(arm, bound, t, q, qd)

        def path(s):
            return phi_of(arm, bound, t + s, q + qd * s + 0.5 * qdd * s * s)

        def d2(h):
            return (path(h) - 2 * path(0.0) + path(-h)) / (h * h)

        def richardson(h):          # (4 D(h/2) - D(h))/3: O(h^4)
            return (4 * d2(h / 2) - d2(h)) / 3
        h = 8e-3
        fd = richardson(h / 2)
        # its O(h^4) error estimated from two steps: |R(h) - R(h/2)|/15, doubled; round-off
        # of D(h/4) (4 c eps S / (h/4)^2) times the weights (4 + 1)/3 of the combination
        round_off = 5 / 3 * 4 * ROUND_OFF_FLOPS * EPS * scale(arm, bound, t, q) / (h / 4) ** 2
        tol = 2 * np.abs(richardson(h) - fd) / 15 + round_off
        np.testing.assert_array_less(np.abs(a @ qdd + kappa - fd), tol)
        assert np.all(tol < 1e-4), tol      # far below the term 2 grad_t . p_dot (>= 0.05)


def _phi_t(arm, bound, t, q, qd):
    """Phi_t = Phi_dot - a . q_dot (gpme), per constraint."""
    _, phi_dot, a, _ = terms(arm, bound, t, q, qd)
    return phi_dot - a @ qd


def test_the_time_dependent_gradient_term_is_large_here(arm, bound):
    """The states exercise the term the factor 2 multiplies: grad(phi_t) . p_dot is the
    rate of Phi_t along q + q_dot s at fixed t (one-sided difference, h = 1e-6: error
    ~1e-6 against the asserted size 0.05)."""
    h = 1e-6
    for t, q, qd, _ in states(arm, 103):
        size = np.abs(_phi_t(arm, bound, t, q + qd * h, qd) - _phi_t(arm, bound, t, q, qd)) / h
        assert np.all(size > 0.05), size


# --------------------------------------------------------------------------- Pinocchio
def arm_scenario(arm, t, q, qd):
    system = ProgrammedMotion(arm, SPECS, baumgarte=(10.0, 10.0)).with_pivoted_dependent(t, q, qd)
    return Scenario(name="arm_time_dependent_ellipses", model=arm, constraints=SPECS,
                    system=system, q0=q, q_dot0=qd, t_end=1.0, quick_t_end=0.2)


def test_terms_agree_with_pinocchio(arm):
    """Phi, Phi_dot, A and kappa (and the frame terms they use) against Pinocchio's frame
    Jacobian and classical acceleration with the SymPy reference, at seeded states, with
    the Pinocchio check's tolerances (round-off)."""
    pytest.importorskip("pinocchio")
    from crosscheck.pinocchio import check as pc
    from crosscheck.states import State
    wanted = {"Phi", "Phi_dot", "constraint jacobian A", "constraint kappa", "frame jacobian",
              "frame drift", "frame velocity"}
    for k, (t, q, qd, _) in enumerate(states(arm, 104, count=3)):
        case = pc.direct_case(arm_scenario(arm, t, q, qd))
        rows = [r for r in pc.compare_state(case, State(f"random {k}", t, q, qd))
                if r["quantity"] in wanted]
        assert {r["quantity"] for r in rows} == wanted
        bad = [(r["quantity"], r["abs_error"], r["tol_abs"], r["tol_rel"]) for r in rows
               if r["status"] != "pass"]
        assert not bad, bad


def test_model_file_with_rotating_ellipse_crosschecks(tmp_path):
    """tests/data/modelfiles/rotating_ellipse.toml: loads, starts on its constraints, and
    its constraint terms pass the Pinocchio comparison at its initial state and a later
    time on the same state (grad phi moves with t)."""
    pytest.importorskip("pinocchio")
    from crosscheck.pinocchio import check as pc
    from crosscheck.states import State
    from gpme_io.modelfile import load_model_file
    s = load_model_file(DATA / "rotating_ellipse.toml")
    phi = s.system.solve(0.0, s.q0, s.q_dot0).phi
    np.testing.assert_allclose(phi, 0.0, atol=1e-10)
    case = pc.direct_case(s)
    for t in (0.0, 0.7):
        rows = [r for r in pc.compare_state(case, State(f"t={t}", t, s.q0, s.q_dot0))
                if r["quantity"] in {"Phi", "Phi_dot", "constraint jacobian A",
                                     "constraint kappa"}]
        assert len(rows) == 4 and all(r["status"] == "pass" for r in rows), rows

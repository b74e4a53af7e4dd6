"""Kill tests for gpme_core.constraints (docs/mutation.md): Phi_dot = a.q_dot + Phi_t and
Phi_ddot = a.q_ddot + kappa against finite differences in time for constraints whose
gradient moves with time (the 2 grad(phi_t).p_dot term), an off-centre ellipse and
coordinate programmes on every axis; joint programmes by hand; input checks."""
import numpy as np
import pytest
import sympy as sp

from gpme_core.constraints import (CoordinateProgramme, EllipseConstraint, JointProgramme,
                                   SympyPointConstraint, bind_constraints, evaluate_constraints)
from gpme_core.errors import ModelError
from gpme_core.kinematics import chain_kinematics
from gpme_core.time_functions import QuinticRamp, Sine

pytestmark = pytest.mark.both_computation_paths

x, y, z, t = sp.symbols("x y z t")


def _fd_check(model, specs, seed):
    """Along q(s) = q + qd s + qdd s^2/2 (t = t0 + s): central differences with h = 1e-4
    have truncation error O(h^2 |Phi'''|) ~ 1e-7 and round-off O(eps |Phi| / h^2) ~ 1e-8,
    so 1e-6 (first) and 1e-4 (second derivative) are safe; the checked terms are O(1)."""
    rng = np.random.default_rng(seed)
    n = model.n_coordinates
    bound = bind_constraints(model, specs)
    q, qd, qdd = rng.normal(0, 0.4, n), rng.normal(0, 1, n), rng.normal(0, 1, n)
    t0 = 0.37

    def ev(s):
        return evaluate_constraints(model, bound, t0 + s, chain_kinematics(model, q + qd * s + 0.5 * qdd * s * s),
                                    qd + qdd * s)

    phi0, pd0, a, kappa = ev(0.0)
    h = 1e-4
    ph, pm = ev(h)[0], ev(-h)[0]
    np.testing.assert_allclose(pd0, (ph - pm) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(a @ qdd + kappa, (ph - 2 * phi0 + pm) / h ** 2, atol=1e-4)
    return phi0, pd0, a, kappa


def test_time_dependent_gradient_constraints_match_finite_differences(arm):
    """phi = x cos(w t) + y sin(w t) + z t - 0.3 (a rotating, drifting plane: grad_t != 0)
    and phi = (x - t^2)^2 + y z (Hessian and grad_t both non-zero), on one point: the
    cached point kinematics serves both."""
    specs = [SympyPointConstraint(x * sp.cos(3 * t) + y * sp.sin(3 * t) + z * t - 0.3, name="plane"),
             SympyPointConstraint((x - t ** 2) ** 2 + y * z, name="quad")]
    for seed in (1, 2, 3):
        _fd_check(arm, specs, seed)


def test_off_centre_ellipse_and_programmes_on_each_axis(arm):
    """Ellipse with a != b and a centre off the origin; x, y and z programmes following a
    sine and a quintic ramp (mid-ramp, where f' and f'' are non-zero)."""
    specs = [EllipseConstraint(0.7, 0.4, center=(0.15, -0.25), name="ell"),
             CoordinateProgramme(Sine(0.1, 0.3, 1.3, 0.2), axis=0, name="px"),
             CoordinateProgramme(QuinticRamp(0.5, 1.0), axis=1, name="py"),
             CoordinateProgramme(Sine(-0.2, 0.1, 0.9), axis=2, name="pz")]
    for seed in (4, 5):
        phi, *_ = _fd_check(arm, specs, seed)
    # values by hand at q = 0, t = 0.37: p = the world position of frame E
    kin = chain_kinematics(arm, np.zeros(arm.n_coordinates))
    fr = arm.frame("E")
    p = (kin.T[fr.link_index] @ fr.transform[:, 3])[:3]
    phi, _, _, _ = evaluate_constraints(arm, bind_constraints(arm, specs), 0.37, kin, np.zeros(arm.n_coordinates))
    s = 0.37
    np.testing.assert_allclose(phi, [((p[0] - 0.15) / 0.7) ** 2 + ((p[1] + 0.25) / 0.4) ** 2 - 1,
                                     p[0] - (0.1 + 0.3 * np.sin(2 * np.pi * 0.37 / 1.3 + 0.2)),
                                     p[1] - 0.5 * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5),
                                     p[2] - (-0.2 + 0.1 * np.sin(2 * np.pi * 0.37 / 0.9))], rtol=1e-12, atol=1e-14)


def test_joint_programme_terms_by_hand(arm):
    """q_k - f(t): Phi = q_k - f, row e_k, Phi_dot = q_dot_k - f', kappa = -f''."""
    f = Sine(0.1, 0.5, 2.0, 0.3)
    jp = JointProgramme("q2", f)
    assert jp.name == "Phi_q2"
    b = bind_constraints(arm, [jp])
    q = np.linspace(0.1, 0.5, arm.n_coordinates)
    qd = np.linspace(-1.0, 1.0, arm.n_coordinates)
    phi, phi_dot, a, kappa = evaluate_constraints(arm, b, 0.7, chain_kinematics(arm, q), qd)
    w = 2 * np.pi / 2.0
    assert phi[0] == pytest.approx(q[2] - (0.1 + 0.5 * np.sin(w * 0.7 + 0.3)), abs=1e-14)
    assert phi_dot[0] == pytest.approx(qd[2] - 0.5 * w * np.cos(w * 0.7 + 0.3), abs=1e-13)
    assert kappa[0] == pytest.approx(0.5 * w ** 2 * np.sin(w * 0.7 + 0.3), abs=1e-13)
    np.testing.assert_array_equal(a[0], np.eye(arm.n_coordinates)[2])
    assert JointProgramme("q1", f, name="mine").name == "mine"


def test_constraint_inputs_are_checked(arm):
    """Bad semi-axes, axes, function types, expressions and repeated names raise ModelError."""
    for bad in (lambda: EllipseConstraint(0.0, 1.0), lambda: EllipseConstraint(1.0, float("nan")),
                lambda: EllipseConstraint(1.0, -2.0),
                lambda: CoordinateProgramme(Sine(0, 1, 1), axis=3),
                lambda: CoordinateProgramme(lambda s: s, axis=0),
                lambda: JointProgramme("q0", lambda s: s),
                lambda: SympyPointConstraint("x +* y"),
                lambda: bind_constraints(arm, [EllipseConstraint(1, 1, name="A"),
                                               CoordinateProgramme(Sine(0, 1, 1), name="A")])):
        with pytest.raises(ModelError):
            bad()
    e = EllipseConstraint(2.0, 0.5, center=(1.0, 0.0), frame="E", name="ok")
    assert (e.a, e.b, e.frame, e.name) == (2.0, 0.5, "E", "ok")

"""Trace-form M, h, g against Lagrange's equations obtained by finite-differencing the
energies, and against an independent double-sum evaluation of the trace formulas."""
import numpy as np

from gpme_core import dynamics as dy
from gpme_core.kinematics import chain_kinematics
import pytest

pytestmark = pytest.mark.both_computation_paths

H = 1e-6  # central-difference step; errors ~ h^2 * 3rd derivative ~ 1e-12 plus eps/h ~ 1e-10


def _grad(f, x, h=H):
    n = len(x)
    out = np.empty(n)
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        out[i] = (f(x + e) - f(x - e)) / (2 * h)
    return out


def test_mass_matrix_equals_trace_double_sum(arm, crane, tree, rng):
    for model in (arm, crane, tree):
        n = model.n_coordinates
        q = rng.uniform(-1, 1, n)
        kin = chain_kinematics(model, q)
        m = np.zeros((n, n))
        for l in range(n):
            hl = model.pseudo_inertias[l]
            for i in range(n):
                for j in range(n):
                    m[i, j] += np.trace(kin.T_first(l, i) @ hl @ kin.T_first(l, j).T)
        np.testing.assert_allclose(dy.mass_matrix(model, q), m, rtol=1e-13, atol=1e-13)


def test_mass_matrix_symmetric_positive_definite(arm, crane, tree, rng):
    for model in (arm, crane, tree):
        for _ in range(5):
            m = dy.mass_matrix(model, rng.uniform(-2, 2, model.n_coordinates))
            np.testing.assert_array_equal(m, m.T)
            assert np.linalg.eigvalsh(m).min() > 0


def test_kinetic_energy_trace_form_equals_quadratic_form(arm, crane, tree, rng):
    for model in (arm, crane, tree):
        n = model.n_coordinates
        q, qd = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
        e = dy.kinetic_energy(model, q, qd)
        assert abs(e - 0.5 * qd @ dy.mass_matrix(model, q) @ qd) < 1e-13 * max(e, 1)


def test_velocity_products_match_lagrange_equations(arm, crane, tree, rng):
    """c = d/dt(dT/dq_dot)|_{q_ddot=0} - dT/dq = (dM/dt) q_dot - dT/dq, and h = -c."""
    for model in (arm, crane, tree):
        n = model.n_coordinates
        q, qd = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
        dt_dq = _grad(lambda x: dy.kinetic_energy(model, x, qd), q)
        m_dot = (dy.mass_matrix(model, q + H * qd) - dy.mass_matrix(model, q - H * qd)) / (2 * H)
        c = m_dot @ qd - dt_dq
        h = dy.velocity_product_terms(model, q, qd)
        np.testing.assert_allclose(-h, c, atol=1e-7 * max(1, np.abs(c).max()))


def test_gravity_is_gradient_of_potential(arm, crane, tree, rng):
    for model in (arm, crane, tree):
        q = rng.uniform(-1, 1, model.n_coordinates)
        g_fd = _grad(lambda x: dy.gravity_potential_energy(model, x), q)
        np.testing.assert_allclose(dy.gravity_forces(model, q), g_fd, atol=1e-7)


def test_gravity_sign_lifting_a_mass_costs_energy(crane):
    """Gravity (0, 0, -9.81): raising the support by dz changes E_p by m_total * 9.81 * dz."""
    q = np.zeros(crane.n_coordinates)
    g = dy.gravity_forces(crane, q)
    assert np.isclose(g[crane.index("z1")], crane.total_mass * 9.81, rtol=1e-14)


def test_springs_and_dampers_are_gradients_of_v_and_r(arm, rng):
    n = arm.n_coordinates
    q, qd = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
    np.testing.assert_allclose(dy.spring_forces(arm, q),
                               _grad(lambda x: dy.spring_potential_energy(arm, x), q), atol=1e-8)
    np.testing.assert_allclose(dy.damper_forces(arm, qd),
                               _grad(lambda x: dy.rayleigh_function(arm, x), qd), atol=1e-8)
    # no factor-2 slip: V = 1/2 k dq^2 exactly
    k = arm.index("q4")
    dq = q[k] - arm.spring_reference[k]
    assert np.isclose(dy.spring_forces(arm, q)[k], 50.0 * dq)

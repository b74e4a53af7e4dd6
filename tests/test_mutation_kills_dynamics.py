"""Kill tests for gpme_core.dynamics, gpme_core.kinematics and the compiled kernels of
gpme_core.fast (docs/mutation.md): a planar double pendulum whose M, h, g, energies and
end-point kinematics are written out by hand, run on whichever path is active (numpy
reference under GPME_NO_JIT=1, numba kernels otherwise)."""
import numpy as np
import pytest

from gpme_core import dynamics as dyn
from gpme_core import kinematics as kin_mod
from gpme_core import transforms as tf
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder
from gpme_core.time_functions import Constant

pytestmark = pytest.mark.both_computation_paths

M1, M2, L1, C1, C2, G0 = 2.0, 1.5, 0.8, 0.3, 0.45, 9.81
B1, B2 = (0.6, 0.1, 0.2), (0.9, 0.15, 0.05)         # box sizes (x, y, z) m
K, QREF, D, TAU = (3.0, 5.0), (0.2, -0.1), (0.4, 0.7), (1.5, -0.25)
# closed forms and the trace form differ only by round-off of O(10) flops on O(10) values
TOL = 1e-11


def izz(m, s):
    return m * (s[0] ** 2 + s[1] ** 2) / 12.0


def pendulum():
    """Two revolute joints about world z (gravity along -y: a vertical plane), link 1 of
    length L1 with its centre of mass at C1, link 2 at C2 from joint 2, frame E at the
    end of link 2 offset (0.9, 0.05, 0.02)."""
    b = ChainBuilder("double_pendulum", gravity=(0.0, -G0, 0.0))
    b.add_joint("q1", REVOLUTE, (0, 0, 1), stiffness=K[0], spring_reference=QREF[0], damping=D[0])
    b.add_body(cuboid(M1, B1, com=(C1, 0, 0)))
    b.add_joint("q2", REVOLUTE, (0, 0, 1), origin=tf.translation(L1, 0, 0), stiffness=K[1],
                spring_reference=QREF[1], damping=D[1])
    b.add_body(cuboid(M2, B2, com=(C2, 0, 0)))
    b.add_frame("E", tf.translation(0.9, 0.05, 0.02))
    b.add_drive("q1", Constant(TAU[0]))
    b.add_drive("q2", Constant(TAU[1]))
    return b.build()


def closed_form(q, qd):
    """Textbook double pendulum: M, h = -(Coriolis + centrifugal), g = dV/dq, E_k, V."""
    c2, s2 = np.cos(q[1]), np.sin(q[1])
    i1, i2 = izz(M1, B1), izz(M2, B2)
    m11 = i1 + M1 * C1 ** 2 + i2 + M2 * (L1 ** 2 + C2 ** 2 + 2 * L1 * C2 * c2)
    m12 = i2 + M2 * (C2 ** 2 + L1 * C2 * c2)
    m22 = i2 + M2 * C2 ** 2
    m = np.array([[m11, m12], [m12, m22]])
    hh = M2 * L1 * C2 * s2
    h = np.array([hh * (2 * qd[0] * qd[1] + qd[1] ** 2), -hh * qd[0] ** 2])
    g = np.array([M1 * G0 * C1 * np.cos(q[0]) + M2 * G0 * (L1 * np.cos(q[0]) + C2 * np.cos(q[0] + q[1])),
                  M2 * G0 * C2 * np.cos(q[0] + q[1])])
    v = M1 * G0 * C1 * np.sin(q[0]) + M2 * G0 * (L1 * np.sin(q[0]) + C2 * np.sin(q[0] + q[1]))
    return m, h, g, 0.5 * qd @ m @ qd, v


# joint velocities 0, +1 and -1 exactly among them (the compiled point kernel branches on
# q_dot_l != 0)
STATES = [((0.3, -0.7), (1.1, -0.4)), ((-1.2, 2.0), (-0.3, 0.9)), ((2.5, 0.4), (0.0, 1.7)),
          ((0.6, -1.9), (1.0, -1.0))]


@pytest.mark.parametrize("q, qd", STATES)
def test_double_pendulum_terms_equal_the_textbook_equations(q, qd):
    """M, h, g, springs, dampers, drives, Q = -(g + d + f) + t and h + Q of dynamics_terms
    and of the separate functions equal the closed form of the planar double pendulum."""
    model = pendulum()
    q, qd = np.array(q), np.array(qd)
    m, h, g, ek, v = closed_form(q, qd)
    f = np.array(K) * (q - QREF)
    d = np.array(D) * qd
    t = np.array(TAU)
    terms = dyn.dynamics_terms(model, 0.0, q, qd)
    for got, want in ((terms.M, m), (terms.h, h), (terms.g, g), (terms.f, f), (terms.d, d),
                      (terms.t, t), (terms.Q, -(g + d + f) + t), (terms.rhs, h - (g + d + f) + t),
                      (dyn.mass_matrix(model, q), m), (dyn.velocity_product_terms(model, q, qd), h),
                      (dyn.gravity_forces(model, q), g),
                      (dyn.generalized_forces(model, 0.0, q, qd), -(g + d + f) + t)):
        np.testing.assert_allclose(got, want, rtol=TOL, atol=TOL)
    assert dyn.kinetic_energy(model, q, qd) == pytest.approx(ek, rel=TOL)
    assert dyn.gravity_potential_energy(model, q) == pytest.approx(v, rel=TOL, abs=TOL)
    vs = 0.5 * np.sum(np.array(K) * (q - QREF) ** 2)
    assert dyn.spring_potential_energy(model, q) == pytest.approx(vs, rel=TOL)
    assert dyn.potential_energy(model, q) == pytest.approx(v + vs, rel=TOL, abs=TOL)
    assert dyn.rayleigh_function(model, qd) == pytest.approx(0.5 * np.sum(np.array(D) * qd ** 2), rel=TOL)


@pytest.mark.parametrize("q, qd", STATES)
def test_end_point_kinematics_of_the_double_pendulum(q, qd):
    """Frame E at r = (0.9, 0.05, 0.02) on link 2: p = R(q1) (L1, 0, 0) + R(q1 + q2) r;
    Jacobian, velocity and drift (p_ddot at q_ddot = 0: -omega^2 terms) by hand."""
    model = pendulum()
    q, qd = np.array(q), np.array(qd)
    link, r = kin_mod.frame_point(model, "E")
    assert link == 1
    np.testing.assert_array_equal(r, [0.9, 0.05, 0.02])
    a1, a12 = q[0], q[0] + q[1]
    w1, w12 = qd[0], qd[0] + qd[1]

    def rot(a, v):
        return np.array([np.cos(a) * v[0] - np.sin(a) * v[1], np.sin(a) * v[0] + np.cos(a) * v[1]])

    def perp(v):                       # z x v
        return np.array([-v[1], v[0]])
    u1, u2 = rot(a1, (L1, 0.0)), rot(a12, r[:2])
    pos = np.array([*(u1 + u2), 0.02])
    jac = np.zeros((3, 2))
    jac[:2, 0] = perp(u1 + u2)
    jac[:2, 1] = perp(u2)
    drift = np.array([*(-w1 ** 2 * u1 - w12 ** 2 * u2), 0.0])
    kin = kin_mod.chain_kinematics(model, q)
    pk = kin_mod.point_kinematics(model, kin, qd, link, r)
    np.testing.assert_allclose(pk.position, pos, rtol=TOL, atol=TOL)
    np.testing.assert_allclose(pk.jacobian, jac, rtol=TOL, atol=TOL)
    np.testing.assert_allclose(pk.velocity, jac @ qd, rtol=TOL, atol=TOL)
    np.testing.assert_allclose(pk.drift, drift, rtol=TOL, atol=TOL)
    # a point on link 1 does not move with q2
    pk1 = kin_mod.point_kinematics(model, kin, qd, 0, np.array([L1, 0, 0]))
    np.testing.assert_allclose(pk1.jacobian[:, 1], 0.0, atol=0)
    np.testing.assert_allclose(pk1.drift[:2], -w1 ** 2 * u1, rtol=TOL, atol=TOL)


def test_point_kinematics_with_a_resting_joint():
    """q_dot_1 = 0 (the compiled kernel skips resting joints): only joint 2 turns, the end
    point moves on a circle about joint 2: drift = -w2^2 (p - p_joint2)."""
    model = pendulum()
    q, qd = np.array([0.4, 0.9]), np.array([0.0, 1.3])
    kin = kin_mod.chain_kinematics(model, q)
    pk = kin_mod.point_kinematics(model, kin, qd, 1, np.array([0.9, 0.05, 0.02]))
    joint2 = kin.T[1, :3, 3]
    np.testing.assert_allclose(pk.drift, -1.3 ** 2 * np.append((pk.position - joint2)[:2], 0.0),
                               rtol=TOL, atol=TOL)
    np.testing.assert_allclose(pk.velocity, pk.jacobian[:, 1] * 1.3, rtol=TOL, atol=TOL)


def test_single_transform_derivatives_and_rigid_inverse():
    """T_i^(l), T_ij^(l) against central differences (error O(h^2) ~ 1e-8 at h = 1e-4,
    tolerance 1e-6); zero when i or j is beyond the link; rigid_inverse(T) T = E."""
    model = pendulum()
    q = np.array([0.3, -0.7])
    h = 1e-4
    for link in (0, 1):
        for i in (0, 1):
            e = np.eye(2)[i] * h
            fd = (kin_mod.link_transforms(model, q + e)[link] - kin_mod.link_transforms(model, q - e)[link]) / (2 * h)
            got = kin_mod.transform_derivative(model, q, link, i)
            np.testing.assert_allclose(got, fd if i <= link else 0.0, atol=1e-6)
            for j in (0, 1):
                ej = np.eye(2)[j] * h
                fd2 = (kin_mod.transform_derivative(model, q + ej, link, i)
                       - kin_mod.transform_derivative(model, q - ej, link, i)) / (2 * h)
                got2 = kin_mod.transform_second_derivative(model, q, link, i, j)
                np.testing.assert_allclose(got2, fd2, atol=1e-6)
                if max(i, j) > link:
                    assert not got2.any()
    t = kin_mod.link_transforms(model, q)
    np.testing.assert_allclose(kin_mod.rigid_inverse(t) @ t, np.broadcast_to(np.eye(4), t.shape), atol=1e-14)


def test_prismatic_joint_moves_along_its_axis_times_q():
    """A slider along the unit axis u moves its link by q u; a revolute joint after it
    turns about the moved axis (T of the second link by hand)."""
    b = ChainBuilder("slider")
    u = np.array([1.0, 2.0, 2.0]) / 3.0
    b.add_joint("s", PRISMATIC, u, origin=tf.translation(0.1, 0, 0))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_joint("r", REVOLUTE, (0, 0, 1), origin=tf.translation(0, 0.2, 0))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1), com=(0.1, 0, 0)))
    model = b.build()
    q = np.array([0.7, 0.5])
    t = kin_mod.chain_kinematics(model, q).T
    np.testing.assert_allclose(t[0], tf.translation(*(np.array([0.1, 0, 0]) + 0.7 * u)), atol=1e-14)
    np.testing.assert_allclose(t[1], tf.translation(*(np.array([0.1, 0.2, 0]) + 0.7 * u)) @ tf.rot_z(0.5), atol=1e-14)
    # slider mass matrix entry: total mass 2 kg (a slider carries everything after it)
    assert dyn.mass_matrix(model, q)[0, 0] == pytest.approx(2.0, rel=1e-12)
    # gravity along -z on the slider: g_s = -m_total gamma . u = 2 * 9.81 * u_z
    assert dyn.gravity_forces(model, q)[0] == pytest.approx(2.0 * 9.81 * u[2], rel=1e-12)

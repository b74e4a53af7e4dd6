"""Kill tests for gpme_core.inertia (docs/mutation.md): the pseudo-inertia H = int r r^T dm
checked on clouds of point masses (where the integral is a finite sum), the box and
cylinder formulas by hand, and the physical-validity checks at their boundaries."""
import dataclasses

import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.errors import ModelError
from gpme_core.inertia import (RigidBodyInertia, check_pseudo_inertia, cuboid, cylinder,
                               inertia_from_pseudo, pseudo_inertia, transform_pseudo_inertia)

pytestmark = pytest.mark.both_computation_paths

RT = 1e-12      # sums of a handful of products: round-off only


def _cloud(seed=7, k=6):
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 2.0, k)
    r = rng.normal(size=(k, 3))
    mass = m.sum()
    com = (m[:, None] * r).sum(axis=0) / mass
    d = r - com
    i_c = sum(mk * (dk @ dk * np.eye(3) - np.outer(dk, dk)) for mk, dk in zip(m, d))
    h = sum(mk * np.outer(np.append(rk, 1), np.append(rk, 1)) for mk, rk in zip(m, r))
    return m, r, mass, com, i_c, h


def test_pseudo_inertia_is_the_second_moment_of_a_point_cloud():
    """H = sum m_k r_k r_k^T (r = (x, y, z, 1)) from the cloud's mass, centre of mass and
    inertia about it; the inverse map returns them; a rigid change of frame X gives
    sum m (X r)(X r)^T."""
    m, r, mass, com, i_c, h = _cloud()
    np.testing.assert_allclose(pseudo_inertia(mass, com, i_c), h, rtol=RT, atol=1e-12)
    np.testing.assert_allclose(RigidBodyInertia(mass, com, i_c).pseudo_inertia(), h, rtol=RT, atol=1e-12)
    m2, c2, i2 = inertia_from_pseudo(h)
    assert m2 == pytest.approx(mass, rel=RT)
    np.testing.assert_allclose(c2, com, rtol=RT, atol=1e-12)
    np.testing.assert_allclose(i2, i_c, rtol=RT, atol=1e-12)
    x = tf.translation(0.3, -0.2, 0.5) @ tf.rot_x(0.4) @ tf.rot_z(1.1)
    rx = (x[:3, :3] @ r.T).T + x[:3, 3]
    hx = sum(mk * np.outer(np.append(p, 1), np.append(p, 1)) for mk, p in zip(m, rx))
    np.testing.assert_allclose(transform_pseudo_inertia(x, h), hx, rtol=RT, atol=1e-12)


def test_massless_pseudo_inertia_returns_the_rotational_inertia():
    """H with H[3, 3] = 0 (a rotor whose mass is counted elsewhere): J = tr(I)/2 E - I in the
    3x3 block; the inverse map gives I back and com = 0."""
    i = np.array([[2.0, 0.1, 0.0], [0.1, 3.0, 0.2], [0.0, 0.2, 4.0]])
    h = np.zeros((4, 4))
    h[:3, :3] = 0.5 * np.trace(i) * np.eye(3) - i
    mass, com, i_back = inertia_from_pseudo(h)
    assert mass == 0.0
    np.testing.assert_array_equal(com, np.zeros(3))
    np.testing.assert_allclose(i_back, i, rtol=RT)


def test_box_and_cylinder_moments_by_hand():
    """Box m = 12 kg, 1 x 2 x 3 m: I = m/12 (b^2 + c^2, ...) = (13, 10, 5) kg m^2.  Solid
    cylinder m = 12, r = 1, L = 2: axial m r^2/2 = 6, transverse m (3 r^2 + L^2)/12 = 7;
    r = 0.5: axial 1.5, transverse 4.75.  Tube r_o = 1, r_i = 0.5: axial
    m (r_o^2 + r_i^2)/2 = 7.5, transverse m (3 (r_o^2 + r_i^2) + L^2)/12 = 7.75; r_o = 0.5,
    r_i = 0.25: axial 1.875, transverse 4.9375; r = 0.5, L = 3: transverse 9.75."""
    np.testing.assert_allclose(np.diag(cuboid(12.0, (1, 2, 3), com=(1, 2, 3)).inertia_array), [13, 10, 5], rtol=RT)
    assert cuboid(12.0, (1, 2, 3), com=(1, 2, 3)).com == (1.0, 2.0, 3.0)
    np.testing.assert_allclose(np.diag(cylinder(12.0, 1.0, 2.0).inertia_array), [7, 7, 6], rtol=RT)
    np.testing.assert_allclose(np.diag(cylinder(12.0, 1.0, 2.0, axis=0).inertia_array), [6, 7, 7], rtol=RT)
    np.testing.assert_allclose(np.diag(cylinder(12.0, 1.0, 2.0, axis=1, inner_radius=0.5).inertia_array),
                               [7.75, 7.5, 7.75], rtol=RT)
    np.testing.assert_allclose(np.diag(cylinder(12.0, 0.5, 2.0).inertia_array), [4.75, 4.75, 1.5], rtol=RT)
    # L = 3 (L^2 = 9, not 2 L or L + 2): transverse 12 (0.75 + 9) / 12 = 9.75
    np.testing.assert_allclose(np.diag(cylinder(12.0, 0.5, 3.0).inertia_array), [9.75, 9.75, 1.5], rtol=RT)
    np.testing.assert_allclose(np.diag(cylinder(12.0, 0.5, 2.0, inner_radius=0.25).inertia_array),
                               [4.9375, 4.9375, 1.875], rtol=RT)
    assert cylinder(12.0, 1.0, 2.0, com=(0, 0, 1)).com == (0.0, 0.0, 1.0)
    assert cylinder(12.0, 1.0, 2.0).com == (0.0, 0.0, 0.0)          # default: centred
    assert cuboid(12.0, (1, 2, 3)).com == (0.0, 0.0, 0.0)


def test_validity_checks_at_their_boundaries():
    """Accepted: zero mass with zero tensor, a thin plate I1 + I2 = I3 exactly, a thin rod
    (one zero moment), a point mass with a -1e-35 moment (URDF round-off), negative moments
    of 1e-13 of the largest (round-off of a rotated tensor; the tolerance is 1e-12 of it).
    Rejected:
    negative or non-finite mass, non-finite or mis-shaped com/tensor, asymmetric tensor,
    a negative moment.  Accepted but said non-physical (issue 28: as Pinocchio accepts it):
    the triangle inequality broken by 1 %; the plate at equality is physical."""
    ok = [RigidBodyInertia(0.0), RigidBodyInertia(1.0, (0, 0, 0), np.diag([1.0, 1.0, 2.0])),
          RigidBodyInertia(1.0, (0, 0, 0), np.diag([0.0, 1.0, 1.0])),
          RigidBodyInertia(1.0, (0, 0, 0), np.diag([-1e-35, 0.0, 0.0])),
          RigidBodyInertia(1e6, (0, 0, 0), np.diag([-0.5e-6, 0.0, 0.0])),   # below m * (1 um)^2
          # round-off of a rotated tensor: a moment of -1e-13 relative to the largest one
          RigidBodyInertia(0.0, (0, 0, 0), np.diag([-1e-13, 1.0, 1.0])),
          RigidBodyInertia(1.0, (0, 0, 0), np.diag([-5e-10, 1e3, 1e3])),
          # symmetric to round-off only (off-diagonals differ by 1e-13 relative)
          RigidBodyInertia(1.0, (0, 0, 0), [[1, 0.1, 0], [0.1 * (1 + 1e-13), 1, 0], [0, 0, 1]])]
    for body in ok:
        assert body.problems("b") == [] and body.non_physical("b") == [], body
    bad = {"mass must be": RigidBodyInertia(-1.0), "mass must be ": RigidBodyInertia(float("nan")),
           "centre of mass": RigidBodyInertia(1.0, (0, np.inf, 0)),
           "centre of mass ": RigidBodyInertia(1.0, (0, 0)),
           " centre of mass ": RigidBodyInertia(1.0, (0, 0, 0, 0)),
           "finite (3, 3)": RigidBodyInertia(1.0, (0, 0, 0), np.diag([np.nan, 1, 1])),
           "finite (3, 3) ": RigidBodyInertia(1.0, (0, 0, 0), np.eye(2)),
           " finite (3, 3)": RigidBodyInertia(1.0, (0, 0, 0), np.eye(4)),
           " negative principal": RigidBodyInertia(0.0, (0, 0, 0), np.diag([-0.5, 1.0, 1.0])),
           "symmetric": RigidBodyInertia(1.0, (0, 0, 0), [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]),
           "symmetric ": RigidBodyInertia(1.0, (0, 0, 0), [[1, 0.1, 0], [0.15, 1, 0], [0, 0, 1]]),
           "negative principal": RigidBodyInertia(1.0, (0, 0, 0), np.diag([-0.01, 1.0, 1.0]))}
    for msg, body in bad.items():
        p = body.problems("b")
        assert len(p) >= 1 and msg.strip() in " ".join(p), (msg, p)
    # the triangle broken by 1 %, and with three different moments (0.5 + 1.0 < 1.6)
    for body, excess in ((RigidBodyInertia(1.0, (0, 0, 0), np.diag([1.0, 1.0, 2.02])), 0.02),
                         (RigidBodyInertia(1.0, (0, 0, 0), np.diag([1.6, 0.5, 1.0])), 0.1)):
        assert body.problems("b") == []
        assert "triangle inequality" in body.non_physical("b")[0]
        assert body.triangle_excess() == pytest.approx(excess, rel=1e-12)
    # a negative moment of a point mass just above the 1 um threshold is rejected
    assert RigidBodyInertia(1.0, (0, 0, 0), np.diag([-2e-12, 0, 0])).problems("b")


def test_defaults_and_immutability():
    """RigidBodyInertia(m) is a point mass at the body origin (com 0, tensor 0); the record
    is frozen (a model's bodies must not change under it)."""
    body = RigidBodyInertia(2.0)
    assert body.com == (0.0, 0.0, 0.0)
    np.testing.assert_array_equal(body.inertia_array, np.zeros((3, 3)))
    with pytest.raises(dataclasses.FrozenInstanceError):
        body.mass = 3.0


def test_check_pseudo_inertia_raises_on_unphysical_h():
    """check_pseudo_inertia: wrong shape and an H whose I_C has a negative principal moment
    raise ModelError; the H of a real box passes, and so does one whose I_C only breaks the
    triangle inequality (accepted, as Pinocchio accepts it: RigidBodyInertia.non_physical)."""
    check_pseudo_inertia(cuboid(2.0, (0.1, 0.2, 0.3), com=(0.1, 0, 0)).pseudo_inertia())
    with pytest.raises(ModelError, match="shape"):
        check_pseudo_inertia(np.eye(3))
    with pytest.raises(ModelError, match="shape"):
        check_pseudo_inertia(np.eye(5))
    check_pseudo_inertia(pseudo_inertia(1.0, (0, 0, 0), np.diag([1.0, 1.0, 2.5])))
    with pytest.raises(ModelError, match="negative principal moment"):
        check_pseudo_inertia(pseudo_inertia(1.0, (0, 0, 0), np.diag([-0.5, 1.0, 2.5])))


def test_check_pseudo_inertia_rejects_a_negative_mass():
    """H[3, 3] = m = -1 kg is no physical body; the docstring promises mass >= 0 is checked."""
    h = np.zeros((4, 4))
    h[3, 3] = -1.0
    with pytest.raises(ModelError, match="mass"):
        check_pseudo_inertia(h)

"""T_i and T_ij of the chain structure against central finite differences of T^(l)."""
import numpy as np
import pytest

from gpme_core.kinematics import (chain_kinematics, link_transforms, point_kinematics,
                                  velocity_product_accelerations)

pytestmark = pytest.mark.both_computation_paths

# Central differences with step h have truncation error ~ h^2 |T'''| / 6 ~ 1e-9 at h = 1e-5
# and round-off ~ eps / h ~ 1e-11; 1e-7 leaves a factor ~100 margin on both.
FD_STEP = 1e-5
FD_TOL = 1e-7


def models(arm, crane, tree):
    return [arm, crane, tree]


def test_first_derivatives_match_finite_differences(arm, crane, tree, rng):
    for model in models(arm, crane, tree):
        n = model.n_coordinates
        q = rng.uniform(-1, 1, n)
        kin = chain_kinematics(model, q)
        for i in range(n):
            dq = np.zeros(n)
            dq[i] = FD_STEP
            fd = (link_transforms(model, q + dq) - link_transforms(model, q - dq)) / (2 * FD_STEP)
            for l in range(n):
                np.testing.assert_allclose(kin.T_first(l, i), fd[l], atol=FD_TOL, rtol=0)


def test_second_derivatives_match_finite_differences(arm, crane, tree, rng):
    for model in models(arm, crane, tree):
        n = model.n_coordinates
        q = rng.uniform(-1, 1, n)
        for i in range(n):
            dq = np.zeros(n)
            dq[i] = FD_STEP
            kp, km = chain_kinematics(model, q + dq), chain_kinematics(model, q - dq)
            kin = chain_kinematics(model, q)
            for j in range(n):
                for l in range(n):
                    fd = (kp.T_first(l, j) - km.T_first(l, j)) / (2 * FD_STEP)
                    np.testing.assert_allclose(kin.T_second(l, i, j), fd, atol=FD_TOL, rtol=0,
                                               err_msg=f"T_{i}{j}^({l})")


def test_velocity_product_recursion_equals_double_sum(arm, tree, rng):
    for model in (arm, tree):
        n = model.n_coordinates
        q, qd = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
        kin = chain_kinematics(model, q)
        b = velocity_product_accelerations(kin.S, qd, model.parents)
        for l in range(n):
            direct = sum(kin.T_second(l, i, j) * qd[i] * qd[j]
                         for i in range(n) for j in range(n))
            np.testing.assert_allclose(b[l] @ kin.T[l], direct, atol=1e-12)


@pytest.mark.parametrize("which, frame", [("arm", "E"), ("tree", "E"), ("tree", "F")])
def test_point_jacobian_and_drift_match_finite_differences_in_time(which, frame, arm, tree,
                                                                     rng):
    model = {"arm": arm, "tree": tree}[which]
    n = model.n_coordinates
    q, qd, qdd = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
    fr = model.frame(frame)
    r = fr.transform[:3, 3]

    def position(t):
        qt = q + qd * t + 0.5 * qdd * t * t
        return link_transforms(model, qt)[fr.link_index] @ np.append(r, 1.0)

    pk = point_kinematics(model, chain_kinematics(model, q), qd, fr.link_index, r)
    h = 1e-4
    vel = (position(h) - position(-h))[:3] / (2 * h)
    acc = (position(h) - 2 * position(0.0) + position(-h))[:3] / h ** 2
    np.testing.assert_allclose(pk.velocity, vel, atol=1e-7)
    # second difference: truncation ~ h^2 |p''''| / 12 ~ 1e-8, round-off ~ eps/h^2 ~ 2e-8
    np.testing.assert_allclose(pk.jacobian @ qdd + pk.drift, acc, atol=1e-6)
    # a joint off the point's path does not move it
    off_path = ~model.moves[:, fr.link_index]
    assert not pk.jacobian[:, off_path].any()

"""The compiled kernels (gpme_core.fast) equal the readable numpy trace-form reference."""
import numpy as np
import pytest

from gpme_core import dynamics as dy
from gpme_core import fast
from gpme_examples.crane import build_crane
from gpme_core.kinematics import chain_kinematics

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: numpy path only")


@pytest.mark.parametrize("n_rfe", [0, 3, 10])
def test_kernels_equal_reference_to_round_off(n_rfe, arm, rng):
    for model in (build_crane(n_rfe), arm):
        n = model.n_coordinates
        q, qd = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
        t_all, s_all = fast.chain(model.origins, model.generators, model.is_revolute, q)
        kin = chain_kinematics(model, q)
        np.testing.assert_allclose(t_all, kin.T, rtol=0, atol=1e-14)
        np.testing.assert_allclose(s_all, kin.S, rtol=0, atol=1e-14)
        m, h, g = fast.terms(t_all, s_all, model.pseudo_inertias, np.append(model.gravity, 0), qd)
        # round-off of sums over n links of 4x4 products: ~n * eps * scale
        for fast_val, ref in ((m, dy.mass_matrix(model, q)),
                              (h, dy.velocity_product_terms(model, q, qd)),
                              (g, dy.gravity_forces(model, q))):
            np.testing.assert_allclose(fast_val, ref, rtol=0, atol=1e-13 * max(1, np.abs(ref).max()))

"""The compiled kernels (gpme_core.fast) equal the readable numpy trace-form reference."""
import numpy as np
import pytest

from gpme_core import dynamics as dy
from gpme_core import fast
from gpme_examples.crane import build_crane
from gpme_core.kinematics import chain_kinematics

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: numpy path only")


@pytest.mark.parametrize("n_rfe", [0, 3, 10])
def test_kernels_equal_reference_to_round_off(n_rfe, arm, tree, rng):
    for model in (build_crane(n_rfe), arm, tree):
        n = model.n_coordinates
        q, qd = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
        t_all, s_all = fast.chain(model.origins, model.generators, model.is_revolute,
                                  model.parents, q)
        kin = chain_kinematics(model, q)
        np.testing.assert_allclose(t_all, kin.T, rtol=0, atol=1e-14)
        np.testing.assert_allclose(s_all, kin.S, rtol=0, atol=1e-14)
        m, h, g = fast.terms(t_all, s_all, model.pseudo_inertias, np.append(model.gravity, 0),
                             model.parents, model.moves, qd)
        # round-off of sums over n links of 4x4 products: ~n * eps * scale
        for fast_val, ref in ((m, dy.mass_matrix(model, q)),
                              (h, dy.velocity_product_terms(model, q, qd)),
                              (g, dy.gravity_forces(model, q))):
            np.testing.assert_allclose(fast_val, ref, rtol=0, atol=1e-13 * max(1, np.abs(ref).max()))


def _with_path(monkeypatch, enabled, compute):
    """compute() with gpme_core's dispatch set to the compiled (True) or numpy (False) path."""
    monkeypatch.setattr(fast, "ENABLED", enabled)
    try:
        return compute()
    finally:
        monkeypatch.undo()


@pytest.mark.parametrize("n_rfe", [0, 3])
def test_point_kinematics_compiled_equals_numpy(n_rfe, arm, tree, rng, monkeypatch):
    """fast.point against the numpy route of kinematics.point_kinematics (position, velocity,
    Jacobian C, drift d of a point off the link origin) at random states, on every link."""
    from gpme_core.kinematics import point_kinematics
    for model in (build_crane(n_rfe), arm, tree):
        n = model.n_coordinates
        q, qd = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
        kin = chain_kinematics(model, q)
        r_local = rng.uniform(-0.5, 0.5, 3)
        for link in range(n):
            compiled = _with_path(monkeypatch, True,
                                  lambda: point_kinematics(model, kin, qd, link, r_local))
            reference = _with_path(monkeypatch, False,
                                   lambda: point_kinematics(model, kin, qd, link, r_local))
            for name in ("position", "velocity", "jacobian", "drift"):
                a, b = getattr(compiled, name), getattr(reference, name)
                # sums over <= n 4x4 products of O(1) entries: round-off ~ n eps |b|
                np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * max(1.0, np.abs(b).max()),
                                           err_msg=f"{model.name} link {link} {name}")


@pytest.mark.parametrize("n_rfe", [0, 3])
def test_reduced_solve_compiled_equals_numpy(n_rfe, rng, monkeypatch):
    """The compiled reduced solve (gpme_core.kernels.reduced_solve, the compiled runs' own:
    Cholesky of N^T M N) against the numpy reference (LU of N^T M q_ddot = N^T rhs with the
    constraint rows): accelerations and multipliers at random states near the crane's
    manifold (Baumgarte terms active, so the whole right-hand side is exercised)."""
    from gpme_examples.crane import crane_system, initial_state
    system = crane_system(n_rfe)
    q0, _ = initial_state(system.model)
    n = system.model.n_coordinates
    for _ in range(3):
        q = q0 + rng.normal(0.0, 0.05, n)
        qd = rng.normal(0.0, 0.5, n)
        compiled = _with_path(monkeypatch, True, lambda: system.solve(0.3, q, qd))
        reference = _with_path(monkeypatch, False, lambda: system.solve(0.3, q, qd))
        # a linear solve of condition number ~cond(M) * cond(A_dc): allow 1e-10 relative
        # (cond(M) of the crane with the RFEM arm ~1e5, eps ~ 2e-16 -> ~1e-11)
        for name in ("q_ddot", "multipliers"):
            a, b = getattr(compiled, name), getattr(reference, name)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * max(1.0, np.abs(b).max()),
                                       err_msg=name)


def test_state_array_gives_writeable_float_arrays_and_copies_only_when_needed():
    frozen = np.arange(4.0)
    frozen.setflags(write=False)
    out = fast.state_array(frozen)
    assert out.flags.writeable and out.flags.c_contiguous and out.dtype == np.float64
    assert np.array_equal(out, frozen) and out is not frozen
    mine = np.linspace(0.0, 1.0, 5)
    assert fast.state_array(mine) is mine                  # nothing to copy
    assert fast.state_array([1, 2]).dtype == np.float64    # lists and ints become floats


def test_a_read_only_state_compiles_no_second_kernel_signature():
    """numba types read-only arrays apart; dynamics_terms and the compiled evaluation
    hand it writeable states, so no kernel is (compiled or loaded) for a read-only q."""
    from gpme_core.compiled import for_system
    from gpme_io.scenario import crane_scenario
    sc = crane_scenario(1, on_constraints=True)
    q, qd = np.array(sc.q0, float), np.array(sc.q_dot0, float)
    q.setflags(write=False)
    qd.setflags(write=False)
    dy.dynamics_terms(sc.model, 0.0, q, qd)
    compiled, _ = for_system(sc.system)
    compiled.evaluate(0.0, q, qd, sc.system.ic, sc.system.dc)
    for kernel, state_args in ((fast.chain_and_terms, (-2, -1)),
                               (compiled.module.evaluate, (1, 2))):
        assert kernel.signatures
        for sig in kernel.signatures:
            assert not any(sig[k].mutable is False for k in state_args), (kernel, sig)

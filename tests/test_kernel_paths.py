"""The two code paths of the compiled trace-form terms (gpme_core.fast.terms_into, issue 29):
the serial-chain path (one running composite sum from the tip) and the tree path (each
joint's subtree sums added to its parent's), against each other and against the numpy
reference (gpme_core.dynamics); and the compiled reduced solve, which forms only the lower
triangle of N^T M N, on both sides of kernels.LAPACK_FROM.  The free solve of a serial chain
(gpme_core.fast.chain_solve, which skips M) against the dense one: tests/test_chain_solve.py."""
import numpy as np
import pytest

from gpme_core import dynamics as dy
from gpme_core import compiled, fast, kernels
from gpme_core.gpme import ProgrammedMotion, _numpy_reduced_solve
from gpme_examples.crane import build_crane

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: numpy path only")

SERIAL, TREE = 1, 0          # terms_into's ``serial`` argument (-1: decide from parents)


def _terms(model, q, q_dot, serial):
    """(M, h, g) of the compiled terms on the given path."""
    n = model.n_coordinates
    t_all, s_all = fast.chain(model.origins, model.generators, model.is_revolute,
                              model.parents, q)
    m, h, g = np.empty((n, n)), np.empty(n), np.empty(n)
    fast.terms_into(t_all, s_all, model.pseudo_inertias, np.append(model.gravity, 0.0),
                    model.parents, model.moves, q_dot, m, h, g,
                    np.empty(fast.terms_scratch_size(n)), serial)
    return m, h, g


def _reference(model, q, q_dot):
    return (dy.mass_matrix(model, q), dy.velocity_product_terms(model, q, q_dot),
            dy.gravity_forces(model, q))


def _assert_round_off(values, reference, label):
    # round-off of sums over n links of 4x4 products: ~n eps scale (tests/test_fast.py)
    for name, a, b in zip("Mhg", values, reference):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * max(1.0, np.abs(b).max()),
                                   err_msg=f"{label}: {name}")


@pytest.mark.parametrize("n_rfe", [0, 3, 10])
def test_serial_path_equals_tree_path_and_reference_on_a_chain(n_rfe, arm, rng):
    """On a serial chain both paths add the same numbers in the same order (a running sum
    from the tip is the tree's child-into-parent sum; IEEE addition commutes), so they
    agree bit for bit; both agree with the numpy reference to round-off."""
    for model in (build_crane(n_rfe), arm):
        assert fast.is_serial(model.parents)
        n = model.n_coordinates
        q, q_dot = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
        serial = _terms(model, q, q_dot, SERIAL)
        tree = _terms(model, q, q_dot, TREE)
        for a, b in zip(serial, tree):
            np.testing.assert_array_equal(a, b)
        _assert_round_off(serial, _reference(model, q, q_dot), model.name)
        # the default decides from the parents: the serial path
        for a, b in zip(_terms(model, q, q_dot, -1), serial):
            np.testing.assert_array_equal(a, b)


def test_a_tree_takes_the_tree_path(tree, rng):
    """A tree is not serial; the default takes the tree path, which equals the reference,
    while the serial path's running sum would couple the branches (so a wrong dispatch
    would show here)."""
    assert not fast.is_serial(tree.parents)
    n = tree.n_coordinates
    q, q_dot = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
    reference = _reference(tree, q, q_dot)
    by_default = _terms(tree, q, q_dot, -1)
    for a, b in zip(by_default, _terms(tree, q, q_dot, TREE)):
        np.testing.assert_array_equal(a, b)
    _assert_round_off(by_default, reference, tree.name)
    wrong = _terms(tree, q, q_dot, SERIAL)
    assert np.abs(wrong[0] - reference[0]).max() > 1e-3 * np.abs(reference[0]).max()


def test_is_serial_reads_every_parent():
    assert fast.is_serial(np.array([-1, 0, 1, 2]))
    assert fast.is_serial(np.array([], dtype=np.int64))
    assert not fast.is_serial(np.array([-1, 0, 0, 2]))      # a branch at the end
    assert not fast.is_serial(np.array([0, 1]))             # first joint not on the world
    assert not fast.is_serial(np.array([-1, 0, 1, -1]))     # a second root


@pytest.mark.parametrize("model_name", ["arm", "tree"])
def test_compiled_evaluation_equals_reference_on_chain_and_tree(model_name, arm, tree, rng,
                                                                 monkeypatch):
    """kernels.evaluate (the fused right-hand side, whichever path its terms take; the arm's
    free solve is the recursion gpme_core.fast.chain_solve, the tree's the dense Cholesky)
    against the numpy reference of a free model: q_ddot to round-off in cond(M)."""
    model = {"arm": arm, "tree": tree}[model_name]
    system = ProgrammedMotion(model)
    n = model.n_coordinates
    q, q_dot = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
    cs, reason = compiled.for_system(system)
    assert cs is not None, reason
    status, q_ddot, _, _ = cs.evaluate(0.3, q, q_dot, system.ic, system.dc)
    assert status == kernels.OK
    monkeypatch.setattr(fast, "ENABLED", False)
    ref = system.solve(0.3, q, q_dot).q_ddot
    scale = 1e3 * np.finfo(float).eps * np.linalg.cond(dy.mass_matrix(model, q))
    np.testing.assert_allclose(q_ddot, ref, rtol=0, atol=scale * np.abs(ref).max())


@pytest.mark.parametrize("n", [9, kernels.LAPACK_FROM + 1, kernels.LAPACK_FROM + 12])
def test_reduced_solve_from_the_lower_triangle_equals_numpy(n, rng):
    """kernels.reduced_solve forms only the lower triangle of N^T M N (the Cholesky factor
    reads no other) and (M N) only on the dependent rows; with the dependent coordinates
    inside the range (not the last ones) it equals the numpy reference (LU of [N^T M; A])
    on both sides of LAPACK_FROM (the reduced size is n - 2)."""
    half = rng.normal(size=(n, n))
    m = half @ half.T + n * np.eye(n)
    rhs, a, c = rng.normal(size=n), rng.normal(size=(2, n)), rng.normal(size=2)
    dc = np.array([n // 3, n - 2])
    ic = np.setdiff1d(np.arange(n), dc)
    q_ddot, lam = np.zeros(n), np.zeros(2)
    ws = np.full(kernels.reduced_scratch_size(n, 2), np.nan)   # nothing unset may be read
    status, _ = kernels.reduced_solve(m, rhs, a, c, ic, dc, 0.0, 1e-14, q_ddot, lam, ws)
    assert status == kernels.OK
    ref_q_ddot, ref_lam, _, ok = _numpy_reduced_solve(m, rhs, a, c, ic, dc)
    assert ok
    # round-off of a solve: eps x the condition of the system both solve, [N^T M; A]
    gamma = -np.linalg.solve(a[:, dc], a[:, ic])
    basis = np.zeros((n, n - 2))
    basis[ic] = np.eye(n - 2)
    basis[dc] = gamma
    scale = 1e3 * np.finfo(float).eps * np.linalg.cond(np.vstack([basis.T @ m, a]))
    np.testing.assert_allclose(q_ddot, ref_q_ddot, rtol=0, atol=scale * np.abs(ref_q_ddot).max())
    np.testing.assert_allclose(lam, ref_lam, rtol=0, atol=scale * np.abs(ref_lam).max())
    np.testing.assert_allclose(a @ q_ddot, c, rtol=0, atol=scale * np.abs(c).max())

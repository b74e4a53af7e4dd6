"""The two code paths of the compiled trace-form terms (gpme_core.fast.terms_into, issue 29):
the serial-chain path (one running composite sum from the tip) and the tree path (each
joint's subtree sums added to its parent's), against each other and against the numpy
reference (gpme_core.dynamics); and the compiled reduced solve, which forms only the lower
triangle of N^T M N, on both sides of kernels.LAPACK_FROM.  The free solve of a serial chain
(gpme_core.fast.chain_solve, which skips M) against the dense one: tests/test_chain_solve.py."""
import sys

import numpy as np
import pytest

from gpme_core import dynamics as dy
from gpme_core import kinematics as kin
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


def test_leaf_kernels_without_reference_counting_release_what_they_are_given(rng):
    """chain_into, terms_into and chain_solve are compiled without numba's reference
    counting (gpme_core.fast._jit_leaf) and are given views carved by reference-counted
    callers (kernels.evaluate, rk4_advance): after many calls every array handed in holds
    as many references as before (a view whose reference is never released would keep
    its array, a run's workspace, alive for ever)."""
    model = build_crane(3)
    system = ProgrammedMotion(model)
    cs, reason = compiled.for_system(system)
    assert cs is not None, reason
    n = model.n_coordinates
    q, q_dot = rng.uniform(-0.5, 0.5, n), rng.uniform(-1, 1, n)
    q_ddot, lam, info = np.empty(n), np.empty(0), np.empty(kernels.INFO_SIZE)
    ws = np.empty(kernels.workspace_size(n, 0, cs.cd[0][1]))
    given = (q, q_dot, q_ddot, ws, *cs.md)
    before = [sys.getrefcount(a) for a in given]
    for _ in range(50):
        assert kernels.evaluate(0.0, q, q_dot, cs.md, cs.cd, cs.options(), system.ic,
                                system.dc, q_ddot, lam, info, ws) == kernels.OK
    y = np.concatenate([q, q_dot, np.zeros(kernels.N_WORK)])
    status, _, _ = kernels.rk4_advance(0.0, y, 1e-6, 20, cs.md, cs.cd, cs.options(),
                                       system.ic, system.dc, np.empty_like(y))
    assert status == kernels.OK
    assert [sys.getrefcount(a) for a in given] == before


@pytest.mark.parametrize("n_rfe", [0, 3])
def test_rk4_loop_equals_its_stages_from_derivative(n_rfe, rng):
    """kernels.rk4_advance writes each stage out (evaluate on views made once per call)
    instead of calling kernels.derivative: its steps equal classical RK4 formed from
    derivative, bit for bit, on the free crane (the recursive solve, massless links)."""
    system = ProgrammedMotion(build_crane(n_rfe))
    cs, reason = compiled.for_system(system)
    assert cs is not None, reason
    n = system.model.n_coordinates
    y0 = np.concatenate([rng.uniform(-0.3, 0.3, n), rng.uniform(-1, 1, n),
                         np.zeros(kernels.N_WORK)])
    dt, steps = 1e-4, 3
    y = y0.copy()
    status, done, _ = kernels.rk4_advance(0.0, y, dt, steps, cs.md, cs.cd, cs.options(),
                                          system.ic, system.dc, np.empty_like(y))
    assert (status, done) == (kernels.OK, steps)
    ws = np.empty(kernels.workspace_size(n, 0, cs.cd[0][1]))
    lam, info = np.empty(0), np.empty(kernels.INFO_SIZE)

    def slope(t, state):
        dy_ = np.empty_like(state)
        assert kernels.derivative(t, state, cs.md, cs.cd, cs.options(), system.ic, system.dc,
                                  dy_, lam, info, ws) == kernels.OK
        return dy_

    ref = y0.copy()
    for step in range(steps):
        t = 0.0 + step * dt
        k1 = slope(t, ref)
        k2 = slope(t + 0.5 * dt, ref + 0.5 * dt * k1)
        k3 = slope(t + 0.5 * dt, ref + 0.5 * dt * k2)
        k4 = slope(t + dt, ref + dt * k3)
        ref = ref + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    np.testing.assert_array_equal(y, ref)


def test_massless_links_and_plain_origins_take_their_short_paths_to_the_reference(rng):
    """The crane's RFEM links between its coincident joints are massless and their joints'
    origins have no rotation: terms_into leaves their exact-zero products out, chain_into
    the identity block of their origins.  With the free solve's settings (no M) h, g and
    the world pseudo-inertias equal those of the full path (M formed) bit for bit, and
    all equal the numpy reference to round-off."""
    model = build_crane(4)
    assert any(not model.pseudo_inertias[l].any() for l in range(model.n_coordinates))
    n = model.n_coordinates
    q, q_dot = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
    t_all, s_all = fast.chain(model.origins, model.generators, model.is_revolute,
                              model.parents, q)
    ref_t = kin.link_transforms(model, q)
    for name, a, b in (("T", t_all, ref_t), ("S", s_all, kin.joint_twists(model, ref_t))):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-14 * max(1.0, np.abs(b).max()),
                                   err_msg=name)
    out = {}
    for form_mass in (True, False):
        m, h, g = np.zeros((n, n)), np.empty(n), np.empty(n)
        scratch = np.empty(fast.terms_scratch_size(n))
        fast.terms_into(t_all, s_all, model.pseudo_inertias, np.append(model.gravity, 0.0),
                        model.parents, model.moves, q_dot, m, h, g, scratch, -1, form_mass)
        out[form_mass] = (h, g, fast.world_pseudo_inertias(scratch, n).copy(), m)
    for a, b in zip(out[True][:3], out[False][:3]):
        np.testing.assert_array_equal(a, b)
    assert not out[False][3].any()                 # M left unset (zeros as given)
    _assert_round_off((out[True][3], out[True][0], out[True][1]), _reference(model, q, q_dot),
                      model.name)

"""The O(n) free solve of a serial chain (gpme_core.fast.chain_solve, issue 29) against the
dense Cholesky of M that it replaces in gpme_core.kernels.evaluate (k == 0): the same solution to
round-off on random chains of revolute and prismatic joints and on the crane, the same
status where M is not positive definite, and the dispatch (a chain takes the recursion, a
tree or a constrained system the dense path).

Round-off bound (stated once, :func:`_round_off_operations`): on either path each entry of
M is formed from the same world pseudo-inertias and twists (gpme_core.fast) by at most
n + 36 rounded operations (a sum over at most n links of a 6 x 6 quadratic form u_i^T I u_j,
36 products), and solved with a backward error of at most about n eps ||M|| more (the
Cholesky factor's entries are sums of at most n products; the recursion's rank-one updates
run over at most n joints).  Each solution is therefore a backward-stable solve with
||delta M|| <= (2 n + 36) eps ||M||, its forward error at most cond(M) times that, and the
two differ by at most twice:

    ||x_recursive - x_dense||_2 <= 2 (2 n + 36) eps cond_2(M) ||x||_2,
    ||M x_recursive - b||_2     <= 2 (2 n + 36) eps ||M||_2 ||x_recursive||_2.

(Measured on these chains: at most ~12 and ~14 eps cond(M) resp. eps ||M|| ||x||, at
n = 1, where the formation dominates.)  The residual bound does not grow with cond(M), so it
catches a planted 1e-3 fault in the recursion even on the crane at n_rfe = 50 (cond(M)
~ 6e8, where the forward bound allows ~1e-4).
"""
import numpy as np
import pytest

from gpme_core import compiled, fast, kernels
from gpme_core import transforms as tf
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder
from gpme_core.time_functions import Sine
from gpme_examples.crane import build_crane

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: numpy path only")

EPS = np.finfo(float).eps
REVOLUTE_SHARE = 0.6          # of the random chains' joints
LAPACK_SIDE = kernels.LAPACK_FROM + 6     # a size on LAPACK's side of the dense solve


def _round_off_operations(n):
    """Rounded operations per entry of M behind one solve (module docstring): n + 36 to
    form it, about n more to solve."""
    return 2 * n + 36


def _random_rotation(rng):
    return (tf.rot_z(rng.uniform(-np.pi, np.pi)) @ tf.rot_y(rng.uniform(-np.pi, np.pi))
            @ tf.rot_x(rng.uniform(-np.pi, np.pi)))


def random_chain(n, rng, massless_tip=False):
    """A serial chain of n joints, revolute (REVOLUTE_SHARE) or prismatic, on random unit
    axes, random joint frames (offsets up to 0.4 m, any rotation), each link a box of 0.1 to
    5 kg, 5 to 50 cm sides, its centre up to 0.2 m off the link origin; springs, dampers on
    some joints.  massless_tip: no body on the last link (not a valid model: see
    :func:`_packed_without_tip_mass`)."""
    b = ChainBuilder(f"random_chain_{n}")
    for k in range(n):
        axis = rng.normal(size=3)
        kind = REVOLUTE if rng.random() < REVOLUTE_SHARE else PRISMATIC
        origin = tf.translation(*rng.uniform(-0.4, 0.4, 3)) @ _random_rotation(rng)
        b.add_joint(f"q{k}", kind, axis / np.linalg.norm(axis), origin=origin,
                    stiffness=rng.choice([0.0, 30.0]), damping=rng.choice([0.0, 0.4]))
        b.add_body(cuboid(rng.uniform(0.1, 5.0), rng.uniform(0.05, 0.5, 3),
                          com=rng.uniform(-0.2, 0.2, 3)))
    return b.build()


def _solve_both(model, q, b):
    """(x_recursive, x_dense, M) for M q_ddot = b at q: fast.chain_solve on the world
    pseudo-inertias terms_into leaves, and kernels' dense Cholesky of the M it forms."""
    n = model.n_coordinates
    t_all, s_all = fast.chain(model.origins, model.generators, model.is_revolute,
                              model.parents, q)
    m, h, g = np.empty((n, n)), np.empty(n), np.empty(n)
    scratch = np.empty(fast.terms_scratch_size(n))
    fast.terms_into(t_all, s_all, model.pseudo_inertias, np.append(model.gravity, 0.0),
                    model.parents, model.moves, np.zeros(n), m, h, g, scratch)
    x_rec, x_dense = np.full(n, np.nan), np.full(n, np.nan)
    scratch_solve = np.full(fast.chain_solve_scratch_size(n), np.nan)   # nothing unset is read
    assert fast.chain_solve(s_all, fast.world_pseudo_inertias(scratch, n), b, x_rec,
                            scratch_solve)
    assert kernels._cholesky_solve(m, b, np.empty((n, n)), x_dense)
    return x_rec, x_dense, m


def _assert_same_solution(x_rec, x_dense, m, b, label):
    bound = 2 * _round_off_operations(m.shape[0]) * EPS
    forward = np.linalg.norm(x_rec - x_dense) / np.linalg.norm(x_dense)
    assert forward <= bound * np.linalg.cond(m), f"{label}: forward error {forward:.3g}"
    residual = np.linalg.norm(m @ x_rec - b) / (np.linalg.norm(m, 2) * np.linalg.norm(x_rec))
    assert residual <= bound, f"{label}: residual {residual:.3g}"


@pytest.mark.parametrize("n", [1, 2, 7, kernels.LAPACK_FROM + 1, 60])
def test_recursive_solve_equals_dense_cholesky_on_random_chains(n, rng):
    for trial in range(4):
        model = random_chain(n, rng)
        q = rng.uniform(-np.pi, np.pi, n)
        b = rng.normal(size=n) * 10.0                                 # N or N m
        x_rec, x_dense, m = _solve_both(model, q, b)
        _assert_same_solution(x_rec, x_dense, m, b, f"chain {n}, trial {trial}")


@pytest.mark.parametrize("n_rfe", [0, 5, 50])
def test_recursive_solve_equals_dense_cholesky_on_the_crane(n_rfe, rng):
    model = build_crane(n_rfe)
    n = model.n_coordinates
    q = rng.uniform(-0.5, 0.5, n)
    b = rng.normal(size=n) * 100.0
    x_rec, x_dense, m = _solve_both(model, q, b)
    _assert_same_solution(x_rec, x_dense, m, b, f"crane n_rfe={n_rfe}")


def _evaluate(system, q, q_dot, dense=False, md=None, t=0.3):
    """(status, q_ddot) of kernels.evaluate on the default path, or with the dense free
    solve forced (opts[OPT_DENSE_FREE_SOLVE] = 1); md replaces the packed model data."""
    form, reason = compiled.for_system(system)
    assert form is not None, reason
    opts = form.options()
    assert opts.shape[0] == kernels.OPT_DENSE_FREE_SOLVE     # compiled gives no switch
    if dense:
        opts = np.append(opts, 1.0)
    n = system.model.n_coordinates
    q_ddot = np.full(n, np.nan)
    status = kernels.evaluate(t, q, q_dot, form.md if md is None else md, form.cd, opts,
                              system.ic, system.dc, q_ddot, np.empty(system.n_constraints),
                              np.empty(kernels.INFO_SIZE), form.workspace())
    return status, q_ddot


def _bound_of_evaluation(model, q):
    m = fast.chain_and_terms(model.origins, model.generators, model.is_revolute,
                             model.pseudo_inertias, np.append(model.gravity, 0.0),
                             model.parents, model.moves, q, np.zeros(model.n_coordinates))[2]
    return 2 * _round_off_operations(m.shape[0]) * EPS * np.linalg.cond(m)


@pytest.mark.parametrize("n_rfe", [0, 5, 50])
def test_free_crane_evaluation_takes_the_recursion_and_agrees_with_the_dense_path(n_rfe, rng):
    """kernels.evaluate on the free crane (springs, dampers and the drive in its right-hand
    side): the default path is the recursion (free_solve_is_recursive), the forced one the
    dense Cholesky; their q_ddot agree to the round-off bound.  At n_rfe = 50 (154
    coordinates) two different algorithms cannot agree bit for bit; identical results
    there would mean the default took the dense path too."""
    model = build_crane(n_rfe)
    system = ProgrammedMotion(model)
    n = model.n_coordinates
    q, q_dot = rng.uniform(-0.5, 0.5, n), rng.uniform(-1.0, 1.0, n)
    form, _ = compiled.for_system(system)
    assert kernels.free_solve_is_recursive(0, form.md[3], form.options())
    status, q_ddot = _evaluate(system, q, q_dot)
    status_dense, q_ddot_dense = _evaluate(system, q, q_dot, dense=True)
    assert status == status_dense == kernels.OK
    difference = np.linalg.norm(q_ddot - q_ddot_dense) / np.linalg.norm(q_ddot_dense)
    assert difference <= _bound_of_evaluation(model, q)
    if n_rfe == 50:
        assert difference > 0.0


def _arm_with_every_force():
    """A chain with a prismatic joint, joint springs and dampers, a drive and a point
    spring (all in the right-hand side, which the solve does not touch)."""
    b = ChainBuilder("arm_with_every_force")
    b.add_joint("q0", REVOLUTE, (0, 0, 1), stiffness=3.0, spring_reference=0.2, damping=0.1)
    b.add_body(cuboid(2.0, (0.2, 0.3, 0.4), com=(0.05, -0.02, 0.1)))
    b.add_joint("q1", PRISMATIC, np.array([1, 1, 0]) / np.sqrt(2),
                origin=tf.translation(0.1, 0, 0.3), stiffness=20.0, damping=0.3)
    b.add_body(cuboid(1.0, (0.1, 0.5, 0.2), com=(0.0, 0.1, 0.0)))
    b.add_joint("q2", REVOLUTE, np.array([0, 1, 1]) / np.sqrt(2),
                origin=tf.translation(0, 0.2, 0.1) @ tf.rot_x(0.3), damping=0.05)
    b.add_body(cuboid(0.7, (0.6, 0.1, 0.1), com=(0.3, 0.0, 0.02)))
    b.add_frame("tip", tf.translation(0.6, 0.0, 0.0))
    b.add_drive("q2", Sine(0.4, 2.0, 0.7, 0.2))
    b.add_point_spring("hold", "tip", (0.5, 0.5, 0.8), stiffness=80.0, free_length=0.3,
                       damping=1.5)
    return b.build()


def test_every_force_reaches_the_recursive_solve_through_the_right_hand_side(rng,
                                                                             monkeypatch):
    """Springs, dampers, a drive and a point spring on a chain with a prismatic joint: the
    recursion's q_ddot equals the dense path's and the numpy reference's
    (ProgrammedMotion.solve, LU of the reference M) to the round-off bound."""
    model = _arm_with_every_force()
    system = ProgrammedMotion(model)
    n = model.n_coordinates
    q, q_dot = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
    status, q_ddot = _evaluate(system, q, q_dot, t=0.37)
    status_dense, q_ddot_dense = _evaluate(system, q, q_dot, dense=True, t=0.37)
    assert status == status_dense == kernels.OK
    bound = _bound_of_evaluation(model, q) * np.linalg.norm(q_ddot_dense)
    assert np.linalg.norm(q_ddot - q_ddot_dense) <= bound
    monkeypatch.setattr(fast, "ENABLED", False)
    reference = system.solve(0.37, q, q_dot).q_ddot
    assert np.linalg.norm(q_ddot - reference) <= bound


def test_a_tree_and_a_constrained_chain_keep_the_dense_path(tree, arm, rng):
    """A tree is solved densely whatever the option says (its default and forced-dense
    results are the same bits); so is any system with constraints (k > 0)."""
    form, _ = compiled.for_system(ProgrammedMotion(tree))
    opts = form.options()
    arm_parents = np.asarray(arm.parents, dtype=np.int64)
    assert not kernels.free_solve_is_recursive(0, form.md[3], opts)
    assert not kernels.free_solve_is_recursive(1, arm_parents, opts)
    assert not kernels.free_solve_is_recursive(0, arm_parents, np.append(opts, 1.0))
    assert kernels.free_solve_is_recursive(0, arm_parents, np.append(opts, 0.0))
    system = ProgrammedMotion(tree)
    n = tree.n_coordinates
    q, q_dot = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
    status, q_ddot = _evaluate(system, q, q_dot)
    status_dense, q_ddot_dense = _evaluate(system, q, q_dot, dense=True)
    assert status == status_dense == kernels.OK
    np.testing.assert_array_equal(q_ddot, q_ddot_dense)


def _packed_without_tip_mass(form):
    """The packed model data with the last link's pseudo-inertia set to zero: its joint
    moves nothing, so M has a zero last row and column (ChainBuilder refuses such a model;
    the kernels must still report it)."""
    mats, vecs, gamma, parents, moves = form.md
    mats = mats.copy()
    mats[2, -1] = 0.0                 # mats[2]: the pseudo-inertias (kernels.model_parts)
    return mats, vecs, gamma, parents, moves


@pytest.mark.parametrize("n", [1, 2, LAPACK_SIDE])
def test_a_joint_that_moves_no_mass_is_singular_on_both_paths(n, rng):
    """M is positive semi-definite with a zero pivot: the recursion stops at D = 0 with
    SINGULAR_REDUCED, as the dense Cholesky does (on both sides of LAPACK_FROM), instead of
    dividing by it into NaN."""
    model = random_chain(n, rng)
    system = ProgrammedMotion(model)
    form, _ = compiled.for_system(system)
    md = _packed_without_tip_mass(form)
    q, q_dot = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
    for dense in (False, True):
        status, _ = _evaluate(system, q, q_dot, dense=dense, md=md)
        assert status == kernels.SINGULAR_REDUCED, f"dense={dense}"
    # and the kernel itself: False, q_ddot left as it was
    t_all, s_all = fast.chain(model.origins, model.generators, model.is_revolute,
                              model.parents, q)
    hw = np.einsum("lij,ljk,lmk->lim", t_all, md[0][2], t_all)
    x = np.full(n, 7.0)
    assert not fast.chain_solve(s_all, hw, rng.normal(size=n), x,
                                np.empty(fast.chain_solve_scratch_size(n)))
    np.testing.assert_array_equal(x, 7.0)


def test_spatial_inertia_reproduces_the_trace_form(rng):
    """The map of the module docstring, entry by entry: for any two twists u, u' and a
    pseudo-inertia J, u^T I(J) u' = tr(S J S'^T) with S = [[skew(omega), v], [0, 0]]
    (the quadratic form the mass matrix is made of)."""
    model = random_chain(3, rng)
    pose = _random_rotation(rng) @ tf.translation(0.3, -0.2, 0.5)     # a link's T_0_l
    hw = np.einsum("ij,ljk,mk->lim", pose, model.pseudo_inertias, pose)   # T H T^T
    hw = 0.5 * (hw + hw.transpose(0, 2, 1))       # exactly symmetric, as terms_into's
    inertia = np.zeros((6, 6))
    fast.add_spatial_inertia(hw, 1, inertia)
    np.testing.assert_array_equal(inertia, inertia.T)
    for _ in range(5):
        u, v = rng.normal(size=6), rng.normal(size=6)
        trace = np.trace(_twist_matrix(u) @ hw[1] @ _twist_matrix(v).T)
        # two evaluations of one bilinear form of O(1) numbers: ~ 50 eps relative
        assert u @ inertia @ v == pytest.approx(trace, rel=1e-13, abs=1e-13)


def _twist_matrix(u):
    """(4, 4) [[skew(omega), v], [0, 0]] of a unit twist u = (omega, v)."""
    wx, wy, wz, vx, vy, vz = u
    return np.array([[0.0, -wz, wy, vx], [wz, 0.0, -wx, vy], [-wy, wx, 0.0, vz],
                     [0.0, 0.0, 0.0, 0.0]])

"""Compiled (numba) kernels of the chain kinematics, the trace-form dynamics terms and the
O(n) free solve of a serial chain.

The same formulas as gpme_core.kinematics and gpme_core.dynamics (which stay the readable
numpy reference; tests/test_fast.py checks both agree to round-off), written as loops over
4x4 matrices so that one evaluation costs microseconds instead of the ~100 us of numpy call
overhead.  Set the environment variable GPME_NO_JIT=1 to use the numpy reference instead.

Shapes: n coordinates; origins, generators, pseudo_inertias (n, 4, 4); q, q_dot (n,);
gamma (4,) = (gravity, 0); parents (n,) int64, the parent link of each joint (-1 the
world, < the joint's index); moves (n, n) bool, moves[i, l] when joint i moves link l
(model.parents, model.moves: a kinematic tree, a serial chain when parents[k] = k - 1).

Free solve of a serial chain (:func:`chain_solve`, issue 29)
============================================================
gpme_core.kernels.evaluate solves M q_ddot = b for a model without programmed constraints
(k == 0) whose joints form one serial chain (:func:`is_serial`) by the articulated-body
recursion below, in O(n) and without forming M; trees and constrained systems keep the dense
paths.  The right-hand side b = h + Q (velocity products, gravity, springs, dampers, drives,
point springs) is formed by the caller as before: only M^-1 b is replaced.

From the trace form to spatial inertias
---------------------------------------
Frames and units: everything here is in the world frame 0, SI (m, kg, s, rad).
A link's world pseudo-inertia (:func:`terms_into`'s ``hw``; docs/conventions.md)

    J = T H T^T = int r r^T dm  (4, 4),  r = (x, 1) the homogeneous world position,
    J[:3, :3] = Sigma = int x x^T dm (kg m^2, second moments about the world origin),
    J[:3, 3] = m c (kg m, c the centre of mass), J[3, 3] = m (kg).

Joint i's world twist matrix S_i = T^(i) Q_i T^(i)^-1 (4, 4) = [[W_i, v_i], [0, 0]] has
W_i = skew(omega_i); its unit twist is

    u_i = (omega_i, v_i) (6,):  omega_i (3,) rad/s per unit q_dot_i, the joint's world axis
          for a revolute joint, 0 for a prismatic one; v_i (3,) m/s per unit q_dot_i, the
          velocity of the body-fixed point at the world origin (the axis for a prismatic
          joint).  omega_i = (S_i[2, 1], S_i[0, 2], S_i[1, 0]), v_i = S_i[:3, 3].

S_i r = (omega_i x x + v_i, 0) is the velocity of the material point at x per unit q_dot_i,
so for i <= j on a chain (joint i moves every link joint j moves)

    m_ij = tr(S_i Hc_j S_j^T) = sum over links l >= j of int (S_i r)^T (S_j r) dm
         = sum_l int (omega_i x x + v_i) . (omega_j x x + v_j) dm
         = u_i^T Ic_j u_j,      Ic_j = sum_{l >= j} I_l,

with, per link (a^T skew(x)^T skew(x) b = (a x x).(b x x), (a x x).v = a^T skew(x) v):

    I_l = [[tr(Sigma) E - Sigma, skew(m c)],      (6, 6) spatial inertia about the world
           [skew(m c)^T,         m E      ]]      origin, ordered (omega, v): kg m^2 | kg m
                                                                               kg m   | kg

(E the 3 x 3 identity; tr(Sigma) E - Sigma = int (|x|^2 E - x x^T) dm is the inertia tensor
about the world origin).  The map J -> I is linear, so Ic_j is the image of the composite
pseudo-inertia Hc_j that terms_into accumulates.  Hence M_ij = u_i^T Ic_max(i,j) u_j: M is
semiseparable of rank 6, the mass matrix of a chain in the composite-rigid-body form.

The recursion (Featherstone, Rigid Body Dynamics Algorithms, 2008, ch. 7; here without
velocity terms and without frame changes: every quantity is about the world origin)
---------------------------------------------------------------------------------------
Backward, i = n-1 .. 0, from I^A = 0, p^A = 0 (6,):

    I^A += I_i                       articulated inertia of links i.. with joints > i free
    U_i = I^A u_i,  D_i = u_i^T U_i   (D_i must be > 0)
    w_i = b_i - u_i^T p^A
    I^A -= U_i U_i^T / D_i           what links i.. oppose to a motion of link i - 1
    p^A += U_i w_i / D_i             the force they transmit to it

Forward, i = 0 .. n-1, from a = 0 (6,): the spatial acceleration of the link before joint
i, its velocity-product part left out (it is in b):

    q_ddot_i = (w_i - U_i^T a) / D_i,   a += u_i q_ddot_i

This solves M q_ddot = b with M the matrix above (the articulated-body algorithm with zero
velocity and gravity computes M^-1 tau).  It is Gaussian elimination of M from its last row
upwards (M = L^T D L, L unit lower triangular): D_i is the Schur complement of the trailing
block of M, so all D_i > 0 exactly when M is positive definite (Sylvester's criterion on
the trailing principal minors).  A D_i that is not > 0 (or NaN) returns False, the status
the dense Cholesky gives for the same matrix (gpme_core.kernels.SINGULAR_REDUCED), before
anything is divided by it.

Why this and not a semiseparable Cholesky from the generators (u_i, Ic_j): both are
O(36 n); the recursion needs only the per-link inertias (no composite sums, no generator
matrices of the factor), its pivots are the positive-definiteness test, and it is the
textbook algorithm a reader can check line by line.  Cost per joint: about 150 flops
(U = I^A u: 36 multiply-adds, the rank-one update: 36, adding I_i: 15), against the
n^3 / 3 of the dense factor and the 6 n^2 of forming M, which this path skips.

Round-off: this path and the dense one build M's entries (implicitly here, explicitly
there) from the same world pseudo-inertias and twists in at most about n + 36 rounded
operations (a sum over <= n links of a 6 x 6 quadratic form), and solve with a backward
error of about n eps ||M|| more; so the residual is <~ (2 n + 36) eps ||M|| ||q_ddot|| and
the two solutions differ by <~ 2 (2 n + 36) eps cond(M) relative (the bounds
tests/test_chain_solve.py checks).  Both work about the world origin: a chain far from it
loses the same digits on either path (the pseudo-inertias hw carry its lever arms).
"""
import os

import numpy as np

ENABLED = os.environ.get("GPME_NO_JIT", "") not in ("1", "true", "yes")

try:
    import numba  # noqa: F401 (is numba there: else the reference path)
except ImportError:  # pragma: no cover - numba is a dependency; keep the reference path
    ENABLED = False

if ENABLED:
    # numba.njit with a disk cache that a change in any gpme_core source the kernels are
    # built from invalidates, not only one in their own file (gpme_core.jit_cache)
    from .jit_cache import kernel_jit
    _jit = kernel_jit(fastmath=False)
    # the per-evaluation kernels that allocate nothing, return no array and call only
    # kernels of their own kind (chain_into, terms_into, chain_solve and their helpers):
    # compiled without numba's reference counting (its NRT), so that the views they carve
    # from the caller's arrays cost no atomic increment and decrement each (measured:
    # 0.3 of 2.9 us per free evaluation of the crane at n_rfe = 5, issue 29).  They must
    # not call a function that returns an array (its reference would never be released)
    _jit_leaf = kernel_jit(fastmath=False, _nrt=False)
    # generated code of the user's expressions (gpme_core.compiled): a division by zero
    # gives inf or nan as in numpy, for the caller's finiteness check to report, instead
    # of raising ZeroDivisionError out of the compiled loop
    _jit_user = kernel_jit(fastmath=False, error_model="numpy")
else:  # pragma: no cover
    def _jit(f):
        return f
    _jit_user = _jit_leaf = _jit


def state_array(x) -> np.ndarray:
    """``x`` as a writeable C-contiguous float64 array (copied only when it is not one).

    numba types a read-only array apart from a writeable one, so a kernel called once with
    a read-only state (a scenario's frozen q0, a pandas column) and once with a writeable
    one is compiled twice, and every kernel it calls with it (measured: evaluate, chain_
    and_terms and point each compiled a second time, ~15 s of a cold start).  The state
    vectors handed to the kernels go through here, so each signature is compiled once."""
    a = np.ascontiguousarray(x, dtype=float)
    return a if a.flags.writeable else a.copy()


def run(kernel, *args):
    """``kernel(*args)``, giving back an interrupt that arrived while it ran.

    A signal handler that raises (Ctrl-C's KeyboardInterrupt; gpme's SIGTERM handler raises
    a subclass of it) while a compiled kernel returns makes the call fail with SystemError
    ("... returned a result with an exception set") chained to the interrupt; an
    ``except Exception`` on the way up would then take the interrupt for a failure.
    """
    try:
        return kernel(*args)
    except SystemError as exc:
        interrupt = _interrupt_in_chain(exc)
        if interrupt is not None:
            raise interrupt from None
        raise


def _interrupt_in_chain(exc, depth=32):
    """The KeyboardInterrupt behind ``exc`` (through __cause__ / __context__, several
    SystemErrors deep when numba was unpickling a kernel), or None."""
    seen = set()
    todo = [exc]
    while todo and len(seen) < depth:
        e = todo.pop()
        if e is None or id(e) in seen:
            continue
        seen.add(id(e))
        if isinstance(e, KeyboardInterrupt):
            return e
        todo += [e.__cause__, e.__context__]
    return None


@_jit
def chain(origins, generators, is_revolute, parents, q):
    """(T, S): world transforms T^(l) and world twist matrices S_l = T^(l) Q_l T^(l)^-1."""
    n = q.shape[0]
    t_all = np.empty((n, 4, 4))
    s_all = np.empty((n, 4, 4))
    chain_into(origins, generators, is_revolute, parents, q, t_all, s_all, np.empty((2, 4, 4)))
    return t_all, s_all


@_jit_leaf
def chain_into(origins, generators, is_revolute, parents, q, t_all, s_all, scratch):
    """:func:`chain` into t_all, s_all (n, 4, 4); scratch (2, 4, 4) work space.

    Every transform is homogeneous (last row 0, 0, 0, 1): only the rotation (3 x 3) and
    the translation are multiplied, in the order of a full 4 x 4 product (the terms left
    out are exact zeros, so the results are those of the full products).  Arrays are
    indexed in full rather than through per-link views (a view costs a reference count)."""
    n = q.shape[0]
    motion = scratch[0]
    local = scratch[1]
    for k in range(n):
        for i in range(3):
            for j in range(4):
                motion[i, j] = 1.0 if i == j else 0.0
                s_all[k, i, j] = 0.0
        for j in range(4):
            s_all[k, 3, j] = 0.0
        if is_revolute[k]:
            # Rodrigues: R = I + sin K + (1 - cos) K^2, K = skew(axis); K^2 = a a^T - |a|^2 E
            # written out from K's entries (K's zero diagonal drops the other products of
            # K K exactly)
            s, c = np.sin(q[k]), np.cos(q[k])
            ax, ay, az = generators[k, 2, 1], generators[k, 0, 2], generators[k, 1, 0]
            kk00, kk11, kk22 = -(az * az) - ay * ay, -(az * az) - ax * ax, -(ay * ay) - ax * ax
            kk01, kk02, kk12 = ay * ax, az * ax, az * ay
            one_c = 1.0 - c
            motion[0, 0] += s * generators[k, 0, 0] + one_c * kk00
            motion[0, 1] += s * generators[k, 0, 1] + one_c * kk01
            motion[0, 2] += s * generators[k, 0, 2] + one_c * kk02
            motion[1, 0] += s * generators[k, 1, 0] + one_c * kk01
            motion[1, 1] += s * generators[k, 1, 1] + one_c * kk11
            motion[1, 2] += s * generators[k, 1, 2] + one_c * kk12
            motion[2, 0] += s * generators[k, 2, 0] + one_c * kk02
            motion[2, 1] += s * generators[k, 2, 1] + one_c * kk12
            motion[2, 2] += s * generators[k, 2, 2] + one_c * kk22
        else:
            for i in range(3):
                motion[i, 3] = generators[k, i, 3] * q[k]
        # local = origin @ motion; an origin without rotation (the RFEM's coincident
        # joints, most links of a chain) only shifts the translation: the products with its
        # identity block are exact and left out
        if _rotation_is_identity(origins, k):
            for i in range(3):
                for j in range(3):
                    local[i, j] = motion[i, j]
                local[i, 3] = motion[i, 3] + origins[k, i, 3]
        else:
            for i in range(3):
                for j in range(3):
                    local[i, j] = origins[k, i, 0] * motion[0, j] \
                        + origins[k, i, 1] * motion[1, j] + origins[k, i, 2] * motion[2, j]
                local[i, 3] = origins[k, i, 0] * motion[0, 3] + origins[k, i, 1] * motion[1, 3] \
                    + origins[k, i, 2] * motion[2, 3] + origins[k, i, 3]
        p = parents[k]
        if p < 0:
            for i in range(3):
                for j in range(4):
                    t_all[k, i, j] = local[i, j]
        else:
            for i in range(3):
                for j in range(3):
                    t_all[k, i, j] = t_all[p, i, 0] * local[0, j] + t_all[p, i, 1] * local[1, j] \
                        + t_all[p, i, 2] * local[2, j]
            if local[0, 3] == 0.0 and local[1, 3] == 0.0 and local[2, 3] == 0.0:
                # a joint at its parent's origin: the translation is the parent's (exact)
                for i in range(3):
                    t_all[k, i, 3] = t_all[p, i, 3]
            else:
                for i in range(3):
                    t_all[k, i, 3] = t_all[p, i, 0] * local[0, 3] \
                        + t_all[p, i, 1] * local[1, 3] + t_all[p, i, 2] * local[2, 3] \
                        + t_all[p, i, 3]
        t_all[k, 3, 0], t_all[k, 3, 1], t_all[k, 3, 2], t_all[k, 3, 3] = 0.0, 0.0, 0.0, 1.0
        if is_revolute[k]:
            # S = [[W, -W p], [0, 0]],  W = R K R^T = skew(R k): the axis k = (K[2, 1],
            # K[0, 2], K[1, 0]) turned into the world frame
            ax, ay, az = generators[k, 2, 1], generators[k, 0, 2], generators[k, 1, 0]
            wx = t_all[k, 0, 0] * ax + t_all[k, 0, 1] * ay + t_all[k, 0, 2] * az
            wy = t_all[k, 1, 0] * ax + t_all[k, 1, 1] * ay + t_all[k, 1, 2] * az
            wz = t_all[k, 2, 0] * ax + t_all[k, 2, 1] * ay + t_all[k, 2, 2] * az
            s_all[k, 0, 1], s_all[k, 0, 2] = -wz, wy
            s_all[k, 1, 0], s_all[k, 1, 2] = wz, -wx
            s_all[k, 2, 0], s_all[k, 2, 1] = -wy, wx
            for i in range(3):
                s_all[k, i, 3] = -(s_all[k, i, 0] * t_all[k, 0, 3]
                                   + s_all[k, i, 1] * t_all[k, 1, 3]
                                   + s_all[k, i, 2] * t_all[k, 2, 3])
        else:
            for i in range(3):
                s_all[k, i, 3] = t_all[k, i, 0] * generators[k, 0, 3] \
                    + t_all[k, i, 1] * generators[k, 1, 3] + t_all[k, i, 2] * generators[k, 2, 3]


@_jit_leaf
def _rotation_is_identity(transforms, k):
    """True when transforms[k] (4, 4) has the rotation block E exactly (a translation only)."""
    return (transforms[k, 0, 0] == 1.0 and transforms[k, 1, 1] == 1.0
            and transforms[k, 2, 2] == 1.0 and transforms[k, 0, 1] == 0.0
            and transforms[k, 0, 2] == 0.0 and transforms[k, 1, 0] == 0.0
            and transforms[k, 1, 2] == 0.0 and transforms[k, 2, 0] == 0.0
            and transforms[k, 2, 1] == 0.0)


@_jit
def terms(t_all, s_all, pseudo_inertias, gamma, parents, moves, q_dot):
    """(M (n, n), h (n,), g (n,)) in trace form with composite world pseudo-inertias."""
    n = q_dot.shape[0]
    m = np.empty((n, n))
    h = np.empty(n)
    g = np.empty(n)
    terms_into(t_all, s_all, pseudo_inertias, gamma, parents, moves, q_dot, m, h, g,
               np.empty(terms_scratch_size(n)))
    return m, h, g


@_jit
def terms_scratch_size(n):
    """Length of the float scratch of :func:`terms_into` for n coordinates."""
    return 16 * N_TERMS_BLOCKS * n + 16 * N_TERMS_SMALL + 6 * n + n + n


N_TERMS_BLOCKS = 6      # (n, 4, 4) arrays of terms_into's scratch: hw, B, V, Hc, Gc, wc
N_TERMS_SMALL = 3       # its (4, 4) work matrices


@_jit_leaf
def is_serial(parents):
    """True when the joints form one serial chain (parents[k] = k - 1 for every k)."""
    for k in range(parents.shape[0]):
        if parents[k] != k - 1:
            return False
    return True


@_jit
def world_pseudo_inertias(scratch, n):
    """The links' world pseudo-inertias hw (n, 4, 4) = T^(l) H_l T^(l)^T (kg m^2 | kg m |
    kg, about the world origin) that :func:`terms_into` leaves at the head of its scratch:
    a view, valid after terms_into and until the scratch is used again
    (:func:`chain_solve` reads them)."""
    return scratch[:16 * n].reshape((n, 4, 4))


@_jit_leaf
def terms_into(t_all, s_all, pseudo_inertias, gamma, parents, moves, q_dot, m, h, g,
               scratch, serial=-1, form_mass=True):
    """:func:`terms` into m (n, n), h (n,), g (n,); scratch (terms_scratch_size(n),).
    ``form_mass`` False leaves m unset (a caller that solves without M:
    :func:`chain_solve`); h, g and the world pseudo-inertias are formed either way.

    Per link l: hw_l = T H T^T (world pseudo-inertia); per joint j, over the links it moves
    (gpme_core.dynamics): Hc_j (composite pseudo-inertia), Gc_j (sum of B_l hw_l), wc_j
    (first moments: the last columns of T H), accumulated from the leaves to the root.  A
    serial chain (``serial`` 1, or -1 and :func:`is_serial`) keeps one running sum from the
    tip (index 0 of hc, gc, wc); a tree (``serial`` 0) keeps each joint's sum and adds it
    to its parent's.  Arrays are indexed in full rather than through per-link views (a
    view costs a reference count).

    Structure used (every product left out is an exact zero, so the results are those of
    the full 4 x 4 products, bit for bit for finite values): a massless link (H = 0, the
    RFEM's links between its coincident joints) has hw = 0 and adds nothing to Hc, Gc, wc;
    S_j's rotation block has a zero diagonal, so the trace tr(S_j Gc_j^T) and S_j wc_j
    skip it and Gc's diagonal is not formed; without M (``form_mass`` False) a chain's Hc
    is not accumulated."""
    n = q_dot.shape[0]
    if serial < 0:
        serial = 1 if is_serial(parents) else 0
    # the (4, 4) blocks are carved from one reshaped view (a reshape costs a call, a slice
    # of the first axis does not); hw first: world_pseudo_inertias reads it there
    n_blocks = N_TERMS_BLOCKS * n + N_TERMS_SMALL
    blocks = scratch[:16 * n_blocks].reshape((n_blocks, 4, 4))
    hw = blocks[:n]
    b_all = blocks[n:2 * n]
    v_all = blocks[2 * n:3 * n]
    hc = blocks[3 * n:4 * n]
    gc = blocks[4 * n:5 * n]
    wc = blocks[5 * n:6 * n]                  # wc_j in row 0 of block j (a chain: block 0)
    th, tmp = blocks[6 * n], blocks[6 * n + 1]
    used = 16 * n_blocks
    s6 = scratch[used:used + 6 * n].reshape((6, n))
    column = scratch[used + 6 * n:used + 7 * n]
    massive = scratch[used + 7 * n:used + 8 * n]   # 1.0 a link with mass, 0.0 a massless one
    for l in range(n):
        if _is_zero_4x4(pseudo_inertias, l):
            # a massless link (the RFEM's links between coincident joints): hw = 0, and
            # every product with it below is an exact zero, left out
            massive[l] = 0.0
            for i in range(4):
                for j in range(4):
                    hw[l, i, j] = 0.0
            continue
        massive[l] = 1.0
        # T H (its last row is H's: T's last row is (0, 0, 0, 1))
        for i in range(3):
            for j in range(4):
                th[i, j] = t_all[l, i, 0] * pseudo_inertias[l, 0, j] \
                    + t_all[l, i, 1] * pseudo_inertias[l, 1, j] \
                    + t_all[l, i, 2] * pseudo_inertias[l, 2, j] \
                    + t_all[l, i, 3] * pseudo_inertias[l, 3, j]
        # T H T^T is symmetric: the upper triangle, mirrored; its last column is T H's
        for i in range(3):
            for j in range(i, 3):
                v = th[i, 0] * t_all[l, j, 0] + th[i, 1] * t_all[l, j, 1] \
                    + th[i, 2] * t_all[l, j, 2] + th[i, 3] * t_all[l, j, 3]
                hw[l, i, j] = v
                hw[l, j, i] = v
            hw[l, i, 3] = th[i, 3]
            hw[l, 3, i] = th[i, 3]
        hw[l, 3, 3] = pseudo_inertias[l, 3, 3]
    if serial:
        for a in range(4):
            wc[0, 0, a] = 0.0
            for c in range(4):
                hc[0, a, c] = 0.0
                gc[0, a, c] = 0.0
    else:
        # the subtree sums start with the link's own part: its children add theirs
        # below before the joint reads them (a child's index is above its parent's)
        for l in range(n):
            for i in range(4):
                for j in range(4):
                    hc[l, i, j] = hw[l, i, j]
                    gc[l, i, j] = 0.0
                wc[l, 0, i] = hw[l, i, 3]       # the first moments: T H's last column
    # velocity-product accelerations B_l (T_ddot^(l) at q_ddot = 0 is B_l T^(l)):
    # B_l = B_p(l) + (2 V_p(l) + S_l qd_l) S_l qd_l,  V_l = V_p(l) + S_l qd_l.  S, V and B
    # have a zero last row: only the first three are formed, and S's zero last row drops
    # the fourth term of each product
    for l in range(n):
        w = q_dot[l]
        p = parents[l]
        if p < 0:
            for i in range(3):
                for j in range(4):
                    sw = s_all[l, i, j] * w
                    tmp[i, j] = sw
                    b_all[l, i, j] = 0.0
                    v_all[l, i, j] = sw
        else:
            for i in range(3):
                for j in range(4):
                    sw = s_all[l, i, j] * w
                    tmp[i, j] = 2.0 * v_all[p, i, j] + sw
                    b_all[l, i, j] = b_all[p, i, j]
                    v_all[l, i, j] = v_all[p, i, j] + sw
        # (the zero diagonal of S's rotation block drops one of the three products in
        # each of its columns)
        for i in range(3):
            b_all[l, i, 0] += w * (tmp[i, 1] * s_all[l, 1, 0] + tmp[i, 2] * s_all[l, 2, 0])
            b_all[l, i, 1] += w * (tmp[i, 0] * s_all[l, 0, 1] + tmp[i, 2] * s_all[l, 2, 1])
            b_all[l, i, 2] += w * (tmp[i, 0] * s_all[l, 0, 2] + tmp[i, 1] * s_all[l, 1, 2])
            b_all[l, i, 3] += w * (tmp[i, 0] * s_all[l, 0, 3] + tmp[i, 1] * s_all[l, 1, 3]
                                   + tmp[i, 2] * s_all[l, 2, 3])
    # S_i = [[W_i, v_i], [0, 0]] with W_i skew: tr(S_i Y^T) = sum over a < c < 3 of
    # S_i[a, c] (Y[a, c] - Y[c, a]) + sum_a S_i[a, 3] Y[a, 3].  s6[e, i] holds S_i's six
    # independent entries (01, 02, 12, 03, 13, 23), so that each row of M below is a sum
    # of six contiguous, vectorisable products
    if form_mass:
        for i in range(n):
            s6[0, i], s6[1, i], s6[2, i] = s_all[i, 0, 1], s_all[i, 0, 2], s_all[i, 1, 2]
            s6[3, i], s6[4, i], s6[5, i] = s_all[i, 0, 3], s_all[i, 1, 3], s_all[i, 2, 3]
    for j in range(n - 1, -1, -1):
        c_j = 0 if serial else j                  # where joint j's sums are
        if serial and massive[j] != 0.0:
            if form_mass:
                for a in range(4):
                    for c in range(4):
                        hc[0, a, c] += hw[j, a, c]
            for a in range(4):
                wc[0, 0, a] += hw[j, a, 3]
        # Gc_j += B_j hw_j (B_j: three rows), without the diagonal: the trace below pairs
        # it with S_j's zero diagonal (constant loops: unrolled, the test compiles away)
        if massive[j] != 0.0:
            for a in range(3):
                for c in range(4):
                    if c != a:
                        gc[c_j, a, c] += b_all[j, a, 0] * hw[j, 0, c] \
                            + b_all[j, a, 1] * hw[j, 1, c] + b_all[j, a, 2] * hw[j, 2, c] \
                            + b_all[j, a, 3] * hw[j, 3, c]
        if form_mass:
            _mass_row(j, s_all, hc, c_j, s6, serial, moves, column, m)
        acc = 0.0
        for a in range(3):
            for c in range(4):
                if c != a:
                    acc += s_all[j, a, c] * gc[c_j, a, c]
        h[j] = -acc
        gj = 0.0
        for a in range(3):
            sw = 0.0
            for c in range(4):
                if c != a:                    # S_j's zero diagonal
                    sw += s_all[j, a, c] * wc[c_j, 0, c]
            gj += gamma[a] * sw
        g[j] = -gj
        p = parents[j]
        if not serial and p >= 0:
            for a in range(4):
                for c in range(4):
                    hc[p, a, c] += hc[j, a, c]
                    gc[p, a, c] += gc[j, a, c]
                wc[p, 0, a] += wc[j, 0, a]


@_jit_leaf
def _is_zero_4x4(mats, l):
    """True when every entry of mats[l] (4, 4) is an exact zero."""
    for i in range(4):
        for j in range(4):
            if mats[l, i, j] != 0.0:
                return False
    return True


@_jit_leaf
def _mass_row(j, s_all, hc, c_j, s6, serial, moves, column, m):
    """Row and column j of M up to the diagonal: m_ij = m_ji = tr(S_i Hc_j S_j^T) for
    i <= j (zero where joint i does not move link j: other branches of a tree); Hc_j is
    hc[c_j].

    Y = S_j Hc_j is formed on the nine entries the skew trace reads (S_j's zero diagonal
    and last row drop their terms), folded to the six that pair with s6 (terms_into)."""
    s01, s02, s03 = s_all[j, 0, 1], s_all[j, 0, 2], s_all[j, 0, 3]
    s10, s12, s13 = s_all[j, 1, 0], s_all[j, 1, 2], s_all[j, 1, 3]
    s20, s21, s23 = s_all[j, 2, 0], s_all[j, 2, 1], s_all[j, 2, 3]
    y01 = s01 * hc[c_j, 1, 1] + s02 * hc[c_j, 2, 1] + s03 * hc[c_j, 3, 1]
    y10 = s10 * hc[c_j, 0, 0] + s12 * hc[c_j, 2, 0] + s13 * hc[c_j, 3, 0]
    y02 = s01 * hc[c_j, 1, 2] + s02 * hc[c_j, 2, 2] + s03 * hc[c_j, 3, 2]
    y20 = s20 * hc[c_j, 0, 0] + s21 * hc[c_j, 1, 0] + s23 * hc[c_j, 3, 0]
    y12 = s10 * hc[c_j, 0, 2] + s12 * hc[c_j, 2, 2] + s13 * hc[c_j, 3, 2]
    y21 = s20 * hc[c_j, 0, 1] + s21 * hc[c_j, 1, 1] + s23 * hc[c_j, 3, 1]
    e0, e1, e2 = y01 - y10, y02 - y20, y12 - y21
    e3 = s01 * hc[c_j, 1, 3] + s02 * hc[c_j, 2, 3] + s03 * hc[c_j, 3, 3]
    e4 = s10 * hc[c_j, 0, 3] + s12 * hc[c_j, 2, 3] + s13 * hc[c_j, 3, 3]
    e5 = s20 * hc[c_j, 0, 3] + s21 * hc[c_j, 1, 3] + s23 * hc[c_j, 3, 3]
    for i in range(j + 1):
        column[i] = (s6[0, i] * e0 + s6[1, i] * e1 + s6[2, i] * e2 + s6[3, i] * e3
                     + s6[4, i] * e4 + s6[5, i] * e5)
    if serial:
        for i in range(j + 1):
            m[j, i] = column[i]
            m[i, j] = column[i]
    else:
        for i in range(j + 1):
            v = column[i] if moves[i, j] else 0.0
            m[j, i] = v
            m[i, j] = v


@_jit
def point(t_all, s_all, moves, q_dot, link, r_local, w_hom=1.0):
    """(position (3,), velocity (3,), jacobian (3, n), drift (3,)) of a point fixed on link
    (w_hom = 1; r_local (3,) m in the link frame) or of a direction (w_hom = 0: a vector
    r_local turned with the link, 1 for a unit vector)."""
    n = q_dot.shape[0]
    pos, vel, drift = np.empty(3), np.empty(3), np.empty(3)
    jac = np.empty((3, n))
    point_into(t_all, s_all, moves, q_dot, link, r_local, w_hom, pos, vel, jac, drift,
               np.empty(POINT_SCRATCH))
    return pos, vel, jac, drift


POINT_SCRATCH = 28          # floats of point_into's scratch: rw (4), col (4), v_prev (4, 4), r (4)


@_jit
def point_into(t_all, s_all, moves, q_dot, link, r_local, w_hom, pos, vel, jac, drift,
               scratch):
    """:func:`point` into pos (3,), vel (3,), jac (3, n), drift (3,); scratch (POINT_SCRATCH,)."""
    n = q_dot.shape[0]
    rw = scratch[0:4]
    col = scratch[4:8]
    v_prev = scratch[8:24].reshape((4, 4))
    r = scratch[24:28]
    r[0], r[1], r[2], r[3] = r_local[0], r_local[1], r_local[2], w_hom
    for i in range(4):
        acc = 0.0
        for c in range(4):
            acc += t_all[link, i, c] * r[c]
        rw[i] = acc
    for a in range(3):
        vel[a] = 0.0
        drift[a] = 0.0
        for j in range(link + 1, n):
            jac[a, j] = 0.0
    for a in range(4):
        for c in range(4):
            v_prev[a, c] = 0.0
    # p_dot = sum S_i qd_i r_w;  drift = B r_w with B from the recursion along the path
    # of joints that move the link (a serial chain), applied to r_w directly:
    # B r_w = sum_l (2 V_{l-1} + S_l qd_l) S_l qd_l r_w
    for l in range(link + 1):
        if not moves[l, link]:
            for a in range(3):
                jac[a, l] = 0.0
            continue
        for a in range(4):
            acc = 0.0
            for c in range(4):
                acc += s_all[l, a, c] * rw[c]
            col[a] = acc
        for a in range(3):
            jac[a, l] = col[a]
        w = q_dot[l]
        if w != 0.0:
            for a in range(3):
                acc = 0.0
                for c in range(4):
                    acc += (2.0 * v_prev[a, c] + s_all[l, a, c] * w) * col[c]
                drift[a] += acc * w
                vel[a] += col[a] * w
            for a in range(4):
                for c in range(4):
                    v_prev[a, c] += s_all[l, a, c] * w
    for a in range(3):
        pos[a] = rw[a]


@_jit
def chain_and_terms(origins, generators, is_revolute, pseudo_inertias, gamma, parents, moves,
                    q, q_dot):
    """(T, S, M, h, g) in one compiled call (see :func:`chain` and :func:`terms`)."""
    t_all, s_all = chain(origins, generators, is_revolute, parents, q)
    m, h, g = terms(t_all, s_all, pseudo_inertias, gamma, parents, moves, q_dot)
    return t_all, s_all, m, h, g


@_jit
def multipliers_into(m, rhs, q_ddot, inv_dc, dc, lam):
    """lam (k,) = A_dc^-T F[dc] from the reactions F = M q_ddot - rhs = A^T lambda;
    m (n, n), rhs (n,), q_ddot (n,), inv_dc (k, k) = A_dc^-1, dc (k,) indices."""
    n = m.shape[0]
    k = dc.shape[0]
    for i in range(k):
        acc = 0.0
        for p in range(k):
            f = -rhs[dc[p]]
            for c in range(n):
                f += m[dc[p], c] * q_ddot[c]
            acc += inv_dc[p, i] * f
        lam[i] = acc


# ---------------------------------------------------------------- free solve of a chain
N_TWIST = 6          # entries of a unit twist / spatial vector: (omega (3), v (3))
ANGULAR = 0          # where omega (rad/s) and the moment (N m) start in a spatial vector
LINEAR = 3           # where v (m/s) and the force (N) start
SCRATCH_PER_JOINT = N_TWIST + 2                 # U_i (6), D_i, w_i
SCRATCH_FIXED = N_TWIST * N_TWIST + 2 * N_TWIST  # I^A (6, 6), p^A / a (6), u_i (6)
FIXED_ROWS = N_TWIST + 2                        # the fixed part as rows of six


@_jit
def chain_solve_scratch_size(n):
    """Length of the float scratch of :func:`chain_solve` for n joints."""
    return SCRATCH_PER_JOINT * n + SCRATCH_FIXED


@_jit_leaf
def unit_twist_into(s_all, i, u):
    """u (6,) = (omega_i rad, v_i m) per unit q_dot_i: the world unit twist of joint i from
    its world twist matrix s_all[i] (4, 4) = [[skew(omega_i), v_i], [0, 0]]."""
    u[ANGULAR], u[ANGULAR + 1], u[ANGULAR + 2] = s_all[i, 2, 1], s_all[i, 0, 2], s_all[i, 1, 0]
    u[LINEAR], u[LINEAR + 1], u[LINEAR + 2] = s_all[i, 0, 3], s_all[i, 1, 3], s_all[i, 2, 3]


@_jit_leaf
def add_spatial_inertia(hw, link, inertia):
    """inertia (6, 6) += the spatial inertia of ``link`` about the world origin, ordered
    (omega, v), from its world pseudo-inertia hw[link] (4, 4):
    [[tr(Sigma) E - Sigma, skew(m c)], [skew(m c)^T, m E]] (module docstring, "Free
    solve")."""
    second_moment_trace = hw[link, 0, 0] + hw[link, 1, 1] + hw[link, 2, 2]     # kg m^2
    for a in range(3):
        for c in range(3):
            inertia[ANGULAR + a, ANGULAR + c] -= hw[link, a, c]
        inertia[ANGULAR + a, ANGULAR + a] += second_moment_trace
    mcx, mcy, mcz = hw[link, 0, 3], hw[link, 1, 3], hw[link, 2, 3]           # kg m
    # skew(m c) = [[0, -mcz, mcy], [mcz, 0, -mcx], [-mcy, mcx, 0]] and its transpose
    inertia[ANGULAR, LINEAR + 1] -= mcz
    inertia[ANGULAR, LINEAR + 2] += mcy
    inertia[ANGULAR + 1, LINEAR] += mcz
    inertia[ANGULAR + 1, LINEAR + 2] -= mcx
    inertia[ANGULAR + 2, LINEAR] -= mcy
    inertia[ANGULAR + 2, LINEAR + 1] += mcx
    inertia[LINEAR + 1, ANGULAR] -= mcz
    inertia[LINEAR + 2, ANGULAR] += mcy
    inertia[LINEAR, ANGULAR + 1] += mcz
    inertia[LINEAR + 2, ANGULAR + 1] -= mcx
    inertia[LINEAR, ANGULAR + 2] -= mcy
    inertia[LINEAR + 1, ANGULAR + 2] += mcx
    mass = hw[link, 3, 3]                                                      # kg
    for a in range(3):
        inertia[LINEAR + a, LINEAR + a] += mass


@_jit_leaf
def chain_solve(s_all, hw, b, q_ddot, scratch):
    """q_ddot (n,) = M^-1 b for a serial chain (parents[k] = k - 1) by the articulated-body
    recursion in the world frame (module docstring, "Free solve"); False, q_ddot unset,
    when M is not positive definite (a pivot D_i not > 0, or NaN).

    s_all (n, 4, 4): the joints' world twist matrices (:func:`chain_into`);
    hw (n, 4, 4): the links' world pseudo-inertias, kg m^2 | kg m | kg
    (:func:`world_pseudo_inertias` after :func:`terms_into`);
    b (n,): N or N m, the right-hand side h + Q of M q_ddot = h + Q;
    q_ddot (n,): m/s^2 or rad/s^2 (a different array from b);
    scratch (chain_solve_scratch_size(n),) floats (nothing is allocated).
    M itself is not formed."""
    n = b.shape[0]
    # rows of six carved from one reshaped view (a reshape costs a call, a slice does not)
    rows = scratch[:N_TWIST * (n + FIXED_ROWS)].reshape((n + FIXED_ROWS, N_TWIST))
    joint_force = rows[:n]                          # U_i = I^A u_i
    articulated = rows[n:n + N_TWIST]               # I^A (6, 6)
    transmitted = rows[n + N_TWIST]                 # p^A on the way back, then a forward
    u = rows[n + N_TWIST + 1]
    used = N_TWIST * (n + FIXED_ROWS)
    pivot = scratch[used:used + n]                  # D_i = u_i^T U_i
    reduced_b = scratch[used + n:used + 2 * n]      # w_i = b_i - u_i^T p^A
    for a in range(N_TWIST):
        transmitted[a] = 0.0
        for c in range(N_TWIST):
            articulated[a, c] = 0.0
    for i in range(n - 1, -1, -1):
        if not _is_zero_4x4(hw, i):          # a massless link adds nothing
            add_spatial_inertia(hw, i, articulated)
        unit_twist_into(s_all, i, u)
        d = 0.0
        u_dot_p = 0.0
        for a in range(N_TWIST):
            f = 0.0
            for c in range(N_TWIST):
                f += articulated[a, c] * u[c]
            joint_force[i, a] = f
            d += u[a] * f
            u_dot_p += u[a] * transmitted[a]
        if not d > 0.0:
            return False
        pivot[i] = d
        w = b[i] - u_dot_p
        reduced_b[i] = w
        inv_d = 1.0 / d
        # I^A -= U U^T / D, formed as (U_a U_c) (1 / D) so that I^A stays exactly symmetric:
        # its lower triangle, mirrored
        for a in range(N_TWIST):
            fa = joint_force[i, a]
            transmitted[a] += fa * (w * inv_d)
            for c in range(a + 1):
                articulated[a, c] -= (fa * joint_force[i, c]) * inv_d
                articulated[c, a] = articulated[a, c]
    acceleration = transmitted
    for a in range(N_TWIST):
        acceleration[a] = 0.0
    for i in range(n):
        s = reduced_b[i]
        for a in range(N_TWIST):
            s -= joint_force[i, a] * acceleration[a]
        qdd = s / pivot[i]
        q_ddot[i] = qdd
        unit_twist_into(s_all, i, u)
        for a in range(N_TWIST):
            acceleration[a] += u[a] * qdd
    return True

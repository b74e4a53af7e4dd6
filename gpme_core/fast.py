"""Compiled (numba) kernels of the chain kinematics and the trace-form dynamics terms.

The same formulas as gpme_core.kinematics and gpme_core.dynamics (which stay the readable
numpy reference; tests/test_fast.py checks both agree to round-off), written as loops over
4x4 matrices so that one evaluation costs microseconds instead of the ~100 us of numpy call
overhead.  Set the environment variable GPME_NO_JIT=1 to use the numpy reference instead.

Shapes: n coordinates; origins, generators, pseudo_inertias (n, 4, 4); q, q_dot (n,);
gamma (4,) = (gravity, 0); parents (n,) int64, the parent link of each joint (-1 the
world, < the joint's index); moves (n, n) bool, moves[i, l] when joint i moves link l
(model.parents, model.moves: a kinematic tree, a serial chain when parents[k] = k - 1).
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
    # generated code of the user's expressions (gpme_core.compiled): a division by zero
    # gives inf or nan as in numpy, for the caller's finiteness check to report, instead
    # of raising ZeroDivisionError out of the compiled loop
    _jit_user = kernel_jit(fastmath=False, error_model="numpy")
else:  # pragma: no cover
    def _jit(f):
        return f
    _jit_user = _jit


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
def _mm4(a, b, out):
    """out = a @ b for 4x4 arrays, no allocation."""
    for i in range(4):
        for j in range(4):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j] + a[i, 3] * b[3, j]


@_jit
def _mm4_acc(a, b, scale, out):
    """out += scale * (a @ b) for 4x4 arrays."""
    for i in range(4):
        for j in range(4):
            out[i, j] += scale * (a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]
                                  + a[i, 3] * b[3, j])


@_jit
def _mm3(a, b, out):
    """out[:3] = (a @ b)[:3] for 4x4 arrays whose last row of ``a`` is zero (twist and
    velocity-product matrices); out[3] is left as it is (zero in every use here)."""
    for i in range(3):
        for j in range(4):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j] + a[i, 3] * b[3, j]


@_jit
def _mm3_acc(a, b, scale, out):
    """out[:3] += scale * (a @ b)[:3] for 4x4 arrays, ``a`` with a zero last row."""
    for i in range(3):
        for j in range(4):
            out[i, j] += scale * (a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]
                                  + a[i, 3] * b[3, j])


@_jit
def chain(origins, generators, is_revolute, parents, q):
    """(T, S): world transforms T^(l) and world twist matrices S_l = T^(l) Q_l T^(l)^-1."""
    n = q.shape[0]
    t_all = np.empty((n, 4, 4))
    s_all = np.empty((n, 4, 4))
    chain_into(origins, generators, is_revolute, parents, q, t_all, s_all, np.empty((2, 4, 4)))
    return t_all, s_all


@_jit
def chain_into(origins, generators, is_revolute, parents, q, t_all, s_all, scratch):
    """:func:`chain` into t_all, s_all (n, 4, 4); scratch (2, 4, 4) work space."""
    n = q.shape[0]
    motion = scratch[0]
    local = scratch[1]
    for k in range(n):
        g = generators[k]
        for i in range(4):
            for j in range(4):
                motion[i, j] = 1.0 if i == j else 0.0
                s_all[k, i, j] = 0.0
        if is_revolute[k]:
            # Rodrigues: R = I + sin K + (1 - cos) K^2, K = skew(axis)
            s, c = np.sin(q[k]), np.cos(q[k])
            for i in range(3):
                for j in range(3):
                    kk = g[i, 0] * g[0, j] + g[i, 1] * g[1, j] + g[i, 2] * g[2, j]
                    motion[i, j] += s * g[i, j] + (1.0 - c) * kk
        else:
            for i in range(3):
                motion[i, 3] = g[i, 3] * q[k]
        _mm4(origins[k], motion, local)
        if parents[k] < 0:
            t_all[k, :, :] = local
        else:
            _mm4(t_all[parents[k]], local, t_all[k])
        acc = t_all[k]
        if is_revolute[k]:
            # S = [[W, -W p], [0, 0]],  W = R K R^T = skew(R k): the axis k = (K[2, 1],
            # K[0, 2], K[1, 0]) turned into the world frame
            wx = acc[0, 0] * g[2, 1] + acc[0, 1] * g[0, 2] + acc[0, 2] * g[1, 0]
            wy = acc[1, 0] * g[2, 1] + acc[1, 1] * g[0, 2] + acc[1, 2] * g[1, 0]
            wz = acc[2, 0] * g[2, 1] + acc[2, 1] * g[0, 2] + acc[2, 2] * g[1, 0]
            s_all[k, 0, 1], s_all[k, 0, 2] = -wz, wy
            s_all[k, 1, 0], s_all[k, 1, 2] = wz, -wx
            s_all[k, 2, 0], s_all[k, 2, 1] = -wy, wx
            for i in range(3):
                s_all[k, i, 3] = -(s_all[k, i, 0] * acc[0, 3] + s_all[k, i, 1] * acc[1, 3]
                                   + s_all[k, i, 2] * acc[2, 3])
        else:
            for i in range(3):
                s_all[k, i, 3] = acc[i, 0] * g[0, 3] + acc[i, 1] * g[1, 3] + acc[i, 2] * g[2, 3]


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
    return 5 * 16 * n + 4 * n + 12 * n + n + 3 * 16


@_jit
def terms_into(t_all, s_all, pseudo_inertias, gamma, parents, moves, q_dot, m, h, g,
               scratch):
    """:func:`terms` into m (n, n), h (n,), g (n,); scratch (terms_scratch_size(n),).

    Per link l: hw_l = T H T^T (world pseudo-inertia); per joint, over its subtree
    (gpme_core.dynamics): hc (composite pseudo-inertia), gc (sum of B_l hw_l), wc (first
    moments: the last columns of T H), accumulated from the leaves to the root."""
    n = q_dot.shape[0]
    hw = scratch[:16 * n].reshape((n, 4, 4))
    hc = scratch[16 * n:32 * n].reshape((n, 4, 4))
    gc = scratch[32 * n:48 * n].reshape((n, 4, 4))
    b_all = scratch[48 * n:64 * n].reshape((n, 4, 4))
    v_all = scratch[64 * n:80 * n].reshape((n, 4, 4))
    wc = scratch[80 * n:84 * n].reshape((n, 4))
    s_rows = scratch[84 * n:96 * n].reshape((12, n))
    column = scratch[96 * n:97 * n]
    small = scratch[97 * n:97 * n + 3 * 16].reshape((3, 4, 4))
    th, tmp, y = small[0], small[1], small[2]
    for l in range(n):
        _mm4(t_all[l], pseudo_inertias[l], th)
        tl = t_all[l]
        # T H T^T is symmetric: the upper triangle, mirrored
        for i in range(4):
            for j in range(i, 4):
                v = th[i, 0] * tl[j, 0] + th[i, 1] * tl[j, 1] + th[i, 2] * tl[j, 2] \
                    + th[i, 3] * tl[j, 3]
                hw[l, i, j] = v
                hw[l, j, i] = v
            wc[l, i] = th[i, 3]
            for j in range(4):
                # the subtree sums start with the link's own part: its children add theirs
                # below before the joint reads them (a child's index is above its parent's)
                hc[l, i, j] = hw[l, i, j]
                gc[l, i, j] = 0.0
    # velocity-product accelerations B_l (T_ddot^(l) at q_ddot = 0 is B_l T^(l)):
    # B_l = B_p(l) + (2 V_p(l) + S_l qd_l) S_l qd_l,  V_l = V_p(l) + S_l qd_l.  S, V and B
    # have a zero last row: only the first three are formed (what _mm3_acc reads)
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
        _mm3_acc(tmp, s_all[l], w, b_all[l])
    # S has a zero last row: the traces run over its first three rows only.  s_rows[e, i]
    # is entry e = 4 a + c (a < 3) of S_i, so that each m_ij below is a sum over e of
    # contiguous, vectorisable products (summed in the same order as tr(S_i Y^T)).
    for i in range(n):
        for a in range(3):
            for c in range(4):
                s_rows[4 * a + c, i] = s_all[i, a, c]
    for j in range(n - 1, -1, -1):
        hcj = hc[j]
        _mm3_acc(b_all[j], hw[j], 1.0, gc[j])
        _mm3(s_all[j], hcj, y)
        for i in range(j + 1):
            column[i] = 0.0
        for a in range(3):
            for c in range(4):
                yac = y[a, c]
                row = s_rows[4 * a + c]
                for i in range(j + 1):
                    column[i] += row[i] * yac
        # m_ij = tr(S_i Hc_j S_j^T) where joint i moves link j, else 0 (other branches)
        for i in range(j + 1):
            v = column[i] if moves[i, j] else 0.0
            m[i, j] = v
            m[j, i] = v
        acc = 0.0
        for a in range(3):
            for c in range(4):
                acc += s_all[j, a, c] * gc[j, a, c]
        h[j] = -acc
        gj = 0.0
        for a in range(3):
            sw = 0.0
            for c in range(4):
                sw += s_all[j, a, c] * wc[j, c]
            gj += gamma[a] * sw
        g[j] = -gj
        p = parents[j]
        if p >= 0:
            for a in range(4):
                for c in range(4):
                    hc[p, a, c] += hcj[a, c]
                    gc[p, a, c] += gc[j, a, c]
                wc[p, a] += wc[j, a]


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

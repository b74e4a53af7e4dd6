"""Compiled (numba) kernels of the chain kinematics and the trace-form dynamics terms.

The same formulas as gpme_core.kinematics and gpme_core.dynamics (which stay the readable
numpy reference; tests/test_fast.py checks both agree to round-off), written as loops over
4x4 matrices so that one evaluation costs microseconds instead of the ~100 us of numpy call
overhead.  Set the environment variable GPME_NO_JIT=1 to use the numpy reference instead.

Shapes: n coordinates; origins, generators, pseudo_inertias (n, 4, 4); q, q_dot (n,);
gamma (4,) = (gravity, 0).
"""
import os

import numpy as np

ENABLED = os.environ.get("GPME_NO_JIT", "") not in ("1", "true", "yes")

try:
    import numba
except ImportError:  # pragma: no cover - numba is a dependency; keep the reference path
    ENABLED = False

if ENABLED:
    _jit = numba.njit(cache=True, fastmath=False)
else:  # pragma: no cover
    def _jit(f):
        return f


@_jit
def _mm(a, b):
    """Small dense matrix product by loops (BLAS call overhead dominates at 4x4)."""
    n, k = a.shape
    m = b.shape[1]
    out = np.zeros((n, m))
    for i in range(n):
        for p in range(k):
            aip = a[i, p]
            if aip != 0.0:
                for j in range(m):
                    out[i, j] += aip * b[p, j]
    return out


@_jit
def _mv(a, x):
    n, k = a.shape
    out = np.zeros(n)
    for i in range(n):
        acc = 0.0
        for p in range(k):
            acc += a[i, p] * x[p]
        out[i] = acc
    return out


@_jit
def chain(origins, generators, is_revolute, q):
    """(T, S): world transforms T^(l) and world twist matrices S_l = T^(l) Q_l T^(l)^-1."""
    n = q.shape[0]
    t_all = np.empty((n, 4, 4))
    s_all = np.zeros((n, 4, 4))
    acc = np.eye(4)
    motion = np.eye(4)
    for k in range(n):
        motion[:, :] = 0.0
        for i in range(4):
            motion[i, i] = 1.0
        g = generators[k]
        if is_revolute[k]:
            s, c = np.sin(q[k]), np.cos(q[k])
            kk = _mm(g[:3, :3], g[:3, :3])
            for i in range(3):
                for j in range(3):
                    motion[i, j] += s * g[i, j] + (1.0 - c) * kk[i, j]
        else:
            for i in range(3):
                motion[i, 3] = g[i, 3] * q[k]
        acc = _mm(acc, _mm(origins[k], motion))
        t_all[k] = acc
        r = acc[:3, :3]
        p = acc[:3, 3]
        if is_revolute[k]:
            # S = [[R K R^T, -R K R^T p], [0, 0]]
            w = _mm(_mm(r, g[:3, :3]), r.T)
            s_all[k, :3, :3] = w
            s_all[k, :3, 3] = -_mv(w, p)
        else:
            s_all[k, :3, 3] = _mv(r, g[:3, 3])
    return t_all, s_all


@_jit
def _inner(a, b):
    acc = 0.0
    for i in range(4):
        for j in range(4):
            acc += a[i, j] * b[i, j]
    return acc


@_jit
def terms(t_all, s_all, pseudo_inertias, gamma, q_dot):
    """(M (n, n), h (n,), g (n,)) in trace form with composite world pseudo-inertias."""
    n = q_dot.shape[0]
    hw = np.empty((n, 4, 4))
    first = np.empty((n, 4))
    for l in range(n):
        th = _mm(t_all[l], pseudo_inertias[l])
        hw[l] = _mm(th, t_all[l].T)
        first[l] = th[:, 3]
    # velocity-product accelerations B_l (T_ddot^(l) at q_ddot = 0 is B_l T^(l))
    b_all = np.empty((n, 4, 4))
    v_prev = np.zeros((4, 4))
    b_prev = np.zeros((4, 4))
    for l in range(n):
        w = s_all[l] * q_dot[l]
        b_prev = b_prev + _mm(2.0 * v_prev + w, w)
        b_all[l] = b_prev
        v_prev = v_prev + w
    m = np.empty((n, n))
    h = np.empty(n)
    g = np.empty(n)
    hc = np.zeros((4, 4))
    gacc = np.zeros((4, 4))
    wacc = np.zeros(4)
    for j in range(n - 1, -1, -1):
        hc = hc + hw[j]
        gacc = gacc + _mm(b_all[j], hw[j])
        wacc = wacc + first[j]
        y = _mm(s_all[j], hc)
        for i in range(j + 1):
            m[i, j] = _inner(s_all[i], y)
            m[j, i] = m[i, j]
        h[j] = -_inner(s_all[j], gacc)
        sw = _mv(s_all[j], wacc)
        g[j] = -(gamma[0] * sw[0] + gamma[1] * sw[1] + gamma[2] * sw[2])
    return m, h, g


@_jit
def point(t_all, s_all, q_dot, link, r_local):
    """(position (3,), velocity (3,), jacobian (3, n), drift (3,)) of a point fixed on link."""
    n = q_dot.shape[0]
    r = np.empty(4)
    r[:3] = r_local
    r[3] = 1.0
    rw = _mv(t_all[link], r)
    jac = np.zeros((3, n))
    v_prev = np.zeros((4, 4))
    b = np.zeros((4, 4))
    for i in range(link + 1):
        col = _mv(s_all[i], rw)
        jac[:, i] = col[:3]
        w = s_all[i] * q_dot[i]
        b = b + _mm(2.0 * v_prev + w, w)
        v_prev = v_prev + w
    drift = _mv(b, rw)[:3]
    return rw[:3].copy(), _mv(jac, q_dot), jac, drift


@_jit
def chain_and_terms(origins, generators, is_revolute, pseudo_inertias, gamma, q, q_dot):
    """(T, S, M, h, g) in one compiled call (see :func:`chain` and :func:`terms`)."""
    t_all, s_all = chain(origins, generators, is_revolute, q)
    m, h, g = terms(t_all, s_all, pseudo_inertias, gamma, q_dot)
    return t_all, s_all, m, h, g

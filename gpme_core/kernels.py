"""Fused compiled right-hand side of the GPME and the compiled integrator loops.

One call of :func:`evaluate` does, without Python in between: the chain kinematics and
the trace-form terms M, h, g (gpme_core.fast), springs, dampers and drives, the rows of
the programmed constraints (Phi, Phi_dot, A, kappa) and the reduced GPME solve with its
multipliers.  :func:`rk4_advance` and :func:`radau_advance` integrate it over a number of
fixed steps without returning to Python.  gpme_core.compiled packs a ProgrammedMotion into
the arrays these take; gpme_core.integrate drives them.

Reduced solve (same equations as gpme_core.gpme, solved through the symmetric form): with
Gamma = -A_dc^-1 A_ic, N = [I; Gamma] (rows ordered as q) and a particular solution p of
A p = c (p_dc = A_dc^-1 c, p_ic = 0), q_ddot = N z + p where

    (N^T M N) z = N^T (h + Q - M p)        ((n - m) x (n - m), symmetric positive definite)

which is paper eq. 7 with A q_ddot = c substituted; Cholesky instead of the LU of the
unsymmetric n x n system of gpme_core.gpme (same solution, half the work, no pivoting).
Multipliers: lambda = A_dc^-T (M q_ddot - h - Q)_dc.

Everything is SI; q, q_dot (n,) ordered as model.coordinate_names.  Data tuples (built by
gpme_core.compiled.pack):

    md = (mats (3, n, 4, 4): origins, generators, pseudo_inertias; vecs (6, n):
          is_revolute (0/1), stiffness, spring_reference, damping, lower_limits,
          upper_limits; gamma (4,); parents (n,) int64; moves (n, n) bool: the tree,
          gpme_core.fast)                                -> :func:`model_parts`
    cd = (ci int64: m, P, F, D, S, c_kind (m), c_point (m), c_fun (m), c_point_b (m),
          p_link (P), f_kind (F), f_off (F), d_coord (D), d_fun (D), s_a (S), s_b (S); cf
          float: c_par (m, 4), p_r (P, 4) (vector in the link frame, m or 1, and its
          homogeneous w: 1 a point, 0 a direction), s_par (S, 6), f_par)
                                                         -> :func:`constraint_parts`
         (c_point_b: the second vector of a pair constraint, -1 for the others; the point
         springs, gpme_core.point_springs: s_a, s_b their ends in the vector table, s_b -1
         for a world anchor, s_par = (stiffness N/m, free length m, damping N s/m, anchor
         (3,) m))
    opts = float array (alpha 1/s, beta 1/s, paper_eq7 0/1, switch_below, singular_rcond,
           divergence_limit[, dense_free_solve 0/1]) (the last entry optional:
           OPT_DENSE_FREE_SOLVE)

Free solve (k == 0, :func:`free_solve_is_recursive`): a serial chain (gpme_core.fast.
is_serial) is solved by the O(n) articulated-body recursion gpme_core.fast.chain_solve,
without forming M; a tree, or any model with opts[OPT_DENSE_FREE_SOLVE] = 1, by the dense
Cholesky of M.

(few arrays rather than one per quantity: each argument of a compiled function costs its
own typing and unboxing on every call from Python.)

Errors are status codes (never exceptions, never NaN results): the caller re-evaluates
the failing state with the Python reference (gpme_core.gpme) to raise the error message.

The section between the "user functions" markers is replaced by generated code for SymPy
constraints and time functions (gpme_core.compiled); here it holds stubs.
"""
import math

import numpy as np

from .fast import (POINT_SCRATCH, _jit, chain_into, chain_solve,
                   chain_solve_scratch_size, is_serial, multipliers_into, point_into, terms_into,
                   terms_scratch_size)

# ---------------------------------------------------------------- status codes
OK = 0
SINGULAR_PARTITION = 1      # partition rcond <= singular_rcond
SINGULAR_REDUCED = 2        # N^T M N not positive definite
NOT_FINITE = 3              # a constraint, time function or drive value is not finite
SWITCH = 4                  # partition rcond < switch_below: re-choose dependent coordinates
DIVERGED = 5                # state not finite or above divergence_limit
OUT_OF_RANGE = 6            # a coordinate left its limits
NEWTON_FAILED = 7           # the implicit stage equations did not converge

# ---------------------------------------------------------------- kinds
C_ELLIPSE = 0               # c_par = (1/a^2, 1/b^2, x_c, y_c)
C_COORDINATE = 1            # c_par = (axis, ., ., .), phi = p[axis] - f(t)
C_JOINT = 2                 # c_par = (k, ., ., .), phi = q_k - f(t)
C_USER_POINT = 3            # c_par = (user index, ., ., .), generated local terms
# pair constraints (gpme_core.pair_constraints): phi of the stacked vectors s = (s_a, s_b)
C_RELATIVE = 4              # c_par = (axis, ., ., .), phi = s_b[axis] - s_a[axis] - f(t)
C_DISTANCE = 5              # phi = |s_b - s_a| - f(t)
C_AXIS_DOT = 6              # phi = s_a . s_b - f(t) (two directions)
C_USER_PAIR = 7             # c_par = (user index, ., ., .), generated local terms
N_PAIR_TERMS = 51           # phi, grad (6), Hessian (6x6), phi_t, grad_t (6), phi_tt
F_CONSTANT = 0              # (level)
F_COSINE = 1                # (offset, amplitude, omega)
F_SINE = 2                  # (offset, amplitude, omega, phase)
F_QUINTIC = 3               # (level, ramp_time)
F_TABULATED = 4             # (k, times (k), coefficients (k - 1, 4) row-major, v_first, v_last)
F_USER = 5                  # (user index)

# opts index of the optional switch (tests, benchmarks.kernel_profile): 1 solves a free
# serial chain by the dense Cholesky of M instead of gpme_core.fast.chain_solve;
# gpme_core.compiled gives opts without it (the recursive solve)
OPT_DENSE_FREE_SOLVE = 6

INFO_SIZE = 5               # info: partition rcond, W rates (dissipated, drive, reaction), spare
N_WORK = 3

# --- user functions: begin ---


@_jit
def user_point_terms(index, x, y, z, t, out):
    """Generated: the 18 local terms (phi, grad (3), Hessian (3x3 row-major), phi_t,
    grad_t (3), phi_tt) of SymPy point constraint ``index`` at world point (x, y, z) m,
    time t s, into out (18,).  Stub: no user constraints."""
    for i in range(18):
        out[i] = np.nan


@_jit
def user_pair_terms(index, x_a, y_a, z_a, x_b, y_b, z_b, t, out):
    """Generated: the 51 local terms of SymPy pair constraint ``index`` at the frames'
    origins (m) and time t s into out (51,).  Stub: no user pair constraints."""
    for i in range(N_PAIR_TERMS):
        out[i] = np.nan


@_jit
def user_time_terms(index, t, out):
    """Generated: (f, f', f'') of SymPy time function ``index`` at t s into out (3,)."""
    for i in range(3):
        out[i] = np.nan

# --- user functions: end ---


@_jit
def model_parts(md):
    """(origins, generators, is_revolute, pseudo_inertias, gamma, stiffness,
    spring_reference, damping, lower_limits, upper_limits, parents, moves) views of md."""
    mats, vecs, gamma, parents, moves = md
    return (mats[0], mats[1], vecs[0], mats[2], gamma, vecs[1], vecs[2], vecs[3], vecs[4],
            vecs[5], parents, moves)


@_jit
def constraint_parts(cd):
    """(c_kind, c_point, c_fun, c_par, p_link, p_r, f_kind, f_off, f_par, d_coord, d_fun,
    c_point_b, s_a, s_b, s_par) views of cd (module docstring)."""
    ci, cf = cd
    m, n_points, n_fun, n_drive, n_spring = ci[0], ci[1], ci[2], ci[3], ci[4]
    o = 5
    c_kind = ci[o:o + m]
    c_point = ci[o + m:o + 2 * m]
    c_fun = ci[o + 2 * m:o + 3 * m]
    c_point_b = ci[o + 3 * m:o + 4 * m]
    o += 4 * m
    p_link = ci[o:o + n_points]
    o += n_points
    f_kind = ci[o:o + n_fun]
    f_off = ci[o + n_fun:o + 2 * n_fun]
    o += 2 * n_fun
    d_coord = ci[o:o + n_drive]
    d_fun = ci[o + n_drive:o + 2 * n_drive]
    o += 2 * n_drive
    s_a = ci[o:o + n_spring]
    s_b = ci[o + n_spring:o + 2 * n_spring]
    c_par = cf[:4 * m].reshape((m, 4))
    p_r = cf[4 * m:4 * m + 4 * n_points].reshape((n_points, 4))
    o = 4 * m + 4 * n_points
    s_par = cf[o:o + 6 * n_spring].reshape((n_spring, 6))
    f_par = cf[o + 6 * n_spring:]
    return (c_kind, c_point, c_fun, c_par, p_link, p_r, f_kind, f_off, f_par, d_coord, d_fun,
            c_point_b, s_a, s_b, s_par)


@_jit
def drive_parts(cd):
    """(f_kind, f_off, f_par, d_coord, d_fun) views of cd: what the drives read, without
    the reshaped views of :func:`constraint_parts` (a reshape costs a call)."""
    ci, cf = cd
    m, n_points, n_fun, n_drive, n_spring = ci[0], ci[1], ci[2], ci[3], ci[4]
    o = 5 + 4 * m + n_points
    f_kind = ci[o:o + n_fun]
    f_off = ci[o + n_fun:o + 2 * n_fun]
    o += 2 * n_fun
    d_coord = ci[o:o + n_drive]
    d_fun = ci[o + n_drive:o + 2 * n_drive]
    f_par = cf[4 * m + 4 * n_points + 6 * n_spring:]
    return f_kind, f_off, f_par, d_coord, d_fun


@_jit
def time_function(kind, off, par, t, out):
    """(f, f', f'') of time function of ``kind`` with parameters par[off:] at t s -> out."""
    if kind == F_CONSTANT:
        out[0], out[1], out[2] = par[off], 0.0, 0.0
    elif kind == F_COSINE or kind == F_SINE:
        amp, omega = par[off + 1], par[off + 2]
        arg = omega * t + (par[off + 3] if kind == F_SINE else 0.0)
        c, s = math.cos(arg), math.sin(arg)
        if kind == F_COSINE:
            out[0], out[1], out[2] = par[off] + amp * c, -amp * omega * s, -amp * omega * omega * c
        else:
            out[0], out[1], out[2] = par[off] + amp * s, amp * omega * c, -amp * omega * omega * s
    elif kind == F_QUINTIC:
        level, ramp = par[off], par[off + 1]
        s = min(max(t / ramp, 0.0), 1.0)
        out[0] = level * s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s)
        out[1] = level * 30.0 * s * s * (1.0 - s) ** 2 / ramp
        out[2] = level * 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s) / ramp ** 2
    elif kind == F_TABULATED:
        k = int(par[off])
        times = off + 1
        coef = times + k
        if not (par[times] < t < par[times + k - 1]):
            out[0] = par[coef + 4 * (k - 1)] if t <= par[times] else par[coef + 4 * (k - 1) + 1]
            out[1], out[2] = 0.0, 0.0
        else:
            lo, hi = 0, k - 1            # par[times + lo] <= t < par[times + hi]
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if par[times + mid] <= t:
                    lo = mid
                else:
                    hi = mid
            s = t - par[times + lo]
            a, b = par[coef + 4 * lo], par[coef + 4 * lo + 1]
            c, d = par[coef + 4 * lo + 2], par[coef + 4 * lo + 3]
            out[0] = a + s * (b + s * (c + s * d))
            out[1] = b + s * (2.0 * c + 3.0 * s * d)
            out[2] = 2.0 * c + 6.0 * s * d
    else:
        user_time_terms(int(par[off]), t, out)


@_jit
def _local_terms(kind, par, fun, f_kind, f_off, f_par, p, t, out, tf):
    """The 18 local terms of a point constraint at world point p (3,) m -> out (18,)."""
    for i in range(18):
        out[i] = 0.0
    if kind == C_ELLIPSE:
        rx, ry = p[0] - par[2], p[1] - par[3]
        out[0] = par[0] * rx * rx + par[1] * ry * ry - 1.0
        out[1], out[2] = 2.0 * par[0] * rx, 2.0 * par[1] * ry
        out[4], out[8] = 2.0 * par[0], 2.0 * par[1]
    elif kind == C_COORDINATE:
        axis = int(par[0])
        time_function(f_kind[fun], f_off[fun], f_par, t, tf)
        out[0] = p[axis] - tf[0]
        out[1 + axis] = 1.0
        out[13], out[17] = -tf[1], -tf[2]
    else:
        user_point_terms(int(par[0]), p[0], p[1], p[2], t, out)


@_jit
def constraint_rows(t, q, q_dot, t_all, s_all, moves, cd, phi, phi_dot, a, kappa, ws):
    """Phi (m,), Phi_dot (m,), A (m, n), kappa (m,) into the given arrays; False when a
    value is not finite.  ws: float scratch of rows_scratch_size(n, n_points)."""
    c_kind, c_point, c_fun, c_par, p_link, p_r, f_kind, f_off, f_par, _, _, c_point_b, \
        _, _, _ = constraint_parts(cd)
    m = c_kind.shape[0]
    n = q.shape[0]
    n_points = p_link.shape[0]
    pos = ws[:3 * n_points].reshape((n_points, 3))
    vel = ws[3 * n_points:6 * n_points].reshape((n_points, 3))
    drift = ws[6 * n_points:9 * n_points].reshape((n_points, 3))
    used = 9 * n_points
    jac = ws[used:used + 3 * n * n_points].reshape((n_points, 3, n))
    used += 3 * n * n_points
    lt = ws[used:used + N_PAIR_TERMS]
    tf = ws[used + N_PAIR_TERMS:used + N_PAIR_TERMS + 3]
    used += N_PAIR_TERMS + 3
    scratch = ws[used:used + POINT_SCRATCH]
    for k in range(n_points):
        point_into(t_all, s_all, moves, q_dot, p_link[k], p_r[k], p_r[k, 3], pos[k], vel[k],
                   jac[k], drift[k], scratch)
    for c in range(m):
        kind = c_kind[c]
        if kind == C_JOINT:
            k = int(c_par[c, 0])
            time_function(f_kind[c_fun[c]], f_off[c_fun[c]], f_par, t, tf)
            phi[c] = q[k] - tf[0]
            for j in range(n):
                a[c, j] = 0.0
            a[c, k] = 1.0
            phi_dot[c] = q_dot[k] - tf[1]
            kappa[c] = -tf[2]
        elif kind >= C_RELATIVE:
            pa, pb = c_point[c], c_point_b[c]
            _pair_terms(kind, c_par[c], c_fun[c], f_kind, f_off, f_par, pos[pa], pos[pb], t,
                        lt, tf)
            _pair_row(c, lt, vel[pa], vel[pb], jac[pa], jac[pb], drift[pa], drift[pb], phi,
                      phi_dot, a, kappa)
        else:
            pt = c_point[c]
            _local_terms(kind, c_par[c], c_fun[c], f_kind, f_off, f_par, pos[pt], t, lt, tf)
            v = vel[pt]
            for j in range(n):
                a[c, j] = lt[1] * jac[pt, 0, j] + lt[2] * jac[pt, 1, j] + lt[3] * jac[pt, 2, j]
            phi[c] = lt[0]
            phi_dot[c] = lt[1] * v[0] + lt[2] * v[1] + lt[3] * v[2] + lt[13]
            quad = 0.0
            for i in range(3):
                for j in range(3):
                    quad += v[i] * lt[4 + 3 * i + j] * v[j]
            kappa[c] = (lt[1] * drift[pt, 0] + lt[2] * drift[pt, 1] + lt[3] * drift[pt, 2]
                        + quad + 2.0 * (lt[14] * v[0] + lt[15] * v[1] + lt[16] * v[2])
                        + lt[17])
        if not (math.isfinite(phi[c]) and math.isfinite(phi_dot[c])
                and math.isfinite(kappa[c])):
            return False
    return True


@_jit
def _pair_terms(kind, par, fun, f_kind, f_off, f_par, sa, sb, t, out, tf):
    """The 51 local terms (N_PAIR_TERMS) of a pair constraint at the world vectors sa, sb
    (3,) -> out; gpme_core.pair_constraints has the formulas.  A distance between
    coinciding origins gives NaN (the caller reports it through the Python path)."""
    for i in range(N_PAIR_TERMS):
        out[i] = 0.0
    if kind == C_USER_PAIR:
        user_pair_terms(int(par[0]), sa[0], sa[1], sa[2], sb[0], sb[1], sb[2], t, out)
        return
    time_function(f_kind[fun], f_off[fun], f_par, t, tf)
    out[43], out[50] = -tf[1], -tf[2]
    if kind == C_RELATIVE:
        axis = int(par[0])
        out[0] = sb[axis] - sa[axis] - tf[0]
        out[1 + axis], out[4 + axis] = -1.0, 1.0
    elif kind == C_DISTANCE:
        dx, dy, dz = sb[0] - sa[0], sb[1] - sa[1], sb[2] - sa[2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not length > 1e-12:
            out[0] = np.nan
            return
        e0, e1, e2 = dx / length, dy / length, dz / length
        out[0] = length - tf[0]
        out[1], out[2], out[3], out[4], out[5], out[6] = -e0, -e1, -e2, e0, e1, e2
        e = (e0, e1, e2)
        for i in range(3):
            for j in range(3):
                p = ((1.0 if i == j else 0.0) - e[i] * e[j]) / length
                out[7 + 6 * i + j] = p
                out[7 + 6 * i + j + 3] = -p
                out[7 + 6 * (i + 3) + j] = -p
                out[7 + 6 * (i + 3) + j + 3] = p
    else:                                   # C_AXIS_DOT
        out[0] = sa[0] * sb[0] + sa[1] * sb[1] + sa[2] * sb[2] - tf[0]
        for i in range(3):
            out[1 + i], out[4 + i] = sb[i], sa[i]
            out[7 + 6 * i + i + 3] = 1.0
            out[7 + 6 * (i + 3) + i] = 1.0


@_jit
def _pair_row(c, terms, va, vb, ja, jb, da, db, phi, phi_dot, a, kappa):
    """Row c of a pair constraint from its 51 local terms and both vectors' velocity
    (3,), Jacobian (3, n) and drift (3,): a = grad^T J, Phi_dot = grad . s_dot + phi_t,
    kappa = grad . d + s_dot^T H s_dot + 2 grad_t . s_dot + phi_tt (s stacked (a, b))."""
    n = ja.shape[1]
    for j in range(n):
        acc = 0.0
        for i in range(3):
            acc += terms[1 + i] * ja[i, j] + terms[4 + i] * jb[i, j]
        a[c, j] = acc
    pd, grad_d, quad, grad_t = terms[43], 0.0, 0.0, 0.0
    for i in range(6):
        vi = va[i] if i < 3 else vb[i - 3]
        di = da[i] if i < 3 else db[i - 3]
        pd += terms[1 + i] * vi
        grad_d += terms[1 + i] * di
        grad_t += terms[44 + i] * vi
        for j in range(6):
            vj = va[j] if j < 3 else vb[j - 3]
            quad += vi * terms[7 + 6 * i + j] * vj
    phi[c] = terms[0]
    phi_dot[c] = pd
    kappa[c] = grad_d + quad + 2.0 * grad_t + terms[50]


@_jit
def rows_scratch_size(n, n_points):
    """Length of the float scratch of :func:`constraint_rows`."""
    return 9 * n_points + 3 * n * n_points + N_PAIR_TERMS + 3 + POINT_SCRATCH


# from this size on the reduced matrix is factorised by LAPACK (blocked, faster); below
# it by the loops here, which cost less than LAPACK's call and copy.  Measured with
# benchmarks.kernel_profile --cholesky: equal at about 24 rows, LAPACK 1.3x faster at 32
# and 2.6x at 152; OpenBLAS's factor steps up at 34 rows, where the loops are up to 1.3x
# faster again until about 48 (no single threshold wins at every size; 24 is kept)
LAPACK_FROM = 24


@_jit
def _cholesky_solve(mat, b, low, x):
    """x (r,) = mat^-1 b for symmetric positive definite mat (r, r), of which only the lower
    triangle is read (both factors, LAPACK's too, read no other); low (r, r) scratch for
    the factor (LAPACK's own from LAPACK_FROM on); False when mat is not positive definite."""
    r = b.shape[0]
    if r >= LAPACK_FROM:
        for j in range(r):
            if not mat[j, j] > 0.0:
                return False
        ok = True
        try:
            low = np.linalg.cholesky(mat)
        except Exception:  # not positive definite
            ok = False
        if not ok:
            return False
    elif not _cholesky_factor(mat, low):
        return False
    for i in range(r):                       # L w = b
        s = b[i]
        for p in range(i):
            s -= low[i, p] * x[p]
        x[i] = s / low[i, i]
    for i in range(r - 1, -1, -1):           # L^T x = w, by rows of L (axpy form)
        x[i] /= low[i, i]
        xi = x[i]
        for p in range(i):
            x[p] -= low[i, p] * xi
    return True


@_jit
def _cholesky_factor(mat, low):
    """Lower Cholesky factor of mat (r, r) into low (its upper part is not used); False when
    mat is not positive definite.  Only mat's lower triangle is read.  (Rows are indexed
    in full, not through views: a view costs a reference count, r^2 / 2 of them here.)"""
    r = mat.shape[0]
    for j in range(r):
        d = mat[j, j]
        for p in range(j):
            d -= low[j, p] * low[j, p]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        low[j, j] = d
        for i in range(j + 1, r):
            s = mat[i, j]
            for p in range(j):
                s -= low[i, p] * low[j, p]
            low[i, j] = s / d
    return True


@_jit
def _invert_small(a_dc, work, inv):
    """inv = a_dc^-1 for a small square matrix, by Gauss-Jordan with partial pivoting;
    work: scratch of the same shape; False when a_dc is singular."""
    k = a_dc.shape[0]
    for i in range(k):
        for j in range(k):
            work[i, j] = a_dc[i, j]
            inv[i, j] = 1.0 if i == j else 0.0
    for col in range(k):
        piv = col
        for r in range(col + 1, k):
            if abs(work[r, col]) > abs(work[piv, col]):
                piv = r
        if work[piv, col] == 0.0:
            return False
        if piv != col:
            for c in range(k):
                work[col, c], work[piv, c] = work[piv, c], work[col, c]
                inv[col, c], inv[piv, c] = inv[piv, c], inv[col, c]
        d = work[col, col]
        for c in range(k):
            work[col, c] /= d
            inv[col, c] /= d
        for r in range(k):
            if r != col:
                f = work[r, col]
                if f != 0.0:
                    for c in range(k):
                        work[r, c] -= f * work[col, c]
                        inv[r, c] -= f * inv[col, c]
    return True


@_jit
def partition_rcond(a, dc, inv):
    """gpme_core.gpme.partition_rcond from A (m, n), dc (m,) and inv = A_dc^-1."""
    m, n = a.shape
    norm_dc, inv_norm, norm_a = 0.0, 0.0, 0.0
    for j in range(m):
        s, si = 0.0, 0.0
        for i in range(m):
            s += abs(a[i, dc[j]])
            si += abs(inv[i, j])
        norm_dc = max(norm_dc, s)
        inv_norm = max(inv_norm, si)
    for j in range(n):
        s = 0.0
        for i in range(m):
            s += abs(a[i, j])
        norm_a = max(norm_a, s)
    if not (norm_dc > 0.0 and inv_norm > 0.0 and norm_a > 0.0 and math.isfinite(inv_norm)):
        return 0.0
    # rcond(A_dc) ||A_dc||_1 / ||A||_1 = 1 / (||A_dc^-1||_1 ||A||_1)
    return 1.0 / (inv_norm * norm_a)


@_jit
def reduced_scratch_size(n, k):
    """Length of the float scratch of :func:`reduced_solve` for n coordinates, k constraints."""
    ni = n - k
    return 3 * k * k + 2 * k * ni + k + n + 2 * ni * ni + 2 * ni


@_jit
def reduced_solve(m_mat, rhs, a, c, ic, dc, switch_below, singular_rcond, q_ddot, lam, ws):
    """(status, partition rcond): q_ddot (n,) and multipliers lam (m,) of the reduced GPME
    (module docstring) for the partition (ic, dc); status SWITCH before solving when the
    partition rcond < switch_below.  ws: float scratch of reduced_scratch_size(n, m)."""
    n = m_mat.shape[0]
    k = dc.shape[0]
    ni = ic.shape[0]
    a_dc = ws[:k * k].reshape((k, k))
    work = ws[k * k:2 * k * k].reshape((k, k))
    inv = ws[2 * k * k:3 * k * k].reshape((k, k))
    used = 3 * k * k
    gam = ws[used:used + k * ni].reshape((k, ni))          # Gamma = -A_dc^-1 A_ic
    used += k * ni
    p_dc = ws[used:used + k]                 # particular solution, dependent part
    used += k
    r = ws[used:used + n]                    # h + Q - M p
    used += n
    x = ws[used:used + k * ni].reshape((k, ni))            # (M N)_d
    used += k * ni
    red = ws[used:used + ni * ni].reshape((ni, ni))        # N^T M N
    used += ni * ni
    low = ws[used:used + ni * ni].reshape((ni, ni))        # its Cholesky factor
    used += ni * ni
    b = ws[used:used + ni]
    z = ws[used + ni:used + 2 * ni]
    for i in range(k):
        for j in range(k):
            a_dc[i, j] = a[i, dc[j]]
    ok = _invert_small(a_dc, work, inv)
    if not ok:
        return (SWITCH if switch_below > 0.0 else SINGULAR_PARTITION), 0.0
    rel = partition_rcond(a, dc, inv)
    if rel < switch_below:
        return SWITCH, rel
    if not rel > singular_rcond:
        return SINGULAR_PARTITION, rel
    for i in range(k):
        for j in range(ni):
            s = 0.0
            for p in range(k):
                s += inv[i, p] * a[p, ic[j]]
            gam[i, j] = -s
    for i in range(k):
        s = 0.0
        for p in range(k):
            s += inv[i, p] * c[p]
        p_dc[i] = s
    for i in range(n):
        r[i] = rhs[i]
        s = 0.0
        for p in range(k):
            s += m_mat[i, dc[p]] * p_dc[p]
        r[i] -= s
    # N^T M N = M_ii + M_id Gamma + Gamma^T (M N)_d, formed on its lower triangle only (the
    # Cholesky factor reads no other): (M N)_d = x, the k rows of M N of the dependent
    # coordinates, first; then each row i of the reduced matrix up to its diagonal.  The
    # inner loops run along contiguous rows (axpy form) so that they vectorise; rows are
    # indexed in full, not through views (a view costs a reference count).
    for p in range(k):
        dp = dc[p]
        for j in range(ni):
            x[p, j] = m_mat[dp, ic[j]]
        for q in range(k):
            f = m_mat[dp, dc[q]]
            for j in range(ni):
                x[p, j] += f * gam[q, j]
    for i in range(ni):
        ii = ic[i]
        for j in range(i + 1):
            red[i, j] = m_mat[ii, ic[j]]
        s = r[ii]
        for p in range(k):
            f = m_mat[ii, dc[p]]
            for j in range(i + 1):
                red[i, j] += f * gam[p, j]
        for p in range(k):
            f = gam[p, i]
            for j in range(i + 1):
                red[i, j] += f * x[p, j]
            s += f * r[dc[p]]
        b[i] = s
    if not _cholesky_solve(red, b, low, z):
        return SINGULAR_REDUCED, rel
    for i in range(ni):
        q_ddot[ic[i]] = z[i]
    for p in range(k):
        s = p_dc[p]
        for j in range(ni):
            s += gam[p, j] * z[j]
        q_ddot[dc[p]] = s
    multipliers_into(m_mat, rhs, q_ddot, inv, dc, lam)
    return OK, rel


# floats of the point springs' scratch in evaluate: two ends' position, velocity, drift (3
# each) and Jacobian (3 x n), the direction's row (n), and point_into's own scratch
SPRING_SCRATCH_PER_N = 7
SPRING_SCRATCH = 18 + POINT_SCRATCH


@_jit
def _point_springs(t_all, s_all, moves, q_dot, p_link, p_r, s_a, s_b, s_par, paper_eq7, rhs,
                   ws):
    """Subtract the point springs' generalized forces (gpme_core.point_springs: elastic
    k (L - L0) and damping c L_dot along e, mapped by e^T (J_a - J_b)) from rhs (n,); the
    damping part twice with paper_eq7, as gpme_core.gpme does.  Returns the power the
    dampers dissipate (W), NaN where a spring's two points meet."""
    n = q_dot.shape[0]
    pa, va, da = ws[0:3], ws[3:6], ws[6:9]
    pb, vb, db = ws[9:12], ws[12:15], ws[15:18]
    ja = ws[18:18 + 3 * n].reshape((3, n))
    jb = ws[18 + 3 * n:18 + 6 * n].reshape((3, n))
    row = ws[18 + 6 * n:18 + 7 * n]
    scratch = ws[18 + 7 * n:18 + 7 * n + POINT_SCRATCH]
    power = 0.0
    for s in range(s_a.shape[0]):
        a, b = s_a[s], s_b[s]
        point_into(t_all, s_all, moves, q_dot, p_link[a], p_r[a], 1.0, pa, va, ja, da, scratch)
        if b >= 0:
            point_into(t_all, s_all, moves, q_dot, p_link[b], p_r[b], 1.0, pb, vb, jb, db,
                       scratch)
        else:
            for i in range(3):
                pb[i], vb[i] = s_par[s, 3 + i], 0.0
                for j in range(n):
                    jb[i, j] = 0.0
        dx, dy, dz = pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not length > 1e-12:
            return np.nan
        ex, ey, ez = dx / length, dy / length, dz / length
        rate = ex * (va[0] - vb[0]) + ey * (va[1] - vb[1]) + ez * (va[2] - vb[2])
        elastic = s_par[s, 0] * (length - s_par[s, 1])
        damper = s_par[s, 2] * rate
        force = elastic + (2.0 * damper if paper_eq7 != 0.0 else damper)
        for j in range(n):
            row[j] = ex * (ja[0, j] - jb[0, j]) + ey * (ja[1, j] - jb[1, j]) \
                + ez * (ja[2, j] - jb[2, j])
            rhs[j] -= force * row[j]
        power += damper * rate
    return power


@_jit
def workspace_size(n, k, n_points):
    """Length of the float workspace of :func:`evaluate` (n coordinates, k constraints,
    n_points distinct constrained points)."""
    return (32 * n + 32 + terms_scratch_size(n) + n * n + 3 * n + 3 + 5 * k + k * n
            + rows_scratch_size(n, n_points) + reduced_scratch_size(n, k)
            + chain_solve_scratch_size(n) + SPRING_SCRATCH_PER_N * n + SPRING_SCRATCH)


@_jit
def free_solve_is_recursive(k, parents, opts):
    """True when :func:`evaluate` solves M q_ddot = rhs by gpme_core.fast.chain_solve (no M
    formed): no constraints (k == 0), a serial chain, and opts[OPT_DENSE_FREE_SOLVE] absent
    or 0; else M is formed and solved densely."""
    if k != 0 or not is_serial(parents):
        return False
    return not (opts.shape[0] > OPT_DENSE_FREE_SOLVE and opts[OPT_DENSE_FREE_SOLVE] != 0.0)


@_jit
def evaluate(t, q, q_dot, md, cd, opts, ic, dc, q_ddot, lam, info, ws):
    """Status of one evaluation at (t s, q (n,), q_dot (n,)); fills q_ddot (n,), lam (m,)
    and info (INFO_SIZE,) = (partition rcond, q_dot.d (W), q_dot.t (W), q_dot.A^T lam (W),
    0).  ws: float workspace of workspace_size(n, m, n_points) (nothing is allocated)."""
    # md read directly rather than through model_parts: each view costs a reference count,
    # and the limits are not needed here
    mats, vecs, gamma, parents, moves = md
    origins, generators, pseudo = mats[0], mats[1], mats[2]
    is_revolute, stiffness, q_ref, damping = vecs[0], vecs[1], vecs[2], vecs[3]
    alpha, beta, paper_eq7, switch_below, singular_rcond = opts[0], opts[1], opts[2], \
        opts[3], opts[4]
    n = q.shape[0]
    k = dc.shape[0]
    n_points = cd[0][1]
    # T, S, chain_into's two work matrices and the world pseudo-inertias at the head of
    # terms_into's scratch: (4, 4) blocks of one reshaped view (a reshape costs a call, a
    # slice of the first axis does not)
    blocks = ws[:16 * (3 * n + 2)].reshape((3 * n + 2, 4, 4))
    t_all = blocks[:n]
    s_all = blocks[n:2 * n]
    chain_into(origins, generators, is_revolute, parents, q, t_all, s_all,
               blocks[2 * n:2 * n + 2])
    used = 32 * n + 32
    size = terms_scratch_size(n)
    terms_scratch = ws[used:used + size]
    used += size
    m_mat = ws[used:used + n * n].reshape((n, n))
    used += n * n
    h = ws[used:used + n]
    g = ws[used + n:used + 2 * n]
    rhs = ws[used + 2 * n:used + 3 * n]
    tf = ws[used + 3 * n:used + 3 * n + 3]
    used += 3 * n + 3
    recursive = free_solve_is_recursive(k, parents, opts)
    terms_into(t_all, s_all, pseudo, gamma, parents, moves, q_dot, m_mat, h, g, terms_scratch,
               -1, not recursive)
    w_diss, w_drive = 0.0, 0.0
    for i in range(n):
        d_i = damping[i] * q_dot[i]
        rhs[i] = h[i] - g[i] - d_i - stiffness[i] * (q[i] - q_ref[i])
        if paper_eq7 != 0.0:
            rhs[i] -= d_i
        w_diss += q_dot[i] * d_i
    if cd[0][3]:                     # drives (their views: only then)
        f_kind, f_off, f_par, d_coord, d_fun = drive_parts(cd)
        for i in range(d_coord.shape[0]):
            time_function(f_kind[d_fun[i]], f_off[d_fun[i]], f_par, t, tf)
            rhs[d_coord[i]] += tf[0]
            w_drive += q_dot[d_coord[i]] * tf[0]
    if cd[0][4]:                     # point springs (constraint_parts: only then)
        _, _, _, _, p_link, p_r, _, _, _, _, _, _, s_a, s_b, s_par = constraint_parts(cd)
        size = SPRING_SCRATCH_PER_N * n + SPRING_SCRATCH
        w_spring = _point_springs(t_all, s_all, moves, q_dot, p_link, p_r, s_a, s_b, s_par,
                                  paper_eq7, rhs, ws[used:used + size])
        if not math.isfinite(w_spring):
            return NOT_FINITE
        w_diss += w_spring
    used += SPRING_SCRATCH_PER_N * n + SPRING_SCRATCH
    info[0], info[1], info[2], info[3], info[4] = 1.0, w_diss, w_drive, 0.0, 0.0
    if not (math.isfinite(w_drive)):
        return NOT_FINITE
    # the constraint machinery's work arrays (below) and chain_solve's scratch after them;
    # a free system takes neither view of the former (a view costs a reference count)
    rows_size = rows_scratch_size(n, n_points)
    reduced_size = reduced_scratch_size(n, k)
    solve_at = used + 5 * k + k * n + rows_size + reduced_size
    if recursive:
        hw = blocks[2 * n + 2:]     # = fast.world_pseudo_inertias(terms_scratch, n)
        ok = chain_solve(s_all, hw, rhs, q_ddot,
                         ws[solve_at:solve_at + chain_solve_scratch_size(n)])
        return OK if ok else SINGULAR_REDUCED
    phi = ws[used:used + k]
    phi_dot = ws[used + k:used + 2 * k]
    kappa = ws[used + 2 * k:used + 3 * k]
    c = ws[used + 3 * k:used + 4 * k]
    used += 5 * k
    a = ws[used:used + k * n].reshape((k, n))
    used += k * n
    rows_scratch = ws[used:used + rows_size]
    used += rows_size
    reduced_scratch = ws[used:used + reduced_size]
    used += reduced_size
    if k == 0:
        low = reduced_scratch[n:n + n * n].reshape((n, n))
        ok = _cholesky_solve(m_mat, rhs, low, q_ddot)
        return OK if ok else SINGULAR_REDUCED
    if not constraint_rows(t, q, q_dot, t_all, s_all, moves, cd, phi, phi_dot, a, kappa,
                           rows_scratch):
        return NOT_FINITE
    for i in range(k):
        c[i] = -kappa[i] - 2.0 * alpha * phi_dot[i] - beta * beta * phi[i]
    status, rel = reduced_solve(m_mat, rhs, a, c, ic, dc, switch_below, singular_rcond,
                                q_ddot, lam, reduced_scratch)
    info[0] = rel
    if status != OK:
        return status
    w_react = 0.0
    for j in range(n):
        s = 0.0
        for i in range(k):
            s += a[i, j] * lam[i]
        w_react += q_dot[j] * s
    info[3] = w_react
    return OK


@_jit
def state_status(y, n, md, limit):
    """DIVERGED, OUT_OF_RANGE or OK for a state y = (q, q_dot, W)."""
    lower, upper = md[1][4], md[1][5]
    for i in range(2 * n):
        if not (math.isfinite(y[i]) and abs(y[i]) <= limit):
            return DIVERGED
    for i in range(n):
        if y[i] < lower[i] or y[i] > upper[i]:
            return OUT_OF_RANGE
    return OK


@_jit
def derivative(t, y, md, cd, opts, ic, dc, dy, lam, info, ws):
    """dy = (q_dot, q_ddot, W rates) of the integrated state y (2 n + 3,); status.
    ws: the workspace of :func:`evaluate`."""
    n = md[1].shape[1]
    status = evaluate(t, y[:n], y[n:2 * n], md, cd, opts, ic, dc, dy[n:2 * n], lam, info, ws)
    _rates(y, dy, info, n)
    return status


@_jit
def _rates(y, dy, info, n):
    """dy's q_dot part from y and its W rates from info: what :func:`evaluate` does not
    fill of :func:`derivative`'s dy."""
    for i in range(n):
        dy[i] = y[n + i]
    dy[2 * n], dy[2 * n + 1], dy[2 * n + 2] = info[1], info[2], info[3]


@_jit
def rk4_advance(t0, y, dt, n_steps, md, cd, opts, ic, dc, fail_y):
    """Classical RK4 from (t0, y) over n_steps steps of dt s, y updated in place.

    Returns (status, steps done, t of the failure): on a failed evaluation y stays at the
    start of the failing step and fail_y holds the state evaluated; on a state that
    diverges or leaves its range, fail_y holds it (y the step before).

    Each stage is :func:`derivative` written out: :func:`evaluate` on views of the state
    and of the stage's slope made once per call (a view costs a reference count, and a
    call layer the copying of its many arguments, per stage)."""
    size = y.shape[0]
    n = (size - N_WORK) // 2
    k1, k2, k3, k4 = np.empty(size), np.empty(size), np.empty(size), np.empty(size)
    stage = np.empty(size)
    lam = np.empty(dc.shape[0])
    info = np.empty(INFO_SIZE)
    ws = np.empty(workspace_size(n, dc.shape[0], cd[0][1]))
    y_q, y_v, stage_q, stage_v = y[:n], y[n:2 * n], stage[:n], stage[n:2 * n]
    k1_a, k2_a, k3_a, k4_a = k1[n:2 * n], k2[n:2 * n], k3[n:2 * n], k4[n:2 * n]
    for step in range(n_steps):
        t = t0 + step * dt
        st = evaluate(t, y_q, y_v, md, cd, opts, ic, dc, k1_a, lam, info, ws)
        if st != OK:
            fail_y[:] = y
            return st, step, t
        _rates(y, k1, info, n)
        for i in range(size):
            stage[i] = y[i] + 0.5 * dt * k1[i]
        st = evaluate(t + 0.5 * dt, stage_q, stage_v, md, cd, opts, ic, dc, k2_a, lam, info,
                      ws)
        if st != OK:
            fail_y[:] = stage
            return st, step, t + 0.5 * dt
        _rates(stage, k2, info, n)
        for i in range(size):
            stage[i] = y[i] + 0.5 * dt * k2[i]
        st = evaluate(t + 0.5 * dt, stage_q, stage_v, md, cd, opts, ic, dc, k3_a, lam, info,
                      ws)
        if st != OK:
            fail_y[:] = stage
            return st, step, t + 0.5 * dt
        _rates(stage, k3, info, n)
        for i in range(size):
            stage[i] = y[i] + dt * k3[i]
        st = evaluate(t + dt, stage_q, stage_v, md, cd, opts, ic, dc, k4_a, lam, info, ws)
        if st != OK:
            fail_y[:] = stage
            return st, step, t + dt
        _rates(stage, k4, info, n)
        for i in range(size):
            stage[i] = y[i] + (dt / 6.0) * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        st = state_status(stage, n, md, opts[5])
        if st != OK:
            fail_y[:] = stage
            return st, step, t + dt
        for i in range(size):
            y[i] = stage[i]
    return OK, n_steps, t0 + n_steps * dt


# ---------------------------------------------------------------- Radau IIA (order 5)
_SQ6 = math.sqrt(6.0)
RADAU_C = np.array([(4.0 - _SQ6) / 10.0, (4.0 + _SQ6) / 10.0, 1.0])
RADAU_A = np.array([
    [(88.0 - 7.0 * _SQ6) / 360.0, (296.0 - 169.0 * _SQ6) / 1800.0, (-2.0 + 3.0 * _SQ6) / 225.0],
    [(296.0 + 169.0 * _SQ6) / 1800.0, (88.0 + 7.0 * _SQ6) / 360.0, (-2.0 - 3.0 * _SQ6) / 225.0],
    [(16.0 - _SQ6) / 36.0, (16.0 + _SQ6) / 36.0, 1.0 / 9.0]])
RADAU_A2 = RADAU_A @ RADAU_A


def _extrapolation_weights():
    """(3, 4): the previous step's velocity polynomial (through v0 at 0 and V_i at c_i,
    in units of the step) evaluated at 1 + c_i: the Newton predictor of the next step."""
    nodes = np.concatenate([[0.0], RADAU_C])
    weights = np.empty((3, 4))
    for i, x in enumerate(1.0 + RADAU_C):
        for j in range(4):
            others = [nodes[k] for k in range(4) if k != j]
            weights[i, j] = np.prod([(x - o) / (nodes[j] - o) for o in others])
    return weights


RADAU_EXTRAPOLATION = _extrapolation_weights()
# radau work arrays' control entries (ctrl (RADAU_CTRL,))
R_JAC_AGE = 0        # steps since the Jacobian was computed (-1: none yet)
R_HAVE_PREV = 1      # 1 when the previous step's stages can predict this one
R_STEP = 2           # the step the Newton matrix was built for
R_NEWTON_TOL = 3     # scaled Newton increment at which the stages count as converged
R_ITERATIONS = 4     # Newton iterations done so far (statistics)
R_JACOBIANS = 5      # Jacobians computed so far
R_EVALUATIONS = 6    # evaluations of the right-hand side so far
RADAU_CTRL = 8
NEWTON_MAX_ITER = 7
NEWTON_SLOW = 3      # more iterations than this: refresh the Jacobian for the next step


@_jit
def _jacobian(t, q, v, md, cd, opts, ic, dc, jq, jv):
    """Forward-difference Jacobians d q_ddot / d q and d q_ddot / d q_dot (n, n); status.
    The unperturbed evaluation may ask for a partition switch (SWITCH, as any evaluation
    of the run); the perturbed ones, a root-eps away, do not."""
    n = q.shape[0]
    k = dc.shape[0]
    base = np.empty(n)
    out = np.empty(n)
    lam = np.empty(k)
    info = np.empty(INFO_SIZE)
    ws = np.empty(workspace_size(n, k, cd[0][1]))
    opts_fd = opts.copy()
    opts_fd[3] = 0.0
    st = evaluate(t, q, v, md, cd, opts, ic, dc, base, lam, info, ws)
    if st != OK:
        return st
    qp = q.copy()
    vp = v.copy()
    root_eps = math.sqrt(2.220446049250313e-16)
    for j in range(n):
        dq = root_eps * max(1.0, abs(q[j]))
        qp[j] = q[j] + dq
        st = evaluate(t, qp, v, md, cd, opts_fd, ic, dc, out, lam, info, ws)
        qp[j] = q[j]
        if st != OK:
            return st
        for i in range(n):
            jq[i, j] = (out[i] - base[i]) / dq
        dv = root_eps * max(1.0, abs(v[j]))
        vp[j] = v[j] + dv
        st = evaluate(t, q, vp, md, cd, opts_fd, ic, dc, out, lam, info, ws)
        vp[j] = v[j]
        if st != OK:
            return st
        for i in range(n):
            jv[i, j] = (out[i] - base[i]) / dv
    return OK


@_jit
def _newton_matrix_inverse(h, jq, jv):
    """(3 n, 3 n) inverse of I - h (A x Jv) - h^2 (A^2 x Jq), the stage equations'
    derivative with respect to the stage velocities; (inverse, ok)."""
    n = jq.shape[0]
    w = np.zeros((3 * n, 3 * n))
    for i in range(3):
        for l in range(3):
            ha, h2a2 = h * RADAU_A[i, l], h * h * RADAU_A2[i, l]
            for r in range(n):
                for s in range(n):
                    w[i * n + r, l * n + s] = -ha * jv[r, s] - h2a2 * jq[r, s]
    for r in range(3 * n):
        w[r, r] += 1.0
    inv = np.empty((3 * n, 3 * n))
    ok = True
    try:
        inv = np.linalg.inv(w)
    except Exception:
        ok = False
    if ok:
        for r in range(3 * n):
            for s in range(3 * n):
                if not math.isfinite(inv[r, s]):
                    ok = False
    return inv, ok


@_jit
def radau_advance(t0, y, h, n_steps, md, cd, opts, ic, dc, work, fail_y):
    """Fixed-step three-stage Radau IIA (order 5, L-stable) from (t0, y) over n_steps steps
    of h s, y = (q, q_dot, W) updated in place.

    Stage equations for the stage velocities V_i (n,) with Q_i = q0 + h sum_j a_ij V_j:
    V_i = v0 + h sum_j a_ij q_ddot(t0 + c_i h, Q_j, V_j); solved by simplified Newton with
    the matrix I - h (A x Jv) - h^2 (A^2 x Jq) (finite-difference Jacobians of q_ddot, kept
    across steps and recomputed when the iteration converges slowly or fails), predictor
    from the previous step's collocation polynomial.  The work integrals use the same
    quadrature (the last row of A).  work = (w_inv (3n, 3n), jq (n, n), jv (n, n),
    v_prev (4, n): v0 and the stage velocities of the last step, ctrl (RADAU_CTRL,)), kept
    by the caller between calls.  Returns (status, steps done, t of the failure) as
    :func:`rk4_advance`."""
    w_inv, jq, jv, v_prev, ctrl = work
    size = y.shape[0]
    n = (size - N_WORK) // 2
    k = dc.shape[0]
    vs = np.empty((3, n))
    qs = np.empty((3, n))
    fs = np.empty((3, n))
    work_rates = np.empty((3, N_WORK))
    predictor = np.empty((3, n))
    res = np.empty(3 * n)
    lam = np.empty(k)
    info = np.empty(INFO_SIZE)
    q_ddot = np.empty(n)
    stage_y = np.empty(size)
    ws = np.empty(workspace_size(n, k, cd[0][1]))
    tol = ctrl[R_NEWTON_TOL]
    for step in range(n_steps):
        t = t0 + step * h
        q0, v0 = y[:n], y[n:2 * n]
        if ctrl[R_HAVE_PREV] != 0.0:
            for i in range(3):
                for r in range(n):
                    predictor[i, r] = (RADAU_EXTRAPOLATION[i, 0] * v_prev[0, r]
                                       + RADAU_EXTRAPOLATION[i, 1] * v_prev[1, r]
                                       + RADAU_EXTRAPOLATION[i, 2] * v_prev[2, r]
                                       + RADAU_EXTRAPOLATION[i, 3] * v_prev[3, r])
        else:
            for i in range(3):
                predictor[i] = v0
        converged = False
        iterations = 0
        for attempt in range(2):
            # R_JAC_AGE: -1 none or stale (recompute now), 0 computed at this step's start,
            # k > 0 computed k steps ago
            rebuild = ctrl[R_STEP] != h
            if ctrl[R_JAC_AGE] < 0.0:
                st = _jacobian(t, q0, v0, md, cd, opts, ic, dc, jq, jv)
                ctrl[R_EVALUATIONS] += 2 * n + 1
                ctrl[R_JACOBIANS] += 1
                if st != OK:
                    fail_y[:] = y
                    return st, step, t
                ctrl[R_JAC_AGE] = 0.0
                rebuild = True
            if rebuild:
                inv, ok = _newton_matrix_inverse(h, jq, jv)
                if not ok:
                    fail_y[:] = y
                    return NEWTON_FAILED, step, t
                w_inv[:, :] = inv
                ctrl[R_STEP] = h
            vs[:, :] = predictor
            previous = 0.0
            for it in range(NEWTON_MAX_ITER):
                iterations = it + 1
                for i in range(3):
                    for r in range(n):
                        qs[i, r] = q0[r] + h * (RADAU_A[i, 0] * vs[0, r] + RADAU_A[i, 1] * vs[1, r]
                                                + RADAU_A[i, 2] * vs[2, r])
                    st = evaluate(t + RADAU_C[i] * h, qs[i], vs[i], md, cd, opts, ic, dc,
                                  q_ddot, lam, info, ws)
                    ctrl[R_EVALUATIONS] += 1
                    if st != OK:
                        stage_y[:n] = qs[i]
                        stage_y[n:2 * n] = vs[i]
                        stage_y[2 * n:] = y[2 * n:]
                        fail_y[:] = stage_y
                        return st, step, t + RADAU_C[i] * h
                    fs[i] = q_ddot
                    work_rates[i, 0], work_rates[i, 1], work_rates[i, 2] = info[1], info[2], info[3]
                for i in range(3):
                    for r in range(n):
                        res[i * n + r] = vs[i, r] - v0[r] - h * (
                            RADAU_A[i, 0] * fs[0, r] + RADAU_A[i, 1] * fs[1, r]
                            + RADAU_A[i, 2] * fs[2, r])
                norm = 0.0
                for row in range(3 * n):
                    s = 0.0
                    for col in range(3 * n):
                        s -= w_inv[row, col] * res[col]
                    i, r = row // n, row % n
                    vs[i, r] += s
                    norm = max(norm, abs(s) / (1.0 + abs(vs[i, r])))
                if not math.isfinite(norm):
                    break
                if norm <= tol:
                    converged = True
                    break
                if it > 0 and norm > 0.9 * previous:
                    break                    # not contracting
                previous = norm
            ctrl[R_ITERATIONS] += iterations
            if converged:
                break
            if ctrl[R_JAC_AGE] == 0.0:
                break                        # fresh Jacobian: nothing left to try
            ctrl[R_JAC_AGE] = -1.0           # retry with a new one
        if not converged:
            fail_y[:] = y
            return NEWTON_FAILED, step, t
        for r in range(n):
            stage_y[r] = q0[r] + h * (RADAU_A[2, 0] * vs[0, r] + RADAU_A[2, 1] * vs[1, r]
                                      + RADAU_A[2, 2] * vs[2, r])
            stage_y[n + r] = vs[2, r]
        for j in range(N_WORK):
            stage_y[2 * n + j] = y[2 * n + j] + h * (RADAU_A[2, 0] * work_rates[0, j]
                                                     + RADAU_A[2, 1] * work_rates[1, j]
                                                     + RADAU_A[2, 2] * work_rates[2, j])
        st = state_status(stage_y, n, md, opts[5])
        if st != OK:
            fail_y[:] = stage_y
            return st, step, t + h
        v_prev[0] = v0
        for i in range(3):
            v_prev[i + 1] = vs[i]
        ctrl[R_HAVE_PREV] = 1.0
        y[:] = stage_y
        ctrl[R_JAC_AGE] = -1.0 if iterations > NEWTON_SLOW else ctrl[R_JAC_AGE] + 1.0
    return OK, n_steps, t0 + n_steps * h

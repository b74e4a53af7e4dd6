"""The test set's own equations of Andrews' squeezing mechanism, written from its
formulas (Test Set for IVP Solvers, problem "andrews": mass matrix, forces and the six
loop equations in the angles beta, Theta, gamma, Phi, delta, Omega, epsilon) with no gpme
code: the independent side of tests/test_andrews.py and benchmarks/closed_loops.py.  Parameters and order from
gpme_examples.andrews (numbers only)."""
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from gpme_examples import andrews as A

_Q = sp.symbols("beta Theta gamma Phi delta Omega epsilon", real=True)
_V = sp.symbols("v0:7", real=True)


def mass_and_forces(y, yd):
    """(M (7, 7), f (7,)) of the test set at angles y (rad) and rates yd (rad/s), its
    order: M y_ddot = f - G^T lambda."""
    be, th, ga, ph, de, om, ep = y
    bep, thp, gap, php, dep, omp, epp = yd
    e4, z6 = A.E - A.EA, A.ZF - A.FA
    m = np.zeros((7, 7))
    m[0, 0] = A.M1 * A.RA ** 2 + A.M2 * (A.RR ** 2 - 2 * A.DA * A.RR * np.cos(th) + A.DA ** 2) \
        + A.I1 + A.I2
    m[1, 0] = A.M2 * (A.DA ** 2 - A.DA * A.RR * np.cos(th)) + A.I2
    m[1, 1] = A.M2 * A.DA ** 2 + A.I2
    m[2, 2] = A.M3 * (A.SA ** 2 + A.SB ** 2) + A.I3
    m[3, 3] = A.M4 * e4 ** 2 + A.I4
    m[4, 3] = A.M4 * (e4 ** 2 + A.ZT * e4 * np.sin(ph)) + A.I4
    m[4, 4] = A.M4 * (A.ZT ** 2 + 2 * A.ZT * e4 * np.sin(ph) + e4 ** 2) \
        + A.M5 * (A.TA ** 2 + A.TB ** 2) + A.I4 + A.I5
    m[5, 5] = A.M6 * z6 ** 2 + A.I6
    m[6, 5] = A.M6 * (z6 ** 2 - A.U * z6 * np.sin(om)) + A.I6
    m[6, 6] = A.M6 * (z6 ** 2 - 2 * A.U * z6 * np.sin(om) + A.U ** 2) \
        + A.M7 * (A.UA ** 2 + A.UB ** 2) + A.I6 + A.I7
    m = np.tril(m) + np.tril(m, -1).T
    xd = A.SD * np.cos(ga) + A.SC * np.sin(ga) + A.XB
    yd_ = A.SD * np.sin(ga) - A.SC * np.cos(ga) + A.YB
    length = np.hypot(xd - A.XC, yd_ - A.YC)
    force = -A.C0 * (length - A.L0) / length
    fx, fy = force * (xd - A.XC), force * (yd_ - A.YC)
    f = np.array([
        A.MOM - A.M2 * A.DA * A.RR * thp * (thp + 2 * bep) * np.sin(th),
        A.M2 * A.DA * A.RR * bep ** 2 * np.sin(th),
        fx * (A.SC * np.cos(ga) - A.SD * np.sin(ga)) + fy * (A.SD * np.cos(ga) + A.SC * np.sin(ga)),
        A.M4 * A.ZT * e4 * dep ** 2 * np.cos(ph),
        -A.M4 * A.ZT * e4 * php * (php + 2 * dep) * np.cos(ph),
        -A.M6 * A.U * z6 * epp ** 2 * np.cos(om),
        A.M6 * A.U * z6 * omp * (omp + 2 * epp) * np.cos(om)])
    return m, f


def _loops():
    be, th, ga, ph, de, om, ep = _Q
    tip_x = A.RR * sp.cos(be) - A.D * sp.cos(be + th)
    tip_y = A.RR * sp.sin(be) - A.D * sp.sin(be + th)
    return sp.Matrix([tip_x - A.SS * sp.sin(ga) - A.XB,
                      tip_y + A.SS * sp.cos(ga) - A.YB,
                      tip_x - A.E * sp.sin(ph + de) - A.ZT * sp.cos(de) - A.XA,
                      tip_y + A.E * sp.cos(ph + de) - A.ZT * sp.sin(de) - A.YA,
                      tip_x - A.ZF * sp.cos(om + ep) - A.U * sp.sin(ep) - A.XA,
                      tip_y - A.ZF * sp.sin(om + ep) + A.U * sp.cos(ep) - A.YA])


_G = _loops()
_JAC = _G.jacobian(_Q)
_GAMMA = (_JAC * sp.Matrix(_V)).jacobian(_Q) * sp.Matrix(_V)   # d(G) / dt y_dot
loop_values = sp.lambdify((_Q,), _G, "numpy")
loop_jacobian = sp.lambdify((_Q,), _JAC, "numpy")
_gamma = sp.lambdify((_Q, _V), _GAMMA, "numpy")


def accelerations(y, yd):
    """(y_ddot (7,), lambda (6,)) of the index-1 system [M G^T; G 0] [y_ddot; lambda] =
    [f; -G_dot y_dot], test set order and sign."""
    m, f = mass_and_forces(y, yd)
    g = np.array(loop_jacobian(y), dtype=float)
    k = np.block([[m, g.T], [g, np.zeros((6, 6))]])
    sol = np.linalg.solve(k, np.concatenate([f, -np.array(_gamma(y, yd), float).ravel()]))
    return sol[:7], sol[7:]


def solve(t_end=A.T_END, rtol=1e-13, atol=1e-14):
    """(y (7,), y_dot (7,)) at t_end from the test set's start, by scipy's DOP853 on the
    index-1 system (over 0.03 s its drift off the loops stays at the tolerance's level)."""
    y0 = np.concatenate([A.START, np.zeros(7)])
    r = solve_ivp(lambda t, x: np.concatenate([x[7:], accelerations(x[:7], x[7:])[0]]),
                  (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=atol)
    if not r.success:
        raise RuntimeError(r.message)
    return r.y[:7, -1], r.y[7:, -1]

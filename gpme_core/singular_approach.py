"""Why a run failed when an expression of it approached a pole or a domain edge: the
expression, the singular set and the time it is reached, for the message of a run that
diverged, left a joint range or stopped on a value that is not finite.

A pole of a programme or constraint met mid-run (``0.01/(t - 1)`` at t = 1 s) asks the
mechanism for unbounded accelerations: the run diverges a few steps before the pole,
where the stiffness it causes is also above the RK4 step's stability limit, so the
failure looks like an unstable step, and every smaller step fails a little later.  Before
a failure is blamed on the step, :func:`approach` looks at the last recorded state for an
expression that is running into its singular set (expression_checks.singular_parts: the
argument w of a sqrt, log, division, ... whose zero bounds where it is smooth):

- w is not finite there or is 0, or
- w has come at least :data:`CLOSER` times closer to 0 (relative to the size of its
  terms, |w| / scale) than at the start of the run, and
  - w depends on t alone (a programmed pole) and has a zero within three times its
    present time-to-zero |w / (dw/dt)| before or after t (a pole the steps stepped over
    counts: the failure often comes a few steps after it); its time is found by bisection
    (or, for an even zero as of a square, by minimising |w|), or
  - w is approaching 0 (w dw/dt < 0) and reaches it within the rest of the run at its
    present rate (that time is given).
"""
import math
from typing import Optional, Sequence

import numpy as np
import sympy as sp
from scipy.optimize import brentq, minimize_scalar

from .constraints import SympyPointConstraint
from .expression_checks import singular_parts, term_scale
from .kinematics import chain_kinematics, point_kinematics
from .time_functions import SympyTimeFunction

# |w| relative to its largest value near the zero below which an even zero (a square's) is
# taken as reached: the bounded search finds it to ~1e-12 s, w to its square
_ZERO = 1e-12
CLOSER = 10.0
"""How many times closer to its singular set (|w| / scale) an expression must have come
since the start of the run to be named as the cause: an expression that starts near its
set and stays there is not running into it."""


def approach(system, t: float, y: np.ndarray, y0: np.ndarray, t_end: float) -> Optional[str]:
    """None, or a sentence naming the expression of ``system`` (a ProgrammedMotion) whose
    singular set the run is reaching at the state ``y`` (q, q_dot first) at t s, from the
    start ``y0`` at t = 0; the closest in time when there are several.  t_end: s, the run's
    end (a set reached after it is not the cause)."""
    n = system.model.n_coordinates
    found = []
    for who, text, expr, symbols, point in _expressions(system):
        now = _state(system.model, point, y[:n], y[n:2 * n], t)
        start = _state(system.model, point, y0[:n], y0[n:2 * n], 0.0)
        for where, w in singular_parts(expr):
            hit = _reaching(w, symbols, now, start, t, t_end)
            if hit is not None:
                found.append((hit[0], who, text, where, hit[1]))
    if not found:
        return None
    t_star, who, text, where, detail = min(found, key=lambda f: f[0])
    return (f"{who} ({text}) runs into its singular set, {where}, reached at t = "
            f"{t_star:.6g} s ({detail}): a pole or domain edge, where the motion it programs "
            "has no finite second derivative and no step size helps; keep the motion away "
            "from it or write a form that is smooth along the motion")


def _expressions(system):
    """(who, expression text, expression, symbols, point) of each SymPy expression of the
    constraints, programmes and drives: point is (link, r_local) for a point constraint,
    else None (a function of t alone)."""
    for spec, bound in zip(system.constraint_specs, system.bound):
        if isinstance(spec, SympyPointConstraint):
            yield (f"constraint {spec.name!r}", f"phi = {spec.expr}", spec.expr, spec.symbols,
                   (bound.link, bound.r_local))
        fn = getattr(spec, "function", None)
        if isinstance(fn, SympyTimeFunction):
            yield (f"programme {spec.name!r}", f"f(t) = {fn.expr}", fn.expr, (fn.t_symbol,),
                   None)
    for d in system.model.drives:
        fn = d.function
        if isinstance(fn, SympyTimeFunction):
            yield f"drive on {d.joint!r}", f"f(t) = {fn.expr}", fn.expr, (fn.t_symbol,), None


def _state(model, point, q, q_dot, t):
    """(values of the symbols (x, y, z, t) or (t,), their rates) at a state."""
    if point is None:
        return np.array([t]), np.array([1.0])
    kin = chain_kinematics(model, q)
    pk = point_kinematics(model, kin, q_dot, point[0], point[1])
    return (np.append(pk.position, t), np.append(pk.velocity, 1.0))


def _reaching(w: sp.Expr, symbols: Sequence[sp.Symbol], now, start, t: float,
              t_end: float) -> Optional[tuple]:
    """(time, words) when ``w`` reaches 0 as described in the module docstring, else None."""
    args = tuple(symbols)
    f = sp.lambdify(args, [w, term_scale(w)] + [sp.diff(w, s) for s in args], "math")
    try:
        values = f(*now[0])
        v0, s0 = f(*start[0])[:2]
    except (ArithmeticError, ValueError, TypeError):
        return t, f"{w} cannot be evaluated at t = {t:.6g} s"
    value, scale = values[0], values[1]
    rate = float(np.dot(values[2:], now[1]))
    if not (math.isfinite(value) and math.isfinite(rate)) or value == 0.0:
        return t, f"{w} = {value:.3g} at the last recorded state, t = {t:.6g} s"
    distance, distance0 = abs(value) / scale, abs(v0) / max(s0, 1e-300)
    if not (distance * CLOSER <= distance0 and rate != 0.0):
        return None
    closer = (f"{w} = {value:.3g} at the last recorded state, t = {t:.6g} s, "
              f"{distance0 / max(distance, 1e-300):.3g} times closer to 0 relative to its "
              "terms than at the start")
    reach = abs(value / rate)                # time to 0 at the present rate
    if w.free_symbols <= {args[-1]}:        # a function of time alone: its zero near t
        position = tuple(now[0][:-1])
        t_star = _zero_in_time(lambda s: f(*position, s)[0], max(t - 3.0 * reach, 0.0),
                               min(t + 3.0 * reach, t_end))
        return None if t_star is None else (t_star, closer)
    if not value * rate < 0.0 or t + reach > t_end:
        return None                          # moving away, or reached after the run
    return t + reach, closer + " (reached at its present rate of approach)"


def _zero_in_time(w, lo: float, hi: float) -> Optional[float]:
    """The first zero of w(s) in [lo, hi]: by bisection where w changes sign on a grid,
    else (an even zero, as of a square) where |w| is smallest on the grid, refined between
    its neighbours, if it is zero there to round-off; None when there is none."""
    grid = np.linspace(lo, hi, 97)
    try:
        values = np.array([w(s) for s in grid], dtype=float)
    except (ArithmeticError, ValueError, TypeError):
        return None
    for a, b, va, vb in zip(grid, grid[1:], values, values[1:]):
        if va == 0.0:
            return float(a)
        if math.isfinite(va) and math.isfinite(vb) and va * vb < 0.0:
            return float(brentq(w, a, b, xtol=1e-12))
    if not np.isfinite(values).any():
        return None
    k = int(np.nanargmin(np.abs(values)))
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    best = minimize_scalar(lambda s: abs(w(s)), bounds=(a, b), method="bounded",
                           options={"xatol": 1e-12})
    size = float(np.nanmax(np.abs(values)))
    return float(best.x) if best.success and abs(best.fun) <= _ZERO * size else None

"""Whether the constraint and programme expressions of a run are smooth where the run went.

An expression given by a user (gpme_core.constraints.SympyPointConstraint phi(x, y, z, t),
gpme_core.pair_constraints.SympyPairConstraint phi(x_a, ..., z_b, t) of two frames,
gpme_core.time_functions.SympyTimeFunction f(t) of a programme) is accepted when its
functions are smooth on part of the line (sqrt, log, division, ...): expression_checks
cannot know where a run will go.  ``sqrt((z - 0.3)**2)`` is |z - 0.3|: accepted, and a run
holding z at 0.3 sits on its kink.  :func:`check_run` looks at a finished run's samples
(t, and the world position of each constraint's frame) for two signs that the run met a
place where an expression is not smooth:

1. **A kink between two samples.**  Along the straight segment between samples k and k+1
   in (x, y, z, t), with Delta the step, g'(s) = G . Delta and g''(s) = Delta^T H Delta
   (G, H: the generated gradient and Hessian in (x, y, z, t)).  For a smooth function the
   change of the first derivative equals the trapezoid of the second to fourth order:

       r = (G_1 - G_0) . Delta - (Delta^T H_0 Delta + Delta^T H_1 Delta) / 2 = -g''''/12

   which falls as |Delta|^4; where the gradient jumps (a kink) r is the jump itself, of
   the size of the first derivative whatever the sampling.  The measure is |r| over the
   size of the terms it is made of (|g'_0| + |g'_1| + |g''_0| + |g''_1|, plus their
   round-off), which falls as |Delta|^3 for a smooth function and stays at the jump's
   fraction of the slope for a kink; the run fails the check when it exceeds
   :data:`KINK_TOL`.
2. **A singular set reached.**  Each part smooth only on part of the line has an argument
   w whose zero bounds that set (expression_checks.singular_parts: sqrt(u) -> u, 1/u -> u,
   ...).  The run reaches the set where |w| <= :data:`REACH_TOL` x the sum of the sizes of
   w's terms (|w| is zero within the accuracy the run holds positions to), or where w
   changes sign between two samples (a pole or a domain edge stepped over).

Programmes are checked on f(t) alone (p[axis] - f(t) and q_k - f(t) are linear in the
coordinates).  Constraints and programmes of other kinds (EllipseConstraint, Cosine,
QuinticRamp, ...) are smooth by construction and not checked; drives are not checked
(the GPME needs only their value).
"""
import math
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np
import pandas as pd
import sympy as sp

from .constraints import CoordinateProgramme, JointProgramme, SympyPointConstraint
from .pair_constraints import SympyPairConstraint
from .expression_checks import evaluate_along, singular_parts, term_scale
from .time_functions import SympyTimeFunction

KINK_TOL = 0.1
"""Largest accepted kink measure (see the module docstring).  A smooth function sampled so
that it varies little between samples measures (|Delta| / R)^3 / 12 for a feature size R
(1e-6 and below on the repository's models at their output spacing); a kink measures
the fraction of the first derivative that jumps, 1 for |u| crossed head-on.  0.1: a jump
of a tenth of the slope, or a function whose fourth derivative over one sample step
matches its first: not resolved by the run's samples either way."""
REACH_TOL = 1e-8
"""|w| / (sum of |terms of w|) at or below which the run is on w's singular set: the run
holds its constraints to 1e-8 (crosscheck.run_checks.PHI_TOL, m), so a relative distance
below it cannot be told from zero along the motion."""
# round-off of the kink residual: a few float64 rounding errors of each term it adds
_ROUNDOFF = 64.0 * np.finfo(float).eps


@dataclass(frozen=True)
class SmoothnessCheck:
    """The smoothness of one expression over one run.

    who        : "constraint 'height'" or "programme 'Phi_yaw' (yaw = f(t))"
    expression : "phi = sqrt((z - 0.3)**2)" or "f(t) = 0.8*sin(pi*t)"
    kink       : largest kink measure over the run's steps (0 for a linear expression;
                 inf where a sample's derivatives are not finite)
    kink_t     : s, start of the step where it is (nan for a run of one sample)
    reached    : None, or the singular set reached, in words with its time and values
    reached_t  : s, the first time a singular set is reached (nan when none is)
    """
    who: str
    expression: str
    kink: float
    kink_t: float
    reached: Optional[str]
    reached_t: float

    @property
    def smooth(self) -> bool:
        """True when no kink above KINK_TOL and no singular set was met."""
        return self.reached is None and self.kink <= KINK_TOL

    @property
    def t(self) -> float:
        """s, where the check looks: the first failure, else the largest kink measure."""
        if self.reached is not None and not (self.kink > KINK_TOL and
                                             self.kink_t < self.reached_t):
            return self.reached_t
        return self.kink_t

    def describe(self) -> str:
        """One sentence naming the expression: where it is not smooth, or how far from a
        kink it stayed."""
        return f"{self.who}: {self.finding()}"

    def finding(self) -> str:
        """:meth:`describe` without the name: '<expression> is not smooth where the run
        goes: <kink and time>; <singular set reached and time>; ...'."""
        if self.smooth:
            return (f"{self.expression} smooth along the run (largest kink measure "
                    f"{self.kink:.2g} at t = {self.kink_t:.4f} s, tolerance {KINK_TOL:g})")
        parts = []
        if self.kink > KINK_TOL:
            parts.append(f"its gradient jumps between t = {self.kink_t:.4f} s and the next "
                         f"sample (the change of its first derivative differs from its "
                         f"second derivative's by {self.kink:.2g} of their size; smooth: "
                         f"<= {KINK_TOL:g})")
        if self.reached is not None:
            parts.append(self.reached)
        return (f"{self.expression} is not smooth where the run goes: " + "; ".join(parts)
                + "; the GPME needs its second derivative along the motion: write a smooth "
                "form (e.g. sqrt(u**2 + eps**2) for |u|)")


def check_run(system, df: pd.DataFrame) -> list:
    """[SmoothnessCheck, ...], one per SymPy expression of ``system``'s constraints and
    programmes, over the run ``df`` (gpme_core.integrate.simulate of ``system``: columns
    t and x_<frame>, y_<frame>, z_<frame>)."""
    times = df["t"].to_numpy(dtype=float)
    out = []
    for spec in system.constraint_specs:
        frames = ((spec.frame,) if isinstance(spec, SympyPointConstraint) else
                  (spec.frame_a, spec.frame_b) if isinstance(spec, SympyPairConstraint)
                  else ())
        if frames:
            points = df[[f"{a}_{f}" for f in frames for a in "xyz"]].to_numpy(dtype=float)
            gradient, hessian = _space_time(spec.terms_along(points, times), points.shape[1])
            out.append(_check(f"constraint {spec.name!r}", f"phi = {spec.expr}", spec.expr,
                              spec.symbols, np.column_stack([points, times]), gradient,
                              hessian))
        elif isinstance(spec, (JointProgramme, CoordinateProgramme)) and isinstance(
                spec.function, SympyTimeFunction):
            fn = spec.function
            what = (spec.coordinate if isinstance(spec, JointProgramme) else
                    f"{'xyz'[spec.axis]} of frame {spec.frame!r}")
            values = fn.derivatives_along(times)
            out.append(_check(f"programme {spec.name!r} ({what} = f(t))",
                              f"f(t) = {fn.expr}", fn.expr, (fn.t_symbol,), times[:, None],
                              values[:, 1:2], values[:, 2].reshape(-1, 1, 1)))
    return out


def _space_time(terms: np.ndarray, k: int) -> tuple:
    """(gradient (s, k + 1), Hessian (s, k + 1, k + 1)) in (coordinates, t) from the local
    terms (s, ...) of an expression of k world coordinates, laid out as (phi, grad (k),
    Hessian (k x k), phi_t, grad_t (k), phi_tt) (SympyPointConstraint: k = 3,
    SympyPairConstraint: k = 6)."""
    hess_end = 1 + k + k * k
    gradient = np.column_stack([terms[:, 1:1 + k], terms[:, hess_end]])
    hessian = np.empty((len(terms), k + 1, k + 1))
    hessian[:, :k, :k] = terms[:, 1 + k:hess_end].reshape(-1, k, k)
    hessian[:, :k, k] = hessian[:, k, :k] = terms[:, hess_end + 1:hess_end + 1 + k]
    hessian[:, k, k] = terms[:, hess_end + 1 + k]
    return gradient, hessian


def kink_measures(args: np.ndarray, gradient: np.ndarray, hessian: np.ndarray) -> np.ndarray:
    """(k - 1,) kink measure of each step between k samples.

    args     : (k, d) sample points (x, y, z, t or t alone; m and s)
    gradient : (k, d) the expression's gradient there; hessian : (k, d, d)
    A non-finite derivative at either end gives inf."""
    delta = np.diff(args, axis=0)
    g0, g1 = gradient[:-1], gradient[1:]
    h0, h1 = hessian[:-1], hessian[1:]
    d0, d1 = np.sum(g0 * delta, axis=1), np.sum(g1 * delta, axis=1)
    c0 = np.einsum("ki,kij,kj->k", delta, h0, delta)
    c1 = np.einsum("ki,kij,kj->k", delta, h1, delta)
    r = (d1 - d0) - 0.5 * (c0 + c1)
    a = np.abs(delta)
    floor = _ROUNDOFF * (np.sum((np.abs(g0) + np.abs(g1)) * a, axis=1)
                         + np.einsum("ki,kij,kj->k", a, np.abs(h0) + np.abs(h1), a))
    size = np.abs(d0) + np.abs(d1) + np.abs(c0) + np.abs(c1) + floor
    with np.errstate(invalid="ignore", divide="ignore"):
        measure = np.where(size > 0, np.abs(r) / np.where(size > 0, size, 1.0), 0.0)
    measure[~np.isfinite(measure)] = np.inf
    return measure


def _check(who: str, expression: str, expr: sp.Expr, symbols: Sequence[sp.Symbol],
           args: np.ndarray, gradient: np.ndarray, hessian: np.ndarray) -> SmoothnessCheck:
    times = args[:, -1]
    kink, kink_t = 0.0, math.nan
    if len(times) > 1:
        measures = kink_measures(args, gradient, hessian)
        k = int(np.argmax(measures))
        kink, kink_t = float(measures[k]), float(times[k])
    reached, reached_t = _reached(expr, symbols, args)
    return SmoothnessCheck(who, expression, kink, kink_t, reached, reached_t)


def _reached(expr: sp.Expr, symbols: Sequence[sp.Symbol], args: np.ndarray) -> tuple:
    """(words, t) of the first singular set of ``expr`` the samples reach, else (None,
    nan)."""
    times = args[:, -1]
    first, words = math.inf, None
    for where, w in singular_parts(expr):
        values = evaluate_along(sp.lambdify(tuple(symbols), [w, term_scale(w)], "numpy"),
                                [args[:, i] for i in range(args.shape[1])], 2)
        w_k, scale = values[:, 0], values[:, 1]
        with np.errstate(invalid="ignore"):
            on = np.flatnonzero(~(np.abs(w_k) > REACH_TOL * scale))
            crossed = np.flatnonzero(w_k[:-1] * w_k[1:] < 0.0)
        if on.size and times[on[0]] < first:
            k = on[0]
            first = times[k]
            words = (f"{where} is reached at t = {times[k]:.4f} s ({w} = {w_k[k]:.3g}, "
                     f"zero within {REACH_TOL:g} of its terms' size {scale[k]:.3g})")
        if crossed.size and times[crossed[0]] < first:
            k = crossed[0]
            first = times[k]
            words = (f"{where} is crossed between t = {times[k]:.4f} s and "
                     f"{times[k + 1]:.4f} s ({w} goes from {w_k[k]:.3g} to {w_k[k + 1]:.3g})")
    return words, (first if words is not None else math.nan)

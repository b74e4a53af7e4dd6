"""Programmed constraints between two frames of the model: loop closures, two arms holding
one object, one link programmed relative to another.

A *pair constraint* is a scalar phi(s, t) = 0 of the stacked world vectors s = (s_a, s_b)
(6,) of two frames a and b of the model (gpme_core.model.Frame; each fixed on its link):
s_a is frame a's origin (m) or one of its unit axes, turned into the world frame, and s_b
the same of frame b.  With the vector kinematics of gpme_core.kinematics (s_dot = J
q_dot, s_ddot = J q_ddot + d, J (6, n) and d (6,) stacked from both frames, a direction
having homogeneous coordinate 0 so that only the rotations move it):

    a     = grad(phi)^T J                                    (the Jacobian row)
    Phi_dot = grad . s_dot + phi_t
    kappa = grad . d + s_dot^T Hess(phi) s_dot + 2 grad(phi_t) . s_dot + phi_tt

(gpme_core.constraints has the same for one point; here s has six entries).  Kinds:

* :class:`RelativeCoordinate` -- (p_b - p_a)[axis] - f(t): the world x, y or z of b's
  origin relative to a's follows f; with f = 0 on all three axes (:func:`coincident`) the
  origins coincide (a spherical joint closing a loop: 3 rows);
* :class:`Distance` -- |p_b - p_a| - f(t): a massless rod of programmed length (1 row);
* :class:`AxisAlignment` -- (R_a e_i) . (R_b e_j) - f(t): the cosine of the angle between
  axis i of a and axis j of b; with f = 0 for (y, z), (z, x), (x, y) (:func:`aligned`) the
  frames have the same orientation (Haug's three dot-1 conditions; with :func:`coincident`
  a weld, :func:`weld`).  No Euler angles: the rows are smooth everywhere; they are
  independent near the aligned orientation and lose rank only at quarter turns away from
  it, which a constraint that holds never reaches;
* :class:`SympyPairConstraint` -- any phi(x_a, y_a, z_a, x_b, y_b, z_b, t) written in
  SymPy (the origins' world coordinates, m, and t, s), e.g. ``x_b - x_a - 0.4``.

Frames a and b may sit on any two links of a tree (or the same chain); the joints that move
neither do not enter the row.  Redundant loop rows (a planar loop closed in 3D) make the
Jacobian rank deficient; gpme_core.constraint_rank names them.
"""
import math

import numpy as np
import sympy as sp

from . import expression_checks as checks
from .errors import ConstraintError, ModelError
from .kinematics import vector_kinematics
from .time_functions import Constant, TimeFunction

AXIS_NAMES = ("x", "y", "z")
POINT, DIRECTION = 1.0, 0.0       # homogeneous coordinate of an origin and of an axis
PAIR_SYMBOL_NAMES = ("x_a", "y_a", "z_a", "x_b", "y_b", "z_b", "t")
_ZERO6 = np.zeros(6)
_ZERO66 = np.zeros((6, 6))


def _axis_index(axis, label):
    """0, 1, 2 from 0/1/2 or 'x'/'y'/'z'; ModelError otherwise."""
    if axis in (0, 1, 2):
        return int(axis)
    if isinstance(axis, str) and axis in AXIS_NAMES:
        return AXIS_NAMES.index(axis)
    raise ModelError(f"{label}: axis must be 'x', 'y' or 'z' (or 0, 1, 2), got {axis!r}")


def _time_function(function, label):
    """A TimeFunction from a TimeFunction or a number (a constant, m or rad)."""
    if isinstance(function, TimeFunction):
        return function
    try:
        value = float(function)
    except (TypeError, ValueError):
        raise ModelError(f"{label}: the programme must be a number or a TimeFunction with "
                         f"value, rate and acceleration, got {type(function).__name__}") \
            from None
    return Constant(value)


class PairConstraint:
    """Base class: phi(s_a, s_b, t) on two frames.  Subclasses set ``vectors`` = ((local
    vector (3,), homogeneous w) of frame a, same of frame b): w = 1 and (0, 0, 0) for the
    origin, w = 0 and a unit axis for a direction; and implement :meth:`local_terms`."""

    name = "Phi"
    frame_a = frame_b = ""
    vectors = (((0.0, 0.0, 0.0), POINT), ((0.0, 0.0, 0.0), POINT))

    def local_terms(self, s, t):
        """(phi, grad (6,), Hessian (6, 6), phi_t, grad_t (6,), phi_tt) at the stacked world
        vectors s (6,) and time t s."""
        raise NotImplementedError

    def describe(self):
        """One line for messages and reports."""
        return f"{type(self).__name__} between frames {self.frame_a!r} and {self.frame_b!r}"

    def bind(self, model):
        ends = []
        for frame, (local, w) in zip((self.frame_a, self.frame_b), self.vectors):
            fr = model.frame(frame)
            # the vector in the link frame: the frame's origin, or its axis turned by the
            # frame's rotation (a direction does not take the frame's translation)
            vec = fr.transform @ np.append(np.asarray(local, dtype=float), w)
            ends.append((fr.link_index, tuple(float(v) for v in vec[:3]), float(w)))
        return _BoundPairConstraint(self, ends)


class RelativeCoordinate(PairConstraint):
    """(p_b - p_a)[axis] - f(t) = 0: world coordinate ``axis`` of frame b's origin relative
    to frame a's follows f (m; a number for a constant offset)."""

    def __init__(self, frame_a, frame_b, axis, function=0.0, name=None):
        self.frame_a, self.frame_b = frame_a, frame_b
        self.axis = _axis_index(axis, f"relative coordinate {name or ''}".strip())
        self.name = name or f"Phi_{frame_b}_{frame_a}_{AXIS_NAMES[self.axis]}"
        self.function = _time_function(function, f"relative coordinate {self.name!r}")
        self._grad = np.zeros(6)
        self._grad[self.axis], self._grad[3 + self.axis] = -1.0, 1.0

    def describe(self):
        return (f"{AXIS_NAMES[self.axis]} of frame {self.frame_b!r} relative to frame "
                f"{self.frame_a!r} = f(t)")

    def local_terms(self, s, t):
        f, f_t, f_tt = _derivatives(self, t)
        return (float(s[3 + self.axis] - s[self.axis]) - f, self._grad, _ZERO66, -f_t,
                _ZERO6, -f_tt)


class Distance(PairConstraint):
    """|p_b - p_a| - f(t) = 0: the distance between the frames' origins follows f (m, a
    number for a rigid rod).  The row is undefined where the origins meet (ConstraintError);
    f must stay positive."""

    def __init__(self, frame_a, frame_b, function, name=None):
        self.frame_a, self.frame_b = frame_a, frame_b
        self.name = name or f"Phi_{frame_a}_{frame_b}_distance"
        self.function = _time_function(function, f"distance {self.name!r}")

    def describe(self):
        return f"distance between frames {self.frame_a!r} and {self.frame_b!r} = f(t)"

    def local_terms(self, s, t):
        f, f_t, f_tt = _derivatives(self, t)
        d = np.asarray(s[3:6], dtype=float) - np.asarray(s[0:3], dtype=float)
        length = float(np.linalg.norm(d))
        if not length > 1e-12:
            raise ConstraintError(
                f"distance {self.name!r}: the origins of frames {self.frame_a!r} and "
                f"{self.frame_b!r} coincide at t = {float(t):.6g} s (|p_b - p_a| = "
                f"{length:.3g} m), where the direction of the distance row is undefined; "
                "a programmed distance must stay positive")
        e = d / length
        proj = (np.eye(3) - np.outer(e, e)) / length
        grad = np.concatenate([-e, e])
        hess = np.block([[proj, -proj], [-proj, proj]])
        return length - f, grad, hess, -f_t, _ZERO6, -f_tt


class AxisAlignment(PairConstraint):
    """(R_a e_i) . (R_b e_j) - f(t) = 0: the cosine between axis i of frame a and axis j of
    frame b (world unit vectors) follows f (dimensionless; 0: perpendicular)."""

    def __init__(self, frame_a, axis_a, frame_b, axis_b, function=0.0, name=None):
        self.frame_a, self.frame_b = frame_a, frame_b
        i = _axis_index(axis_a, f"axis alignment {name or ''}".strip())
        j = _axis_index(axis_b, f"axis alignment {name or ''}".strip())
        self.axis_a, self.axis_b = i, j
        self.name = name or f"Phi_{frame_a}{AXIS_NAMES[i]}_{frame_b}{AXIS_NAMES[j]}"
        self.function = _time_function(function, f"axis alignment {self.name!r}")
        self.vectors = ((tuple(np.eye(3)[i]), DIRECTION), (tuple(np.eye(3)[j]), DIRECTION))

    def describe(self):
        return (f"{AXIS_NAMES[self.axis_a]} axis of frame {self.frame_a!r} . "
                f"{AXIS_NAMES[self.axis_b]} axis of frame {self.frame_b!r} = f(t)")

    def local_terms(self, s, t):
        f, f_t, f_tt = _derivatives(self, t)
        u, v = np.asarray(s[0:3], dtype=float), np.asarray(s[3:6], dtype=float)
        return float(u @ v) - f, np.concatenate([v, u]), _DOT_HESSIAN, -f_t, _ZERO6, -f_tt


_DOT_HESSIAN = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])
_PAIR_TERM_NAMES = (("phi",) + tuple(f"grad[{s}]" for s in PAIR_SYMBOL_NAMES[:6])
                    + tuple(f"Hessian[{a}, {b}]" for a in PAIR_SYMBOL_NAMES[:6]
                            for b in PAIR_SYMBOL_NAMES[:6])
                    + ("phi_t",) + tuple(f"grad_t[{s}]" for s in PAIR_SYMBOL_NAMES[:6])
                    + ("phi_tt",))
N_PAIR_TERMS = len(_PAIR_TERM_NAMES)       # 51


class SympyPairConstraint(PairConstraint):
    """phi(x_a, y_a, z_a, x_b, y_b, z_b, t) = 0 as a SymPy expression (or a string read by
    ``sympy.sympify``: code you trust; gpme_io.modelfile parses a model file's strings
    without eval) of the world coordinates (m) of the origins of frames a and b and t (s).

    Derivatives are taken once here and compiled with ``sympy.lambdify``; the expression
    is checked as gpme_core.constraints.SympyPointConstraint checks one (one ModelError
    listing every problem), and :meth:`local_terms` raises a ConstraintError naming what is
    not finite."""

    def __init__(self, expr, frame_a, frame_b, name="Phi", symbols=None):
        syms = symbols or sp.symbols(" ".join(PAIR_SYMBOL_NAMES))
        by_name = dict(zip(PAIR_SYMBOL_NAMES, syms))
        label = f"constraint {name!r}"
        parsed, problems = checks.read_expression(
            expr, by_name, label, "x_a, y_a, z_a, x_b, y_b, z_b (world coordinates of the "
            "two frames' origins, m) and t (s)")
        coords = set(syms[:6])
        if parsed is not None and not parsed.free_symbols & coords:
            problems.append(f"{label}: {str(parsed)!r} does not depend on the frames' "
                            "coordinates, so its Jacobian row is zero")
        if problems:
            raise ModelError(problems)
        s, t = syms[:6], syms[6]
        grad = [sp.diff(parsed, v) for v in s]
        hess = [sp.diff(g, v) for g in grad for v in s]
        phi_t = sp.diff(parsed, t)
        grad_t = [sp.diff(phi_t, v) for v in s]
        fns, problems = checks.compile_expressions(
            tuple(syms), [parsed, *grad, *hess, phi_t, *grad_t, sp.diff(phi_t, t)], label,
            parsed)
        if problems:
            raise ModelError(problems)
        self.expr, self.symbols = parsed, tuple(syms)
        self._fast, self._careful = fns["math"], fns["numpy"]
        self.frame_a, self.frame_b, self.name = frame_a, frame_b, name

    def describe(self):
        return f"phi = {self.expr} on frames {self.frame_a!r} (a) and {self.frame_b!r} (b)"

    def terms_along(self, points, times) -> np.ndarray:
        """(k, 51) local terms (phi, grad (6), Hessian (6x6), phi_t, grad_t (6), phi_tt) at
        k stacked origins (k, 6) m (frame a's x, y, z, then b's) and times (k,) s, by
        numpy at once; NaN where a term is not finite (gpme_core.smoothness reads a run's
        samples with it)."""
        pts = np.asarray(points, dtype=float)
        return checks.evaluate_along(self._careful, [pts[:, i] for i in range(6)]
                                     + [np.asarray(times, dtype=float)], N_PAIR_TERMS)

    def local_terms(self, s, t):
        args = tuple(float(v) for v in s) + (float(t),)
        try:
            v = self._fast(*args)
            ok = math.isfinite(sum(v))
        except (ArithmeticError, ValueError, TypeError):
            ok = False
        if ok:
            v = np.array(v, dtype=float)
        else:
            with np.errstate(all="ignore"):
                try:
                    v = np.array(self._careful(*(np.float64(a) for a in args)), dtype=float)
                except (ArithmeticError, ValueError, TypeError):
                    v = np.full(N_PAIR_TERMS, np.nan)
            if not np.isfinite(v).all():
                raise ConstraintError(
                    f"constraint {self.name!r}: {self.describe()} is not finite at t = "
                    f"{float(t):.6g} s, frame a at {checks.format_point(s[:3])}, frame b at "
                    f"{checks.format_point(s[3:6])}: "
                    f"{checks.non_finite_text(_PAIR_TERM_NAMES, v)}; the GPME needs phi and "
                    "its first and second derivatives finite along the motion")
        return (float(v[0]), v[1:7], v[7:43].reshape(6, 6), float(v[43]), v[44:50],
                float(v[50]))


def coincident(frame_a, frame_b, axes="xyz", name=None):
    """[RelativeCoordinate] making the origins of two frames coincide along ``axes`` (world
    x, y, z; 'xy' for a planar loop, whose z row would be redundant)."""
    base = name or f"Phi_{frame_b}_{frame_a}"
    return [RelativeCoordinate(frame_a, frame_b, ax, 0.0, f"{base}_{ax}") for ax in axes]


def aligned(frame_a, frame_b, name=None):
    """[AxisAlignment] x 3: frame b has frame a's orientation (y_a . z_b = z_a . x_b =
    x_a . y_b = 0, independent near the aligned orientation)."""
    base = name or f"Phi_{frame_b}_{frame_a}"
    return [AxisAlignment(frame_a, i, frame_b, j, 0.0, f"{base}_r{AXIS_NAMES[k]}")
            for k, (i, j) in enumerate(((1, 2), (2, 0), (0, 1)))]


def weld(frame_a, frame_b, name=None):
    """The six rows fixing frame b to frame a (same origin, same orientation)."""
    return coincident(frame_a, frame_b, name=name) + aligned(frame_a, frame_b, name=name)


def _derivatives(spec, t):
    """(f, f', f'') of a pair constraint's programme at t, all finite, else ConstraintError."""
    try:
        f, f_t, f_tt = spec.function.derivatives(t)
    except ConstraintError as exc:
        raise ConstraintError(f"constraint {spec.name!r} ({spec.describe()}): {exc}") from None
    if not (math.isfinite(f) and math.isfinite(f_t) and math.isfinite(f_tt)):
        raise ConstraintError(f"constraint {spec.name!r} ({spec.describe()}): the programme "
                              f"{spec.function!r} is not finite at t = {float(t):.6g} s: f = "
                              f"{f:g}, f' = {f_t:g}, f'' = {f_tt:g}")
    return f, f_t, f_tt


class _BoundPairConstraint:
    """A pair constraint on a model: ``ends`` = ((link, vector (3,) in the link frame, w)
    of frame a, same of frame b)."""

    def __init__(self, spec, ends):
        self.spec, self.name, self.ends = spec, spec.name, tuple(ends)
        self.vector_keys = self.ends

    def stacked(self, vectors):
        """(s (6,), s_dot (6,), J (6, n), d (6,)) from the two ends' VectorKinematics."""
        a, b = vectors
        return (np.concatenate([a.position, b.position]),
                np.concatenate([a.velocity, b.velocity]),
                np.vstack([a.jacobian, b.jacobian]), np.concatenate([a.drift, b.drift]))

    def evaluate(self, t, kin, q_dot, vectors):
        s, s_dot, jac, drift = self.stacked(vectors)
        phi, grad, hess, phi_t, grad_t, phi_tt = self.spec.local_terms(s, t)
        row = grad @ jac
        phi_dot = float(grad @ s_dot) + phi_t
        kappa = float(grad @ drift + s_dot @ (hess @ s_dot) + 2.0 * (grad_t @ s_dot) + phi_tt)
        if not (math.isfinite(phi) and math.isfinite(phi_dot) and math.isfinite(kappa)):
            raise ConstraintError(
                f"constraint {self.name!r} ({self.spec.describe()}) is not finite at t = "
                f"{float(t):.6g} s: Phi = {phi:g}, Phi_dot = {phi_dot:g}, kappa = {kappa:g}")
        return phi, row, phi_dot, kappa


def vectors_of(model, kin, q_dot, keys, cache):
    """[VectorKinematics] of the (link, vector, w) keys, computed once per key in ``cache``."""
    out = []
    for key in keys:
        vk = cache.get(key)
        if vk is None:
            vk = vector_kinematics(model, kin, q_dot, key[0], key[1], key[2])
            cache[key] = vk
        out.append(vk)
    return out

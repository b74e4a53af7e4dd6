"""Programmed (task) constraints: holonomic, possibly time dependent, Phi(q, t) = 0.

Each constraint, once bound to a model, returns at (t, q, q_dot):

    Phi                         (value)
    a        (n,)  with  Phi_dot  = a . q_dot + Phi_t     (Jacobian row: paper's u, C_3)
    kappa           with  Phi_ddot = a . q_ddot + kappa   (paper's v, d_3 - z_ddot_a)

A *point constraint* is a scalar phi(x, y, z, t) of the world position p of a point
fixed on a link (the end-effector).  With p_dot = C q_dot, p_ddot = C q_ddot + d (C and d
from T_i and T_ij, see gpme_core.kinematics.point_kinematics):

    a     = grad(phi)^T C
    kappa = grad(phi) . d + p_dot^T Hess(phi) p_dot + 2 grad(phi_t) . p_dot + phi_tt
"""
import math

import numpy as np
import sympy as sp

from . import expression_checks as checks
from .errors import ConstraintError, ModelError
from .kinematics import point_kinematics
from .pair_constraints import vectors_of
from .time_functions import TimeFunction


class PointConstraint:
    """phi(x, y, z, t) = 0 on the origin of the model frame ``frame``.

    Subclasses implement :meth:`local_terms` returning
    (phi, grad (3,), hess (3, 3), phi_t, grad_t (3,), phi_tt) at world point p (3,) m.
    """

    name = "Phi"
    frame = "E"

    def local_terms(self, p, t):
        raise NotImplementedError

    def bind(self, model):
        fr = model.frame(self.frame)
        return _BoundPointConstraint(self, model, fr.link_index, fr.transform[:3, 3].copy())


class EllipseConstraint(PointConstraint):
    """Paper eq. 4.1: ((x - xc)/a)^2 + ((y - yc)/b)^2 - 1 = 0, a horizontal elliptic cylinder.

    a, b : m, semi-axes along world x and y;  center : (xc, yc) m.
    """

    def __init__(self, a, b, center=(0.0, 0.0), frame="E", name="Phi_1"):
        problems = [f"ellipse {name!r}: semi-axis {k} must be positive, got {v!r} m"
                    for k, v in (("a", a), ("b", b)) if not (np.isfinite(v) and v > 0)]
        if problems:
            raise ModelError(problems)
        self.a, self.b, self.center = float(a), float(b), np.asarray(center, dtype=float)
        self.frame, self.name = frame, name
        self._w = np.array([1.0 / self.a ** 2, 1.0 / self.b ** 2, 0.0])
        self._hess = np.diag(2.0 * self._w)
        self._zero = np.zeros(3)

    def local_terms(self, p, t):
        rx, ry = p[0] - self.center[0], p[1] - self.center[1]
        w = self._w
        phi = w[0] * rx * rx + w[1] * ry * ry - 1.0
        return (phi, np.array([2.0 * w[0] * rx, 2.0 * w[1] * ry, 0.0]), self._hess, 0.0,
                self._zero, 0.0)


class CoordinateProgramme(PointConstraint):
    """Paper eq. 4.2 generalised: the world coordinate ``axis`` (0 x, 1 y, 2 z) of the
    point follows f(t):  p[axis] - f(t) = 0.  f is a :class:`TimeFunction`."""

    def __init__(self, function, axis=2, frame="E", name="Phi_2"):
        if not isinstance(function, TimeFunction):
            raise ModelError(f"programme {name!r}: function must be a TimeFunction with value, "
                             f"rate and acceleration, got {type(function).__name__}")
        if axis not in (0, 1, 2):
            raise ModelError(f"programme {name!r}: axis must be 0, 1 or 2, got {axis!r}")
        self.function, self.axis, self.frame, self.name = function, axis, frame, name
        self._e = np.eye(3)[axis]
        self._zero_hess = np.zeros((3, 3))
        self._zero = np.zeros(3)

    def local_terms(self, p, t):
        f, f_t, f_tt = _time_derivatives(
            self.function, t, lambda: f"programme {self.name!r} ({'xyz'[self.axis]} of frame "
                                      f"{self.frame!r} = f(t), at {checks.format_point(p)})")
        return (float(p[self.axis]) - f, self._e, self._zero_hess, -f_t, self._zero, -f_tt)


_XYZ = ("x", "y", "z")
_TERM_NAMES = (("phi",) + tuple(f"grad[{a}]" for a in _XYZ)
               + tuple(f"Hessian[{a}, {b}]" for a in _XYZ for b in _XYZ) + ("phi_t",)
               + tuple(f"grad_t[{a}]" for a in _XYZ) + ("phi_tt",))
"""Names of the 18 numbers of :meth:`SympyPointConstraint.local_terms`, in order."""
_F64 = np.float64


class SympyPointConstraint(PointConstraint):
    """phi given as a SymPy expression in the symbols x, y, z, t (world frame, SI).

    expr    : a SymPy expression, or a string read by ``sympy.sympify`` (code you trust;
              gpme_io.modelfile parses a model file's strings without eval)
    symbols : the symbols (x, y, z, t) if not the plain ``sympy.symbols("x y z t")``; a
              symbol with one of these names but other assumptions is taken as it

    The gradient, Hessian and time derivatives are derived once here and compiled with
    ``sympy.lambdify``; nothing is re-derived during integration.  The expression is
    checked first (gpme_core.expression_checks): one ModelError lists every problem
    (not an expression, other symbols, no x, y or z, undefined functions, constants that
    are not finite reals, functions without a second derivative such as Abs, sign,
    Piecewise, Max, and anything Python's math module or numpy cannot evaluate).
    :meth:`local_terms` raises a ConstraintError naming the constraint, t, the point and
    the quantities when a value is not finite (a pole, a square root or logarithm out of
    its domain); it never warns or divides by a Python zero.
    """

    def __init__(self, expr, frame="E", name="Phi", symbols=None):
        x, y, z, t = symbols or sp.symbols("x y z t")
        label = f"constraint {name!r}"
        parsed, problems = checks.read_expression(
            expr, {"x": x, "y": y, "z": z, "t": t}, label,
            "x, y, z (world coordinates, m) and t (s)")
        if parsed is not None and not parsed.free_symbols & {x, y, z}:
            problems.append(f"{label}: {str(parsed)!r} does not depend on x, y or z, so its "
                            "Jacobian row is zero; a constraint must involve the frame's "
                            "position (a JointProgramme gives a joint q(t))")
        if problems:
            raise ModelError(problems)
        xyz = (x, y, z)
        grad = [sp.diff(parsed, v) for v in xyz]
        hess = [sp.diff(g, v) for g in grad for v in xyz]
        phi_t = sp.diff(parsed, t)
        grad_t = [sp.diff(phi_t, v) for v in xyz]
        phi_tt = sp.diff(phi_t, t)
        fns, problems = checks.compile_expressions(
            (x, y, z, t), [parsed, *grad, *hess, phi_t, *grad_t, phi_tt], label, parsed)
        if problems:
            raise ModelError(problems)
        self.expr = parsed
        self.symbols = (x, y, z, t)
        self._fast, self._careful = fns["math"], fns["numpy"]
        self.frame, self.name = frame, name

    def local_terms(self, p, t):
        """(phi, grad (3,), hess (3, 3), phi_t, grad_t (3,), phi_tt) at world point p (3,)
        m and time t s; ConstraintError when any of them is not finite."""
        try:
            v = self._fast(float(p[0]), float(p[1]), float(p[2]), float(t))
            ok = math.isfinite(sum(v))     # TypeError: complex (a negative to a real power)
        except (ArithmeticError, ValueError, TypeError):
            ok = False
        if ok:
            v = np.array(v, dtype=float)
        else:
            v = self._values(p, t)
            if not np.isfinite(v).all():
                raise ConstraintError(
                    f"constraint {self.name!r}: phi = {self.expr} on frame {self.frame!r} is "
                    f"not finite at t = {float(t):.6g} s, {checks.format_point(p)}: "
                    f"{self.non_finite_terms(p, t)}{checks.why_not_finite(self.expr, (*p, t))}"
                    "; the GPME needs phi and its first and second derivatives finite along "
                    "the motion")
        return float(v[0]), v[1:4], v[4:13].reshape(3, 3), float(v[13]), v[14:17], float(v[17])

    def terms_along(self, points, times) -> np.ndarray:
        """(k, 18) local terms (phi, grad, Hessian, phi_t, grad_t, phi_tt flat, in the order
        of :meth:`local_terms`) at k world points (k, 3) m and times (k,) s, evaluated at
        once by numpy; NaN where a term is not finite (gpme_core.smoothness reads a run's
        samples with it)."""
        pts = np.asarray(points, dtype=float)
        return checks.evaluate_along(self._careful, (pts[:, 0], pts[:, 1], pts[:, 2],
                                                     np.asarray(times, dtype=float)),
                                     len(_TERM_NAMES))

    def non_finite_terms(self, p, t) -> str:
        """'' when every local term at (p, t) is finite, else which are not, e.g.
        'phi = nan, grad[x] = nan, Hessian[x, x] = nan' (p (3,) m, t s)."""
        try:
            v = self._values(p, t, raise_errors=True)
        except (ArithmeticError, ValueError, TypeError) as exc:
            return "the evaluation raised " + checks.evaluation_failure(exc)
        return checks.non_finite_text(_TERM_NAMES, v)

    def _values(self, p, t, raise_errors=False):
        """The 18 local terms (flat, _TERM_NAMES) by numpy in float64, NaN where not
        finite (or everywhere when evaluating raises)."""
        with np.errstate(all="ignore"):
            try:
                return np.array(self._careful(_F64(p[0]), _F64(p[1]), _F64(p[2]), _F64(t)),
                                dtype=float)
            except (ArithmeticError, ValueError, TypeError):
                if raise_errors:
                    raise
                return np.full(len(_TERM_NAMES), np.nan)


class _BoundPointConstraint:
    def __init__(self, spec, model, link, r_local):
        self.spec, self.model, self.link, self.r_local = spec, model, link, r_local
        self.name = spec.name
        self.point_key = (link, tuple(r_local))

    def evaluate(self, t, kin, q_dot, point=None):
        pk = point if point is not None else point_kinematics(self.model, kin, q_dot, self.link,
                                                              self.r_local)
        phi, grad, hess, phi_t, grad_t, phi_tt = self.spec.local_terms(pk.position, t)
        row = grad @ pk.jacobian
        p_dot = pk.velocity
        phi_dot = float(grad @ p_dot) + phi_t
        kappa = float(grad @ pk.drift + p_dot @ (hess @ p_dot) + 2.0 * (grad_t @ p_dot) + phi_tt)
        if not (math.isfinite(phi) and math.isfinite(phi_dot) and math.isfinite(kappa)):
            # a PointConstraint subclass of the user's (SymPy ones raise in local_terms)
            raise ConstraintError(
                f"constraint {self.name!r} ({type(self.spec).__name__} on frame "
                f"{self.spec.frame!r}) is not finite at t = {float(t):.6g} s, "
                f"{checks.format_point(pk.position)}: Phi = {phi:g}, Phi_dot = {phi_dot:g}, "
                f"kappa = {kappa:g}; its local_terms must be finite along the motion")
        return phi, row, phi_dot, kappa


class JointProgramme:
    """Coordinate ``coordinate`` follows f(t):  q_k - f(t) = 0."""

    def __init__(self, coordinate, function, name=None):
        if not isinstance(function, TimeFunction):
            raise ModelError(f"joint programme on {coordinate!r}: function must be a "
                             f"TimeFunction, got {type(function).__name__}")
        self.coordinate, self.function = coordinate, function
        self.name = name or f"Phi_{coordinate}"

    def bind(self, model):
        return _BoundJointProgramme(self, model.index(self.coordinate), model.n_coordinates)


class _BoundJointProgramme:
    point_key = None

    def __init__(self, spec, k, n):
        self.spec, self.k, self.name = spec, k, spec.name
        self.row = np.zeros(n)
        self.row[k] = 1.0

    def evaluate(self, t, kin, q_dot, point=None):
        q = float(kin.q[self.k])
        c = self.spec.coordinate
        f, f_t, f_tt = _time_derivatives(
            self.spec.function, t,
            lambda: f"programme {self.name!r} ({c} = f(t), at {c} = {q:.6g})")
        return q - f, self.row, float(q_dot[self.k]) - f_t, -f_tt


def _time_derivatives(function, t, label):
    """(f, f', f'') of a TimeFunction at t s, all finite, else ConstraintError starting
    with ``label()`` (the programme and the state; built only for the message)."""
    try:
        f, f_t, f_tt = function.derivatives(t)
    except ConstraintError as exc:       # a SympyTimeFunction names what is not finite
        raise ConstraintError(f"{label()}: {exc}") from None
    if not (math.isfinite(f) and math.isfinite(f_t) and math.isfinite(f_tt)):
        raise ConstraintError(f"{label()}: the time function {function!r} is not finite at "
                              f"t = {float(t):.6g} s: f = {f:g}, f' = {f_t:g}, f'' = {f_tt:g}; "
                              "a programme needs f, f' and f'' finite along the motion")
    return f, f_t, f_tt


def bind_constraints(model, constraints):
    """Bind constraint specs to ``model``; names must be unique."""
    bound = [c.bind(model) for c in constraints]
    names = [b.name for b in bound]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ModelError(f"constraint names must be unique, repeated: {dup}")
    return bound


def evaluate_constraints(model, bound, t, kin, q_dot):
    """(Phi (m,), Phi_dot (m,), A (m, n), kappa (m,)) for all bound constraints (point
    constraints, joint programmes and gpme_core.pair_constraints)."""
    m = len(bound)
    phi, phi_dot, kappa = np.empty(m), np.empty(m), np.empty(m)
    a = np.empty((m, model.n_coordinates))
    cache = {}
    for k, c in enumerate(bound):
        point = None
        keys = getattr(c, "vector_keys", None)
        if keys is not None:           # a pair constraint: both frames' vectors
            phi[k], a[k], phi_dot[k], kappa[k] = c.evaluate(
                t, kin, q_dot, vectors_of(model, kin, q_dot, keys, cache))
            continue
        if c.point_key is not None:
            key = (c.link, tuple(c.r_local), 1.0)
            point = cache.get(key)
            if point is None:
                point = point_kinematics(model, kin, q_dot, c.link, c.r_local)
                cache[key] = point
        phi[k], a[k], phi_dot[k], kappa[k] = c.evaluate(t, kin, q_dot, point)
    return phi, phi_dot, a, kappa

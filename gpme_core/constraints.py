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
import numpy as np

from .errors import ModelError
from .kinematics import point_kinematics
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
        f = self.function
        return (float(p[self.axis]) - f.value(t), self._e, self._zero_hess, -f.rate(t),
                self._zero, -f.acceleration(t))


class SympyPointConstraint(PointConstraint):
    """phi given as a SymPy expression in the symbols x, y, z, t (world frame, SI).

    The gradient, Hessian and time derivatives are derived once here and compiled with
    ``sympy.lambdify``; nothing is re-derived during integration.
    """

    def __init__(self, expr, frame="E", name="Phi", symbols=None):
        import sympy as sp
        x, y, z, t = symbols or sp.symbols("x y z t")
        try:
            expr = sp.sympify(expr)
        except (sp.SympifyError, TypeError) as exc:
            raise ModelError(f"constraint {name!r}: cannot read {expr!r} as a SymPy expression "
                             f"({exc})") from None
        unknown = expr.free_symbols - {x, y, z, t}
        if unknown:
            raise ModelError(f"constraint {name!r}: expression uses {sorted(map(str, unknown))}; "
                             "only x, y, z (world coordinates, m) and t (s) are allowed")
        xyz = (x, y, z)
        grad = [sp.diff(expr, v) for v in xyz]
        hess = [[sp.diff(g, v) for v in xyz] for g in grad]
        phi_t = sp.diff(expr, t)
        grad_t = [sp.diff(phi_t, v) for v in xyz]
        phi_tt = sp.diff(phi_t, t)
        self.expr = expr
        self._f = sp.lambdify((x, y, z, t), [expr, grad, hess, phi_t, grad_t, phi_tt], "numpy")
        self.frame, self.name = frame, name

    def local_terms(self, p, t):
        phi, grad, hess, phi_t, grad_t, phi_tt = self._f(p[0], p[1], p[2], t)
        return (float(phi), np.asarray(grad, dtype=float), np.asarray(hess, dtype=float),
                float(phi_t), np.asarray(grad_t, dtype=float), float(phi_tt))


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
        f = self.spec.function
        return (float(kin.q[self.k]) - f.value(t), self.row, float(q_dot[self.k]) - f.rate(t),
                -f.acceleration(t))


def bind_constraints(model, constraints):
    """Bind constraint specs to ``model``; names must be unique."""
    bound = [c.bind(model) for c in constraints]
    names = [b.name for b in bound]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ModelError(f"constraint names must be unique, repeated: {dup}")
    return bound


def evaluate_constraints(model, bound, t, kin, q_dot):
    """(Phi (m,), Phi_dot (m,), A (m, n), kappa (m,)) for all bound constraints."""
    m = len(bound)
    phi, phi_dot, kappa = np.empty(m), np.empty(m), np.empty(m)
    a = np.empty((m, model.n_coordinates))
    cache = {}
    for k, c in enumerate(bound):
        point = None
        if c.point_key is not None:
            point = cache.get(c.point_key)
            if point is None:
                point = point_kinematics(model, kin, q_dot, c.link, c.r_local)
                cache[c.point_key] = point
        phi[k], a[k], phi_dot[k], kappa[k] = c.evaluate(t, kin, q_dot, point)
    return phi, phi_dot, a, kappa

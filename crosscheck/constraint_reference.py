"""Programmed constraints derived on the reference side, independently of gpme's formulas.

gpme evaluates a point constraint phi(x, y, z, t) with its own chain-rule formula
(gpme_core.constraints: kappa = grad . drift + p_dot^T Hess p_dot + 2 grad_t . p_dot + phi_tt).
A crosscheck that reused that formula would repeat any slip in it, so here SymPy
differentiates the composite function Phi(t) = phi(x(t), y(t), z(t), t) twice with respect to
time, with x(t), y(t), z(t) as undetermined functions, and the derivatives are then replaced
by symbols:

    Phi_dot  = dPhi/dt        with x' -> v_x ...            (affine in v)
    Phi_ddot = d^2 Phi/dt^2   with x' -> v_x, x'' -> a_x ... (affine in a)

With the engine's point velocity v = J q_dot and classical acceleration a = J q_ddot + drift
(drift = a at q_ddot = 0), the constraint row is A = dPhi_dot/dv . J and
kappa = Phi_ddot(a = drift).  The input expression is the task definition itself (the
model file's string, or the built-in ellipse / coordinate programme rebuilt here from its
parameters); only the derivatives are computed here.

A joint programme q_k = f(t) gives Phi = q_k - f, A = e_k, kappa = -f''(t), f'' from SymPy.

A constraint between two frames (gpme_core.pair_constraints) is derived the same way as a
function of several points, each the origin of a named frame: the two frames' origins
for a relative coordinate, a distance or an expression in x_a ... z_b, and for an axis
alignment (R_a e_i) . (R_b e_j) four points, each frame's origin and the point one metre
along the axis (``axis_frame_name``: a frame the engines are given for it by
:func:`with_reference_frames`), the axis being their difference.  Nothing of gpme's row
formula (stacked Jacobians, the direction kinematics) is used.

Frames and units: p, v, a in the world frame (m, m/s, m/s^2); J (3, n) m or m/rad.
"""
import dataclasses
from dataclasses import dataclass, fields
from typing import Callable, Optional

import numpy as np
import sympy as sp
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline

from gpme_core import constraints as gc
from gpme_core.gpme import ProgrammedMotion
from gpme_core import pair_constraints as pc
from gpme_core import time_functions as tfn
from gpme_core import transforms as tf
from gpme_core.model import Frame, Model

T = sp.Symbol("t", real=True)
XYZ = sp.symbols("x y z", real=True)
_V = sp.symbols("v_x v_y v_z", real=True)
_A = sp.symbols("a_x a_y a_z", real=True)


def time_expression(function) -> Optional[sp.Expr]:
    """SymPy expression in t of a gpme time function, rebuilt from its parameters, or None
    when it has no closed form here (a tabulated function)."""
    if isinstance(function, tfn.SympyTimeFunction):
        return sp.sympify(function.expr).subs(sp.Symbol("t"), T)
    name = type(function).__name__
    p = {f.name: getattr(function, f.name) for f in fields(function)} \
        if hasattr(function, "__dataclass_fields__") else {}
    if name == "Constant":
        return sp.Float(p["level"])
    if name == "Cosine":
        return p["offset"] + p["amplitude"] * sp.cos(2 * sp.pi * T / p["period"])
    if name == "Sine":
        return p["offset"] + p["amplitude"] * sp.sin(2 * sp.pi * T / p["period"]
                                                       + p.get("phase", 0.0))
    if name == "QuinticRamp":
        s = T / p["ramp_time"]
        ramp = p["level"] * s ** 3 * (10 - 15 * s + 6 * s ** 2)
        return sp.Piecewise((0, T < 0), (ramp, T < p["ramp_time"]), (p["level"], True))
    return None


def _time_derivatives(function) -> Callable[[float], tuple]:
    """t -> (f, f', f'') of a time function, by SymPy where it has a closed form, else by
    an independent cubic spline of its table (scipy) for tabulated functions."""
    if hasattr(function, "reference_derivatives"):
        # a benchmark's time function that carries its published definition (f, f', f'')
        # written out separately from its value/rate/acceleration (gpme_examples.spin_up)
        return function.reference_derivatives
    expr = time_expression(function)
    if expr is not None:
        f = sp.lambdify(T, [expr, sp.diff(expr, T), sp.diff(expr, T, 2)], "numpy")
        return lambda t: tuple(float(v) for v in f(t))
    if hasattr(function, "times") and hasattr(function, "values"):
        spline = CubicSpline(np.asarray(function.times, float), np.asarray(function.values, float),
                             bc_type="natural")
        t0, t1 = float(function.times[0]), float(function.times[-1])

        def tabulated(t):
            if t <= t0 or t >= t1:     # constant outside the table
                return float(spline(min(max(t, t0), t1))), 0.0, 0.0
            return float(spline(t)), float(spline(t, 1)), float(spline(t, 2))
        return tabulated
    raise TypeError(f"no reference form for the time function {function!r}")


def point_expression(spec) -> sp.Expr:
    """phi(x, y, z, t) of a point-constraint spec, rebuilt from its parameters."""
    x, y, z = XYZ
    if isinstance(spec, gc.SympyPointConstraint):
        sym = {sp.Symbol(n): s for n, s in zip(("x", "y", "z", "t"), (*XYZ, T))}
        return sp.sympify(spec.expr).subs(sym)
    if isinstance(spec, gc.EllipseConstraint):
        xc, yc = (float(c) for c in spec.center)
        return ((x - xc) / spec.a) ** 2 + ((y - yc) / spec.b) ** 2 - 1
    if isinstance(spec, gc.CoordinateProgramme):
        f = time_expression(spec.function)
        if f is None:
            raise TypeError(f"constraint {spec.name!r}: no closed form for {spec.function!r}")
        return XYZ[spec.axis] - f
    raise TypeError(f"constraint {getattr(spec, 'name', spec)!r}: no reference derivation for "
                    f"{type(spec).__name__}")


@dataclass(frozen=True)
class ReferencePointConstraint:
    """phi(x, y, z, t) = 0 on the origin of model frame ``frame``, derived independently.

    evaluate(t, p, v, jacobian, drift) -> (Phi, Phi_dot, A (n,), kappa)
    """

    name: str
    frame: str
    expression: sp.Expr
    _f: Callable

    @classmethod
    def from_expression(cls, name, frame, expression):
        fx, fy, fz = (sp.Function(n, real=True)(T) for n in ("X", "Y", "Z"))
        composite = expression.subs({XYZ[0]: fx, XYZ[1]: fy, XYZ[2]: fz})
        first = sp.diff(composite, T)
        second = sp.diff(first, T)
        subs2 = {sp.diff(g, T, 2): a for g, a in zip((fx, fy, fz), _A)}
        subs1 = {sp.diff(g, T): v for g, v in zip((fx, fy, fz), _V)}
        back = {g: s for g, s in zip((fx, fy, fz), XYZ)}
        phi_dot = first.subs(subs1).subs(back)
        phi_ddot = second.subs(subs2).subs(subs1).subs(back)
        dphi_dot_dv = [sp.diff(phi_dot, v) for v in _V]
        f = sp.lambdify((*XYZ, T, *_V, *_A), [expression, phi_dot, dphi_dot_dv, phi_ddot],
                        "numpy")
        return cls(name, frame, expression, f)

    def evaluate(self, t: float, p: NDArray, v: NDArray, jacobian: NDArray, drift: NDArray):
        phi, phi_dot, grad_v, kappa = self._f(*p, t, *v, *drift)
        row = np.asarray(grad_v, dtype=float) @ np.asarray(jacobian, dtype=float)
        return float(phi), float(phi_dot), row, float(kappa)


@dataclass(frozen=True)
class ReferenceJointProgramme:
    """q_k - f(t) = 0 for coordinate ``coordinate`` (index ``index``)."""

    name: str
    coordinate: str
    index: int
    _f: Callable

    def evaluate(self, t: float, q: NDArray, q_dot: NDArray, n: int):
        f, f_dot, f_ddot = self._f(t)
        row = np.zeros(n)
        row[self.index] = 1.0
        return float(q[self.index] - f), float(q_dot[self.index] - f_dot), row, -f_ddot


def axis_frame_name(frame: str, axis: int) -> str:
    """Name of the auxiliary frame one metre along axis ``axis`` (0 x, 1 y, 2 z) of
    ``frame``: its origin minus the frame's origin is that axis in the world frame."""
    return f"{frame}@{'xyz'[axis]}"


def reference_frames(specs) -> dict:
    """{auxiliary frame name: (frame, axis)} the axis alignments of ``specs`` need."""
    out = {}
    for spec in specs:
        if isinstance(spec, pc.AxisAlignment):
            for frame, axis in ((spec.frame_a, spec.axis_a), (spec.frame_b, spec.axis_b)):
                out[axis_frame_name(frame, axis)] = (frame, axis)
    return out


def with_reference_frames(model: Model, specs) -> Model:
    """``model`` with the auxiliary frames of :func:`reference_frames` added (the same
    model when there are none).  Frames do not change the dynamics; the engines' models
    built from it then carry them as named frames, sites or markers."""
    extra = {name: (frame, axis) for name, (frame, axis) in reference_frames(specs).items()
             if name not in model.frames}
    if not extra:
        return model
    frames = dict(model.frames)
    for name, (frame, axis) in extra.items():
        base = model.frame(frame)
        offset = tf.translation(*np.eye(3)[axis])
        frames[name] = Frame(name, base.link_index, base.transform @ offset)
    return Model(model.joints, model.links, frames, model.drives, model.gravity,
                 model.flexible_links, model.name, model.geometry, model.point_springs)


def with_reference_frames_of(scenario):
    """``scenario`` (gpme_io.scenario.Scenario) with its model given the auxiliary frames
    of its constraints (:func:`with_reference_frames`): the same object when none are
    needed; else a copy whose model and system (same constraints, dependent coordinates
    and Baumgarte rates) have them."""
    model = with_reference_frames(scenario.model, scenario.constraints)
    if model is scenario.model:
        return scenario
    system = scenario.system
    copy = ProgrammedMotion(model, system.constraint_specs, dependent=system.dependent,
                            baumgarte=(system.alpha, system.beta),
                            damping_form=system.damping_form)
    return dataclasses.replace(scenario, model=model, system=copy)


def pair_expression(spec) -> tuple:
    """(frames, phi) of a pair constraint: phi in the coordinates (XYZ-like symbols, 3 per
    frame, :func:`point_symbols`) of the origins of ``frames``, rebuilt from the spec's
    parameters."""
    if isinstance(spec, pc.AxisAlignment):
        frames = (spec.frame_a, axis_frame_name(spec.frame_a, spec.axis_a),
                  spec.frame_b, axis_frame_name(spec.frame_b, spec.axis_b))
    else:
        frames = (spec.frame_a, spec.frame_b)
    pts = point_symbols(len(frames))
    f = None if isinstance(spec, pc.SympyPairConstraint) else time_expression(spec.function)
    if f is None and not isinstance(spec, pc.SympyPairConstraint):
        raise TypeError(f"constraint {spec.name!r}: no closed form for {spec.function!r}")
    if isinstance(spec, pc.SympyPairConstraint):
        names = pc.PAIR_SYMBOL_NAMES
        sym = {sp.Symbol(n): s for n, s in zip(names, (*pts[0], *pts[1], T))}
        expr = sp.sympify(spec.expr).subs(sym)
    elif isinstance(spec, pc.RelativeCoordinate):
        expr = pts[1][spec.axis] - pts[0][spec.axis] - f
    elif isinstance(spec, pc.Distance):
        expr = sp.sqrt(sum((pts[1][i] - pts[0][i]) ** 2 for i in range(3))) - f
    elif isinstance(spec, pc.AxisAlignment):
        expr = sum((pts[1][i] - pts[0][i]) * (pts[3][i] - pts[2][i]) for i in range(3)) - f
    else:
        raise TypeError(f"constraint {spec.name!r}: no reference derivation for "
                        f"{type(spec).__name__}")
    return frames, expr


def point_symbols(k: int) -> list:
    """[(x_k, y_k, z_k)] real symbols of k points (m, world frame)."""
    return [sp.symbols(f"px{i} py{i} pz{i}", real=True) for i in range(k)]


@dataclass(frozen=True)
class ReferenceFramesConstraint:
    """phi(p_0, ..., p_{k-1}, t) = 0 on the origins of the model frames ``frames``, derived
    independently as ReferencePointConstraint is, with the points' coordinates as functions
    of time.  evaluate(t, states) with states [(p, v, J, drift)] per frame."""

    name: str
    frames: tuple
    expression: sp.Expr
    _f: Callable

    @classmethod
    def from_spec(cls, spec):
        frames, expression = pair_expression(spec)
        pts = point_symbols(len(frames))
        coords = [c for p in pts for c in p]
        funcs = [sp.Function(f"P{i}", real=True)(T) for i in range(len(coords))]
        vel = sp.symbols(f"v0:{len(coords)}", real=True)
        acc = sp.symbols(f"a0:{len(coords)}", real=True)
        composite = expression.subs(dict(zip(coords, funcs)))
        first = sp.diff(composite, T)
        second = sp.diff(first, T)
        subs2 = {sp.diff(g, T, 2): a for g, a in zip(funcs, acc)}
        subs1 = {sp.diff(g, T): v for g, v in zip(funcs, vel)}
        back = dict(zip(funcs, coords))
        phi_dot = first.subs(subs1).subs(back)
        phi_ddot = second.subs(subs2).subs(subs1).subs(back)
        grad_v = [sp.diff(phi_dot, v) for v in vel]
        f = sp.lambdify((*coords, T, *vel, *acc), [expression, phi_dot, grad_v, phi_ddot],
                        "numpy")
        return cls(spec.name, frames, expression, f)

    def evaluate(self, t: float, states):
        p = np.concatenate([s[0] for s in states])
        v = np.concatenate([s[1] for s in states])
        jac = np.vstack([s[2] for s in states])
        drift = np.concatenate([s[3] for s in states])
        phi, phi_dot, grad_v, kappa = self._f(*p, t, *v, *drift)
        row = np.asarray(grad_v, dtype=float) @ jac
        return float(phi), float(phi_dot), row, float(kappa)


def reference_frame_names(refs) -> list:
    """Every frame whose point state the reference constraints ``refs`` ask for."""
    out = []
    for r in refs:
        for f in getattr(r, "frames", None) or ((r.frame,) if hasattr(r, "frame") else ()):
            if f not in out:
                out.append(f)
    return out


def reference_constraints(specs, coordinate_names):
    """The reference form of each gpme constraint spec (same order and names)."""
    out = []
    for spec in specs:
        if isinstance(spec, pc.PairConstraint):
            out.append(ReferenceFramesConstraint.from_spec(spec))
        elif isinstance(spec, gc.JointProgramme):
            out.append(ReferenceJointProgramme(spec.name, spec.coordinate,
                                               list(coordinate_names).index(spec.coordinate),
                                               _time_derivatives(spec.function)))
        else:
            out.append(ReferencePointConstraint.from_expression(spec.name, spec.frame,
                                                                point_expression(spec)))
    return out


def evaluate_reference(refs, t, q, q_dot, point_state):
    """(Phi (m,), Phi_dot (m,), A (m, n), kappa (m,)) of reference constraints ``refs``.

    point_state : frame name -> (p (3,), v (3,), J (3, n), drift (3,)) from the engine.
    """
    n = len(q)
    m = len(refs)
    phi, phi_dot, kappa = np.empty(m), np.empty(m), np.empty(m)
    a = np.empty((m, n))
    for k, r in enumerate(refs):
        if isinstance(r, ReferenceJointProgramme):
            phi[k], phi_dot[k], a[k], kappa[k] = r.evaluate(t, q, q_dot, n)
        elif isinstance(r, ReferenceFramesConstraint):
            phi[k], phi_dot[k], a[k], kappa[k] = r.evaluate(t, [point_state(f)
                                                                for f in r.frames])
        else:
            phi[k], phi_dot[k], a[k], kappa[k] = r.evaluate(t, *point_state(r.frame))
    return phi, phi_dot, a, kappa

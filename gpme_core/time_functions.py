"""Scalar functions of time with their first two derivatives (programmes and drives).

Each has ``value(t)``, ``rate(t)`` and ``acceleration(t)`` (t in s; the unit of the value
is the unit of what it drives: N or N m for a drive, m or rad for a programme) and is
callable as ``f(t) == f.value(t)`` so it can serve directly as a drive.

The functions with parameters are frozen dataclasses whose field names are their
parameters (gpme_io.urdf stores a drive as ``{"function": class name, "parameters":
dataclasses.asdict(f)}`` and rebuilds it with ``cls(**parameters)``).  Every constructor
checks its parameters and raises one :class:`gpme_core.errors.ModelError` listing every
problem, with the value and what would be valid.
"""
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np
import sympy as sp
from scipy.linalg import solve_banded

from . import expression_checks as checks
from .errors import ConstraintError, ModelError


class TimeFunction:
    """Base class: subclasses implement value, rate, acceleration."""

    def __call__(self, t: float) -> float:
        return self.value(t)

    def value(self, t: float) -> float:
        raise NotImplementedError

    def rate(self, t: float) -> float:
        raise NotImplementedError

    def acceleration(self, t: float) -> float:
        raise NotImplementedError

    def derivatives(self, t: float) -> tuple:
        """(value, rate, acceleration) at t s (one call: what a programme needs)."""
        return self.value(t), self.rate(t), self.acceleration(t)


def _is_real(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _finite_problems(label: str, **values) -> list:
    """'<label>: <name> must be a finite number, got <v>' for each bad value."""
    return [f"{label}: {name} must be a finite number, got {v!r}"
            for name, v in values.items() if not (_is_real(v) and math.isfinite(v))]


def _positive_problems(label: str, unit: str, **values) -> list:
    return [f"{label}: {name} must be a finite number > 0 ({unit}), got {v!r}"
            for name, v in values.items() if not (_is_real(v) and math.isfinite(v) and v > 0)]


def _raise(problems: list) -> None:
    if problems:
        raise ModelError(problems)


@dataclass(frozen=True)
class Constant(TimeFunction):
    """f(t) = level."""

    level: float

    def __post_init__(self):
        _raise(_finite_problems("Constant", level=self.level))

    def value(self, t):
        return self.level

    def rate(self, t):
        return 0.0

    def acceleration(self, t):
        return 0.0


@dataclass(frozen=True)
class Cosine(TimeFunction):
    """f(t) = offset + amplitude cos(2 pi t / period) (paper eq. 8); period in s > 0."""

    offset: float
    amplitude: float
    period: float

    def __post_init__(self):
        _raise(_finite_problems("Cosine", offset=self.offset, amplitude=self.amplitude)
               + _positive_problems("Cosine", "s", period=self.period))

    @property
    def omega(self):
        """rad/s, 2 pi / period."""
        return 2.0 * np.pi / self.period

    def value(self, t):
        return self.offset + self.amplitude * np.cos(self.omega * t)

    def rate(self, t):
        return -self.amplitude * self.omega * np.sin(self.omega * t)

    def acceleration(self, t):
        return -self.amplitude * self.omega ** 2 * np.cos(self.omega * t)


@dataclass(frozen=True)
class Sine(TimeFunction):
    """f(t) = offset + amplitude sin(2 pi t / period + phase); period in s > 0, phase in rad."""

    offset: float
    amplitude: float
    period: float
    phase: float = 0.0

    def __post_init__(self):
        _raise(_finite_problems("Sine", offset=self.offset, amplitude=self.amplitude,
                                phase=self.phase)
               + _positive_problems("Sine", "s", period=self.period))

    @property
    def omega(self):
        """rad/s, 2 pi / period."""
        return 2.0 * np.pi / self.period

    def value(self, t):
        return self.offset + self.amplitude * np.sin(self.omega * t + self.phase)

    def rate(self, t):
        return self.amplitude * self.omega * np.cos(self.omega * t + self.phase)

    def acceleration(self, t):
        return -self.amplitude * self.omega ** 2 * np.sin(self.omega * t + self.phase)


@dataclass(frozen=True)
class QuinticRamp(TimeFunction):
    """Smooth step (paper eq. 9): level (10 s^3 - 15 s^4 + 6 s^5), s = t / ramp_time < 1,
    then ``level``; zero for t < 0.  Value, rate and acceleration are continuous.
    ramp_time in s > 0."""

    level: float
    ramp_time: float

    def __post_init__(self):
        _raise(_finite_problems("QuinticRamp", level=self.level)
               + _positive_problems("QuinticRamp", "s", ramp_time=self.ramp_time))

    def value(self, t):
        s = min(max(t / self.ramp_time, 0.0), 1.0)
        return self.level * s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s)

    def rate(self, t):
        s = min(max(t / self.ramp_time, 0.0), 1.0)
        return self.level * 30.0 * s * s * (1.0 - s) ** 2 / self.ramp_time

    def acceleration(self, t):
        s = min(max(t / self.ramp_time, 0.0), 1.0)
        return self.level * 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s) / self.ramp_time ** 2


@dataclass(frozen=True)
class Tabulated(TimeFunction):
    """The natural cubic spline through the points (times[i], values[i]).

    times  : s, strictly increasing, at least 2 points (2 points: a straight line)
    values : same length, finite

    Inside [times[0], times[-1]] the spline is C2 (value, rate and acceleration
    continuous; acceleration 0 at both ends: the *natural* end conditions).  Outside it
    the function is constant: the end value, rate 0, acceleration 0.  So the value is
    continuous everywhere but the rate jumps at an end of the table unless the table
    starts and ends flat (repeat the end values, e.g. times (.., 4.9, 5.0), values
    (.., 1.0, 1.0), to approach that); gpme_io.modelfile notes such a jump.

    Fields are stored as tuples of floats (lists are accepted).
    """

    times: tuple
    values: tuple

    def __post_init__(self):
        problems = []
        arrays = {}
        for name in ("times", "values"):
            raw = getattr(self, name)
            try:
                items = tuple(raw)
            except TypeError:
                problems.append(f"Tabulated: {name} must be a list of numbers, got {raw!r}")
                continue
            bad = [(k, v) for k, v in enumerate(items) if not (_is_real(v) and math.isfinite(v))]
            if bad:
                problems.append(f"Tabulated: {name} must be finite numbers; entries "
                                + ", ".join(f"[{k}] = {v!r}" for k, v in bad))
                continue
            arrays[name] = tuple(float(v) for v in items)
        if len(arrays) == 2:
            t, v = arrays["times"], arrays["values"]
            if len(t) != len(v):
                problems.append(f"Tabulated: times and values must have the same length, got "
                                f"{len(t)} times and {len(v)} values")
            if len(t) < 2:
                problems.append(f"Tabulated: need at least 2 points, got {len(t)}")
            steps = [k for k in range(len(t) - 1) if not t[k + 1] > t[k]]
            if steps:
                problems.append("Tabulated: times must be strictly increasing (s); not at "
                                + ", ".join(f"times[{k}] = {t[k]!r} -> times[{k + 1}] = "
                                            f"{t[k + 1]!r}" for k in steps))
        _raise(problems)
        object.__setattr__(self, "times", arrays["times"])
        object.__setattr__(self, "values", arrays["values"])
        object.__setattr__(self, "_coefficients", _natural_spline(np.array(self.times),
                                                                  np.array(self.values)))

    def _piece(self, t):
        """(k, s, a, b, c, d) of the piece holding t, or None outside the table."""
        times = self.times
        if not times[0] < t < times[-1]:
            return None
        k = int(np.searchsorted(times, t, side="right")) - 1
        a, b, c, d = self._coefficients[k]
        return t - times[k], a, b, c, d

    def value(self, t):
        p = self._piece(t)
        if p is None:
            return self.values[0] if t <= self.times[0] else self.values[-1]
        s, a, b, c, d = p
        return float(a + s * (b + s * (c + s * d)))

    def rate(self, t):
        p = self._piece(t)
        if p is None:
            return 0.0
        s, _, b, c, d = p
        return float(b + s * (2.0 * c + 3.0 * s * d))

    def acceleration(self, t):
        p = self._piece(t)
        if p is None:
            return 0.0
        s, _, _, c, d = p
        return float(2.0 * c + 6.0 * s * d)

    def end_rates(self):
        """(rate just after times[0], rate just before times[-1]): the jumps to 0 at the
        table's ends (1/s times the value's unit)."""
        a, b, c, d = self._coefficients[-1]
        h = self.times[-1] - self.times[-2]
        return float(self._coefficients[0][1]), float(b + h * (2.0 * c + 3.0 * h * d))


def _natural_spline(t, y):
    """(len(t) - 1, 4) coefficients (a, b, c, d) of y = a + b s + c s^2 + d s^3, s = t -
    t_k on piece k, of the natural cubic spline (second derivative 0 at both ends)."""
    n = len(t)
    h = np.diff(t)
    m = np.zeros(n)                       # second derivatives at the knots
    if n > 2:
        # h_{k-1} m_{k-1} + 2 (h_{k-1} + h_k) m_k + h_k m_{k+1} = 6 (slope_k - slope_{k-1})
        slope = np.diff(y) / h
        ab = np.zeros((3, n - 2))
        ab[0, 1:] = h[1:-1]
        ab[1] = 2.0 * (h[:-1] + h[1:])
        ab[2, :-1] = h[1:-1]
        m[1:-1] = solve_banded((1, 1), ab, 6.0 * np.diff(slope))
    a = y[:-1]
    b = (y[1:] - y[:-1]) / h - h * (2.0 * m[:-1] + m[1:]) / 6.0
    c = 0.5 * m[:-1]
    d = (m[1:] - m[:-1]) / (6.0 * h)
    coef = np.column_stack([a, b, c, d])
    coef.setflags(write=False)
    return coef


_ORDER_NAMES = ("f", "f'", "f''")


class SympyTimeFunction(TimeFunction):
    """f(t) from a SymPy expression in the symbol ``t`` (s); derivatives generated once.

    expr     : a SymPy expression, or a string read by ``sympy.sympify`` (code you
               trust; gpme_io.modelfile parses a model file's strings without eval and
               passes the expression here)
    t_symbol : the time symbol (default ``Symbol('t')``; a symbol named like it with other
               assumptions is taken as it)
    name     : optional, names the function in messages

    The expression is checked first (gpme_core.expression_checks): one ModelError lists
    every problem (not an expression, other symbols, undefined functions, constants that
    are not finite reals, functions without a second derivative such as Abs, sign,
    Heaviside, Piecewise, Max, and anything Python's math module or numpy cannot
    evaluate).  ``expr`` keeps the expression.  value, rate, acceleration and derivatives
    raise a ConstraintError naming the function, t and which of f, f', f'' is not finite
    (a pole, a square root or logarithm out of its domain, an overflow); they never warn or
    divide by a Python zero.
    """

    def __init__(self, expr, t_symbol: Optional[object] = None, name: Optional[str] = None):
        t_sym = t_symbol if t_symbol is not None else sp.Symbol("t")
        label = f"time function {name!r}" if name is not None else "SympyTimeFunction"
        parsed, problems = checks.read_expression(expr, {"t": t_sym}, label,
                                                  f"the time {t_sym} (s)")
        _raise(problems)
        derivs = [parsed, sp.diff(parsed, t_sym), sp.diff(parsed, t_sym, 2)]
        fns, problems = checks.compile_expressions((t_sym,), derivs, label, parsed)
        _raise(problems)
        self.expr = parsed
        self.t_symbol = t_sym
        self.name = name
        self._fast, self._careful = fns["math"], fns["numpy"]
        self._fast_order = [sp.lambdify(t_sym, d, "math") for d in derivs]

    def _order(self, k, t):
        try:
            v = self._fast_order[k](float(t))
            if math.isfinite(v):           # TypeError: complex (a negative to a real power)
                return float(v)
        except (ArithmeticError, ValueError, TypeError):
            pass
        raise self._not_finite(t, {k: self._values(t)[k]})

    def value(self, t):
        return self._order(0, t)

    def rate(self, t):
        return self._order(1, t)

    def acceleration(self, t):
        return self._order(2, t)

    def derivatives(self, t):
        try:
            f, f_t, f_tt = self._fast(float(t))
            if math.isfinite(f + f_t + f_tt):
                return float(f), float(f_t), float(f_tt)
        except (ArithmeticError, ValueError, TypeError):
            pass
        v = self._values(t)
        if not np.isfinite(v).all():
            raise self._not_finite(t, dict(enumerate(v)))
        return float(v[0]), float(v[1]), float(v[2])     # finite, only their sum overflowed

    def derivatives_along(self, times) -> np.ndarray:
        """(k, 3) f, f', f'' at times (k,) s, evaluated at once by numpy; NaN where a value
        is not finite (gpme_core.smoothness reads a run's samples with it)."""
        return checks.evaluate_along(self._careful, (np.asarray(times, dtype=float),), 3)

    def _values(self, t):
        """(f, f', f'') by numpy in float64, NaN where not finite or evaluating raises."""
        with np.errstate(all="ignore"):
            try:
                return np.array(self._careful(np.float64(t)), dtype=float)
            except (ArithmeticError, ValueError, TypeError):
                return np.full(3, np.nan)

    def _not_finite(self, t, values):
        shown = ", ".join(f"{_ORDER_NAMES[k]} = {v:g}" for k, v in values.items()
                          if not math.isfinite(v))
        who = f"time function {self.name!r}" if self.name is not None else "time function"
        return ConstraintError(
            f"{who} f(t) = {self.expr} is not finite at t = {float(t):.6g} s: {shown}"
            f"{checks.why_not_finite(self.expr, (t,))}; a programme or drive needs f, f' and "
            "f'' finite over the run")

    def __repr__(self):
        return f"SympyTimeFunction({str(self.expr)!r})"

"""Scalar functions of time with their first two derivatives (programmes and drives).

Each has ``value(t)``, ``rate(t)`` and ``acceleration(t)`` (t in s) and is callable as
``f(t) == f.value(t)`` so it can serve directly as a drive.
"""
from dataclasses import dataclass

import numpy as np


class TimeFunction:
    """Base class: subclasses implement value, rate, acceleration."""

    def __call__(self, t):
        return self.value(t)

    def value(self, t):
        raise NotImplementedError

    def rate(self, t):
        raise NotImplementedError

    def acceleration(self, t):
        raise NotImplementedError


@dataclass(frozen=True)
class Constant(TimeFunction):
    """f(t) = level."""

    level: float

    def value(self, t):
        return self.level

    def rate(self, t):
        return 0.0

    def acceleration(self, t):
        return 0.0


@dataclass(frozen=True)
class Cosine(TimeFunction):
    """f(t) = offset + amplitude cos(2 pi t / period) (paper eq. 8)."""

    offset: float
    amplitude: float
    period: float

    @property
    def omega(self):
        return 2.0 * np.pi / self.period

    def value(self, t):
        return self.offset + self.amplitude * np.cos(self.omega * t)

    def rate(self, t):
        return -self.amplitude * self.omega * np.sin(self.omega * t)

    def acceleration(self, t):
        return -self.amplitude * self.omega ** 2 * np.cos(self.omega * t)


@dataclass(frozen=True)
class QuinticRamp(TimeFunction):
    """Smooth step (paper eq. 9): level (10 s^3 - 15 s^4 + 6 s^5), s = t / ramp_time < 1,
    then ``level``; zero for t < 0.  Value, rate and acceleration are continuous."""

    level: float
    ramp_time: float

    def value(self, t):
        s = min(max(t / self.ramp_time, 0.0), 1.0)
        return self.level * s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s)

    def rate(self, t):
        s = min(max(t / self.ramp_time, 0.0), 1.0)
        return self.level * 30.0 * s * s * (1.0 - s) ** 2 / self.ramp_time

    def acceleration(self, t):
        s = min(max(t / self.ramp_time, 0.0), 1.0)
        return self.level * 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s) / self.ramp_time ** 2


class SympyTimeFunction(TimeFunction):
    """f(t) from a SymPy expression in the symbol ``t``; derivatives generated once."""

    def __init__(self, expr, t_symbol=None):
        import sympy as sp
        t_sym = t_symbol or sp.Symbol("t")
        self.expr = sp.sympify(expr)
        self._f = [sp.lambdify(t_sym, sp.diff(self.expr, t_sym, k), "numpy") for k in range(3)]

    def value(self, t):
        return float(self._f[0](t))

    def rate(self, t):
        return float(self._f[1](t))

    def acceleration(self, t):
        return float(self._f[2](t))

"""Time functions: derivatives against finite differences and SymPy, the natural spline
against SciPy's, the constant extension, parameter validation, field names."""
import dataclasses
import json
import math

import numpy as np
import pytest
import sympy as sp
from scipy.interpolate import CubicSpline

from gpme_core import time_functions as tfn
from gpme_core.errors import ModelError
from gpme_core.time_functions import (Constant, Cosine, QuinticRamp, Sine, SympyTimeFunction,
                                      Tabulated)

T = sp.Symbol("t")

# (id, function, SymPy expression written from the definition, interval of smooth t)
CLOSED_FORMS = [
    ("constant", Constant(2.5), sp.Float(2.5), (-1.0, 3.0)),
    ("cosine", Cosine(1.0, 0.5, 2.5), 1.0 + 0.5 * sp.cos(2 * sp.pi * T / 2.5), (-1.0, 6.0)),
    ("sine", Sine(-0.2, 0.3, 1.7, 0.4), -0.2 + 0.3 * sp.sin(2 * sp.pi * T / 1.7 + 0.4),
     (-1.0, 6.0)),
    ("sine-no-phase", Sine(0.0, 1.0, 3.0), sp.sin(2 * sp.pi * T / 3.0), (0.0, 6.0)),
    ("quintic-inside", QuinticRamp(1.0, 5.0),
     (T / 5) ** 3 * (10 - 15 * (T / 5) + 6 * (T / 5) ** 2), (0.0, 5.0)),
    ("sympy", SympyTimeFunction("0.3*sin(2*t) + exp(-t)*t**2"),
     0.3 * sp.sin(2 * T) + sp.exp(-T) * T ** 2, (-1.0, 4.0)),
]


@pytest.mark.parametrize("f, expr, interval", [c[1:] for c in CLOSED_FORMS],
                         ids=[c[0] for c in CLOSED_FORMS])
def test_value_rate_acceleration_match_sympy(f, expr, interval):
    rng = np.random.default_rng(11)
    derivs = sp.lambdify(T, [expr, sp.diff(expr, T), sp.diff(expr, T, 2)], "numpy")
    for t in rng.uniform(*interval, size=20):
        ref = [float(v) for v in derivs(t)]
        got = [f.value(t), f.rate(t), f.acceleration(t)]
        np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-13)
        assert f(t) == f.value(t)


TABLE = Tabulated((0.0, 0.4, 1.1, 1.5, 2.6, 3.0), (0.0, 0.8, -0.3, 0.1, 1.2, 1.0))
ALL = CLOSED_FORMS + [("tabulated", TABLE, None, (0.0, 3.0)),
                      ("quintic-ramp", QuinticRamp(-2.0, 0.7), None, (-0.5, 1.5))]


@pytest.mark.parametrize("f, interval", [(c[1], c[3]) for c in ALL], ids=[c[0] for c in ALL])
def test_derivatives_match_central_differences(f, interval):
    rng = np.random.default_rng(12)
    h = 1e-5
    # keep the stencil away from the knots of the table / the ramp's ends, where the
    # third derivative jumps (central differences are exact only for smooth pieces)
    knots = np.array(getattr(f, "times", ()) + ((0.0, f.ramp_time) if
                                                isinstance(f, QuinticRamp) else ()))
    checked = 0
    for t in rng.uniform(*interval, size=60):
        if knots.size and np.min(np.abs(knots - t)) < 10 * h:
            continue
        scale = max(1.0, abs(f.value(t)), abs(f.rate(t)), abs(f.acceleration(t)))
        fd_rate = (f.value(t + h) - f.value(t - h)) / (2 * h)
        fd_acc = (f.rate(t + h) - f.rate(t - h)) / (2 * h)
        # truncation h^2/6 |f'''| (|f'''| <~ 1e3 here) plus round-off eps scale / h
        assert abs(fd_rate - f.rate(t)) < 1e-6 * scale, t
        assert abs(fd_acc - f.acceleration(t)) < 1e-6 * scale, t
        checked += 1
    assert checked > 40


def test_tabulated_is_scipys_natural_cubic_spline():
    rng = np.random.default_rng(13)
    times = np.cumsum(rng.uniform(0.1, 0.6, size=9))
    values = rng.normal(size=9)
    f = Tabulated(tuple(times), tuple(values))
    ref = CubicSpline(times, values, bc_type="natural")
    for t in rng.uniform(times[0], times[-1], size=50):
        np.testing.assert_allclose([f.value(t), f.rate(t), f.acceleration(t)],
                                   [ref(t), ref(t, 1), ref(t, 2)], rtol=1e-12, atol=1e-12)


def test_tabulated_interpolates_is_c2_and_natural():
    f = TABLE
    eps = 1e-9
    for tk, vk in zip(f.times, f.values):
        assert f.value(tk) == pytest.approx(vk, abs=1e-15)
    for tk in f.times[1:-1]:
        for g in (f.value, f.rate, f.acceleration):
            # a jump would show as O(1); continuity leaves O(eps * next derivative)
            assert abs(g(tk + eps) - g(tk - eps)) < 1e-6
    assert abs(f.acceleration(f.times[0] + eps)) < 1e-6
    assert abs(f.acceleration(f.times[-1] - eps)) < 1e-6


def test_tabulated_is_constant_outside_its_range():
    f = TABLE
    for t in (-3.0, f.times[0] - 1e-12, f.times[0]):
        assert (f.value(t), f.rate(t), f.acceleration(t)) == (f.values[0], 0.0, 0.0)
    for t in (f.times[-1], f.times[-1] + 1e-12, 50.0):
        assert (f.value(t), f.rate(t), f.acceleration(t)) == (f.values[-1], 0.0, 0.0)
    start, end = f.end_rates()
    assert start == pytest.approx(f.rate(f.times[0] + 1e-9), abs=1e-6)
    assert end == pytest.approx(f.rate(f.times[-1] - 1e-9), abs=1e-6)


def test_two_point_table_is_a_straight_line():
    f = Tabulated([1.0, 3.0], [2.0, 5.0])
    for t in (1.5, 2.0, 2.9):
        assert f.value(t) == pytest.approx(2.0 + 1.5 * (t - 1.0), rel=1e-15)
        assert f.rate(t) == pytest.approx(1.5, rel=1e-15)
        assert f.acceleration(t) == 0.0


def test_linear_data_give_the_line_exactly_with_uneven_knots():
    times = [0.0, 0.1, 0.7, 0.8, 2.0]
    f = Tabulated(times, [3.0 - 2.0 * t for t in times])
    for t in np.linspace(0.05, 1.95, 11):
        assert f.value(t) == pytest.approx(3.0 - 2.0 * t, abs=1e-14)
        assert f.rate(t) == pytest.approx(-2.0, abs=1e-13)
        assert f.acceleration(t) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("f", [Constant(1.5), Cosine(1.0, 0.5, 2.5), Sine(0.1, 0.2, 0.3, 0.4),
                               QuinticRamp(1.0, 5.0), TABLE],
                         ids=["constant", "cosine", "sine", "quintic", "tabulated"])
def test_rebuilt_from_field_names_through_json(f):
    """gpme_io.urdf stores a drive as (class name, asdict) in JSON and rebuilds it."""
    params = json.loads(json.dumps(dataclasses.asdict(f)))
    again = getattr(tfn, type(f).__name__)(**params)
    assert again == f
    assert again.value(0.77) == f.value(0.77)


def test_field_names_are_the_documented_ones():
    names = {cls: [fl.name for fl in dataclasses.fields(cls)] for cls in (Sine, Tabulated)}
    assert names == {Sine: ["offset", "amplitude", "period", "phase"],
                     Tabulated: ["times", "values"]}
    with pytest.raises(dataclasses.FrozenInstanceError):
        Sine(0.0, 1.0, 1.0).period = 2.0


BAD = [
    ("constant-nan", lambda: Constant(math.nan), r"level must be a finite number, got nan"),
    ("constant-str", lambda: Constant("1"), r"level must be a finite number, got '1'"),
    ("cosine-period-zero", lambda: Cosine(0.0, 1.0, 0.0), r"period must be a finite number > 0 \(s\), got 0"),
    ("sine-all", lambda: Sine(math.inf, None, -1.0, math.nan),
     r"4 problems(.|\n)*offset(.|\n)*amplitude(.|\n)*phase(.|\n)*period"),
    ("quintic-ramp-negative", lambda: QuinticRamp(1.0, -5.0), r"ramp_time must be a finite number > 0 \(s\), got -5"),
    ("table-length", lambda: Tabulated([0, 1, 2], [0, 1]), r"same length, got 3 times and 2 values"),
    ("table-one-point", lambda: Tabulated([0], [1]), r"at least 2 points, got 1"),
    ("table-not-increasing", lambda: Tabulated([0, 2, 1], [0, 1, 2]),
     r"strictly increasing \(s\); not at times\[1\] = 2.0 -> times\[2\] = 1.0"),
    ("table-nan", lambda: Tabulated([0, 1], [0, math.nan]), r"values must be finite numbers; entries \[1\] = nan"),
    ("table-scalar", lambda: Tabulated(1.0, [0.0]), r"times must be a list of numbers, got 1.0"),
    ("sympy-other-symbol", lambda: SympyTimeFunction("sin(t) + w*x"),
     r"uses \['w', 'x'\]; only the time t \(s\) is allowed"),
    ("sympy-not-expression", lambda: SympyTimeFunction("t < 1"), r"not a scalar expression in t"),
]


@pytest.mark.parametrize("make, message", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_parameters_are_named(make, message):
    with pytest.raises(ModelError, match=message):
        make()

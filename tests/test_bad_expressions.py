"""Constraint and programme expressions outside the smooth case (issue 12).

A SymPy expression given to gpme_core (SympyPointConstraint, SympyTimeFunction, and
through them JointProgramme / CoordinateProgramme and the model file) is refused when it
is built if it is not a finite real expression of the allowed symbols with a second
derivative everywhere numpy can evaluate; where it is smooth its derivatives are right;
where a value leaves the domain during a run, a ConstraintError names the constraint or
programme, t, the point or coordinate, which quantity is not finite and where the
expression is not smooth.  Nothing warns, nothing divides by a Python zero.
"""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from sympy.utilities.lambdify import implemented_function

from conftest import spatial_arm
from gpme_core import expression_checks
from gpme_core.constraints import (CoordinateProgramme, JointProgramme, PointConstraint,
                                   SympyPointConstraint)
from gpme_core.errors import ConstraintError, ModelError, ModelFileError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_core.kinematics import chain_kinematics
from gpme_core.time_functions import Sine, SympyTimeFunction, TimeFunction
from gpme_io import expressions as file_expressions
from gpme_io.modelfile import load_model_file

# a warning from numpy (divide by zero, invalid value) is a failure here
pytestmark = pytest.mark.filterwarnings("error")

X, Y, Z, T = sp.symbols("x y z t")
ROOT = Path(__file__).resolve().parents[1]
ARM3_URDF = ROOT / "tests" / "data" / "modelfiles" / "arm3.urdf"
SMOOTH = r"the GPME needs the second derivative of every constraint and programme"


# ============================================================ refused when built (Python API)
REFUSED = [
    ("abs", lambda: SympyPointConstraint(sp.Abs(X) - 0.3, name="edge"),
     r"constraint 'edge': Abs\(x\) is not smooth: its derivative jumps where its argument is "
     r"0 \(use e\.g\. sqrt\(u\*\*2 \+ eps\*\*2\)\); " + SMOOTH),
    ("abs-python-builtin-in-string", lambda: SympyPointConstraint("abs(y) - 0.1", name="edge"),
     r"'edge': Abs\(y\) is not smooth"),
    ("sign", lambda: SympyPointConstraint("sign(x)*y", name="C"),
     r"'C': sign\(x\) is not smooth: it jumps at 0 \(use e\.g\. tanh\(u/eps\)\)"),
    ("dirac-delta", lambda: SympyPointConstraint(X + sp.DiracDelta(Y), name="C"),
     r"'C': DiracDelta\(y\) is not smooth: it is a distribution, not a function"),
    ("heaviside-programme", lambda: SympyTimeFunction(sp.Heaviside(T - 1), name="lift"),
     r"time function 'lift': Heaviside\(t - 1\) is not smooth: it jumps at 0"),
    ("piecewise", lambda: SympyPointConstraint(sp.Piecewise((X, T < 1), (Y, True)), name="C"),
     r"Piecewise\(\(x, t < 1\), \(y, True\)\) is not smooth: its pieces meet"),
    ("max", lambda: SympyPointConstraint("Max(x, y) - 1", name="C"),
     r"Max\(x, y\) is not smooth: it has a kink where its arguments are equal"),
    ("min-programme", lambda: SympyTimeFunction(sp.Min(T, 1)),
     r"SympyTimeFunction: Min\(1, t\) is not smooth: it has a kink"),
    ("floor-division", lambda: SympyPointConstraint("x//2 - y", name="C"),
     r"floor\(x/2\) is not smooth: it jumps at every integer"),
    ("modulo", lambda: SympyTimeFunction("t % 1"),
     r"Mod\(t, 1\) is not smooth: it jumps at every multiple of its modulus"),
    ("real-part", lambda: SympyPointConstraint(sp.re(X) - 1, name="C"),
     r"re\(x\) is not smooth: it is a part of a complex number"),
    ("complex-I", lambda: SympyPointConstraint(X + sp.I, name="C"),
     r"'C': I is complex; constraints and programmes are real"),
    ("complex-python", lambda: SympyTimeFunction(1j * T),
     r"I is complex; constraints and programmes are real"),
    ("zoo", lambda: SympyPointConstraint("x/0", name="C"),
     r"'C': zoo is infinite or undefined; constraints and programmes must be finite"),
    ("nan-float", lambda: SympyTimeFunction(float("nan")),
     r"nan is infinite or undefined"),
    ("infinity", lambda: SympyTimeFunction(T * sp.oo), r"oo is infinite or undefined"),
    ("constant-not-real", lambda: SympyPointConstraint(X + sp.asin(2), name="C"),
     r"the constant asin\(2\) = 1\.5708-1\.31696j is not a real number"),
    ("constant-overflows", lambda: SympyPointConstraint(X * sp.Integer(10) ** 400, name="C"),
     r"the constant 1\.00000e\+400 is beyond float64's range"),
    ("undefined-function", lambda: SympyPointConstraint(sp.Function("f")(X) - 1, name="C"),
     r"'C': f\(x\) is an undefined function \(sympy\.Function\('f'\)\): gpme needs its "
     r"formula"),
    ("undefined-function-in-string", lambda: SympyTimeFunction("g(t)"),
     r"g\(t\) is an undefined function"),
    ("implemented-function", lambda: SympyTimeFunction(implemented_function("h", abs)(T)),
     r"h\(t\) is an undefined function"),
    ("unknown-symbol", lambda: SympyPointConstraint("x + w", name="C"),
     r"'C': expression 'w \+ x' uses \['w'\]; only x, y, z \(world coordinates, m\) and t "
     r"\(s\) are allowed"),
    ("not-an-expression", lambda: SympyPointConstraint("x +* y", name="C"),
     r"'C': cannot read 'x \+\* y' as a SymPy expression \(SyntaxError: invalid syntax"),
    ("comparison", lambda: SympyPointConstraint("x < 1", name="C"),
     r"'x < 1' is not a scalar expression in x, y, z, t \(got a StrictLessThan\)"),
    ("matrix", lambda: SympyPointConstraint(sp.Matrix([X, Y]), name="C"),
     r"Matrix\(\[\[x\], \[y\]\]\) is not a scalar expression"),
    ("none", lambda: SympyTimeFunction(None),
     r"None is neither a SymPy expression nor a string"),
    ("no-numpy-form", lambda: SympyPointConstraint(sp.besselj(0, X) - 0.5, name="C"),
     r"'C': besselj\(0, x\) \(in besselj\(0, x\) - 0\.5 or its derivatives\) has no math "
     r"form: sympy\.lambdify would write it as an unknown name"),
    ("unprintable", lambda: SympyTimeFunction(sp.fresnels(T)),
     r"fresnels\(t\) \(in fresnels\(t\) or its derivatives\) cannot be written as math code"),
    ("unevaluated-derivative", lambda: SympyPointConstraint(sp.Derivative(sp.sin(X), X),
                                                            name="C"),
     r"Derivative\(sin\(x\), x\) .*cannot be written as math code"),
    ("derivative-not-printable", lambda: SympyPointConstraint(sp.gamma(X + 3) - 2, name="C"),
     r"polygamma\(0, x \+ 3\) \(in gamma\(x \+ 3\) - 2 or its derivatives\) has no math form"),
    ("time-only-constraint", lambda: SympyPointConstraint("t - 1", name="C"),
     r"'t - 1' does not depend on x, y or z, so its Jacobian row is zero"),
    ("every-problem-at-once", lambda: SympyPointConstraint("Abs(x) + w + sign(y) + I",
                                                           name="many"),
     r"4 problems in the model:\n  - constraint 'many': .*uses \['w'\].*\n  - .*I is complex"
     r".*\n  - .*Abs\(x\) is not smooth.*\n  - .*sign\(y\) is not smooth"),
]


@pytest.mark.parametrize("make, message", [c[1:] for c in REFUSED], ids=[c[0] for c in REFUSED])
def test_bad_expression_is_refused_when_built(make, message):
    with pytest.raises(ModelError, match=message):
        make()


def test_joint_and_coordinate_programmes_refuse_through_their_function():
    """The programmes take a TimeFunction: a bad expression is refused when it is built,
    before the programme exists; a bare expression is not a TimeFunction."""
    with pytest.raises(ModelError, match=r"time function 'q2': Abs\(t - 1\) is not smooth"):
        JointProgramme("q2", SympyTimeFunction("Abs(t - 1)", name="q2"))
    with pytest.raises(ModelError, match=r"function must be a TimeFunction.*got str"):
        CoordinateProgramme("0.3*sin(t)", axis=2)


def test_a_symbol_with_assumptions_is_taken_by_name():
    xr = sp.Symbol("x", real=True)
    c = SympyPointConstraint(xr ** 2 - 1, name="C")
    assert c.expr == X ** 2 - 1
    assert c.local_terms(np.array([2.0, 0.0, 0.0]), 0.0)[0] == 3.0


def test_file_parser_and_python_api_share_one_table():
    assert file_expressions.NON_SMOOTH is expression_checks.NON_SMOOTH
    assert file_expressions.singular_sets is expression_checks.singular_sets
    for cls in expression_checks.NON_SMOOTH_TYPES:       # every refused class has a file name
        assert any(expression_checks.NON_SMOOTH_TYPES[cls] == r
                   for r in expression_checks.NON_SMOOTH.values())


# ============================================================ not finite where evaluated
def arm_point(q):
    """World position (3,) m of the arm's frame E at q."""
    arm = spatial_arm()
    kin = chain_kinematics(arm, q)
    fr = arm.frame("E")
    return (kin.T[fr.link_index] @ fr.transform[:, 3])[:3]


NOT_FINITE = [
    ("sqrt-of-negative", "sqrt(x - 1) - 0.1", (0.2, 0.0, 0.3), 0.0,
     r"constraint 'C': phi = sqrt\(x - 1\) - 0\.1 on frame 'E' is not finite at t = 0 s, "
     r"x, y, z = 0\.2, 0, 0\.3 m: phi = nan, grad\[x\] = nan, Hessian\[x, x\] = nan; where it "
     r"is not smooth or out of its domain: sqrt: where x - 1 <= 0"),
    ("pole", "1/y - 2", (0.2, 0.0, 0.3), 0.0,
     r"is not finite at t = 0 s, x, y, z = 0\.2, 0, 0\.3 m: phi = inf, grad\[y\] = -inf, "
     r"Hessian\[y, y\] = inf; .*division: where y = 0"),
    ("log-of-negative", "log(z) - 1", (0.2, 0.0, -0.3), 0.5,
     r"not finite at t = 0\.5 s, x, y, z = 0\.2, 0, -0\.3 m: phi = nan; .*log: where z <= 0"),
    ("atan2-at-origin", "atan2(y, x) - t", (0.0, 0.0, 0.3), 0.1,
     r"t = 0\.1 s, x, y, z = 0, 0, 0\.3 m: grad\[x\] = nan, grad\[y\] = nan, Hessian\[x, x\] = "
     r"nan.*atan2: where y = x = 0"),
    ("time-pole", "z - 1/(t - 0.5)", (0.2, 0.0, 0.3), 0.5,
     r"t = 0\.5 s.*phi = -?inf, phi_t = -?inf, phi_tt = -?inf; .*division: where t - 0\.5 = 0"),
    ("overflow", "exp(1000*x) - 1", (1.0, 0.0, 0.3), 0.0,
     r"phi = inf, grad\[x\] = inf, Hessian\[x, x\] = inf; it has no singular point known here: "
     r"a value overflowed float64"),
    ("point-not-finite", "x - 1", (np.nan, 0.0, 0.3), 0.0,
     r"x, y, z = nan, 0, 0\.3 m: phi = nan; the state it was evaluated at is itself not finite"),
]


@pytest.mark.parametrize("phi, p, t, message", [c[1:] for c in NOT_FINITE],
                         ids=[c[0] for c in NOT_FINITE])
def test_non_finite_constraint_value_names_constraint_time_point_and_quantity(phi, p, t,
                                                                               message):
    c = SympyPointConstraint(phi, name="C")
    with pytest.raises(ConstraintError, match=message):
        c.local_terms(np.array(p), t)            # t a Python float: no ZeroDivisionError
    assert c.non_finite_terms(np.array(p), t)    # the same check without raising


@pytest.mark.parametrize("method, quantity", [("value", "f = inf"), ("rate", "f' = -inf"),
                                              ("acceleration", "f'' = inf"),
                                              ("derivatives", "f = inf, f' = -inf, f'' = inf"),
                                              ("__call__", "f = inf")])
def test_time_function_at_its_pole(method, quantity):
    f = SympyTimeFunction("1/(t - 0.05)", name="lift")
    with pytest.raises(ConstraintError, match=r"time function 'lift' f\(t\) = 1/\(t - 0\.05\) is "
                       r"not finite at t = 0\.05 s: " + quantity + r"; .*division: where t - "
                       r"0\.05 = 0"):
        getattr(f, method)(0.05)
    assert f.derivatives(0.04) == pytest.approx((-100.0, -1e4, -2e6))


def test_time_function_out_of_its_domain():
    f = SympyTimeFunction("sqrt(1 - t)")
    with pytest.raises(ConstraintError, match=r"not finite at t = 2 s: f = nan; .*sqrt: where "
                       r"1 - t <= 0"):
        f(2)
    with pytest.raises(ConstraintError, match=r"at t = 1 s: f' = -inf, f'' = -inf"):
        f.derivatives(1.0)


def test_pole_at_the_start_stops_the_run_before_any_step():
    arm = spatial_arm()
    zero = np.zeros(arm.n_coordinates)
    y0 = float(arm_point(zero)[1])
    system = ProgrammedMotion(arm, [SympyPointConstraint(f"1/(y - {y0!r}) - 1", name="pole")])
    with pytest.raises(ConstraintError, match=r"constraint 'pole': .* is not finite at t = 0 s, "
                       r"x, y, z = .* m: phi = inf, grad\[y\] = -inf, .*division: where"):
        simulate(system, 0.01, zero, zero, dt=1e-3)


def test_sqrt_of_negative_at_the_start_stops_on_manifold_placement():
    arm = spatial_arm()
    zero = np.zeros(arm.n_coordinates)
    x0 = float(arm_point(zero)[0])
    system = ProgrammedMotion(arm, [SympyPointConstraint(f"sqrt(x - {x0 + 0.01!r})",
                                                         name="reach")], dependent=["q1"])
    with pytest.raises(ConstraintError, match=r"constraint 'reach'.*t = 0 s.*phi = nan.*sqrt: "
                       r"where x - 0\.90"):
        simulate(system, 0.01, zero, zero, dt=1e-3, on_manifold=True)


def test_programme_pole_in_the_middle_of_a_run():
    """q2 = 0.001/(t - 0.05) run to 0.1 s: the stage at t = 0.05 s stops the run."""
    arm = spatial_arm()
    zero = np.zeros(arm.n_coordinates)
    system = ProgrammedMotion(arm, [JointProgramme("q2", SympyTimeFunction("0.001/(t - 0.05)"),
                                                   name="pole")])
    with pytest.raises(ConstraintError, match=r"programme 'pole' \(q2 = f\(t\), at q2 = "
                       r"-?[0-9.]+\): time function f\(t\) = 0\.001/\(t - 0\.05\) is not finite "
                       r"at t = 0\.05 s: f = inf, f' = -inf, f'' = inf; .*division: where "
                       r"t - 0\.05 = 0"):
        simulate(system, 0.1, zero, zero, dt=1e-3, on_manifold=True)


def test_point_constraint_leaves_its_domain_in_the_middle_of_a_run():
    arm = spatial_arm()
    zero = np.zeros(arm.n_coordinates)
    z0 = float(arm_point(zero)[2])
    system = ProgrammedMotion(arm, [SympyPointConstraint(f"z - {z0!r} - 0.01*sqrt(0.05 - t)",
                                                         name="dip")])
    with pytest.raises(ConstraintError, match=r"constraint 'dip': .* is not finite at t = 0\.05 "
                       r"s, x, y, z = .* m: phi_t = -?inf, phi_tt = -?inf; .*sqrt: where "
                       r"0\.05 - t <= 0"):
        simulate(system, 0.1, zero, zero, dt=1e-3)


def test_coordinate_programme_names_itself_and_the_point():
    c = CoordinateProgramme(SympyTimeFunction("0.3 + 0.1*log(1 - t)"), axis=2, name="lift")
    with pytest.raises(ConstraintError, match=r"programme 'lift' \(z of frame 'E' = f\(t\), at "
                       r"x, y, z = 0\.1, 0\.2, 0\.3 m\): time function .* not finite at t = 1 s: "
                       r"f = -inf, f' = -inf, f'' = -inf; .*log: where 1 - t <= 0"):
        c.local_terms(np.array([0.1, 0.2, 0.3]), 1.0)


class _Broken(PointConstraint):
    """A user's own constraint class whose terms go non-finite."""
    name, frame = "mine", "E"

    def local_terms(self, p, t):
        return (float("nan"), np.zeros(3), np.zeros((3, 3)), 0.0, np.zeros(3), 0.0)


class _Spike(TimeFunction):
    def value(self, t):
        return 0.0

    def rate(self, t):
        return 0.0

    def acceleration(self, t):
        return float("inf")


@pytest.mark.parametrize("spec, message", [
    (_Broken(), r"constraint 'mine' \(_Broken on frame 'E'\) is not finite at t = 0\.2 s, x, y, "
                r"z = .* m: Phi = nan"),
    (JointProgramme("q2", _Spike(), name="spike"),
     r"programme 'spike' \(q2 = f\(t\), at q2 = 0\): the time function .* is not finite at "
     r"t = 0\.2 s: f = 0, f' = 0, f'' = inf"),
], ids=["user-point-constraint", "user-time-function"])
def test_user_classes_that_go_non_finite_are_named(spec, message):
    arm = spatial_arm()
    system = ProgrammedMotion(arm, [spec])
    zero = np.zeros(arm.n_coordinates)
    with pytest.raises(ConstraintError, match=message):
        system.constraints(0.2, zero, zero)


# ============================================================ right where smooth
SMOOTH_CASES = [
    ("distance", "sqrt(x**2 + y**2) - 0.5"),
    ("pole-away", "1/(y + 2) - 0.4"),
    ("log", "log(z + 1) - 0.1*t"),
    ("atan2", "atan2(y, x) - 0.3*sin(t)"),
    ("moving", "(x - 0.1*cos(2*t))**2 + y*exp(-t) + z*t**2"),
]


@pytest.mark.parametrize("phi", [c[1] for c in SMOOTH_CASES], ids=[c[0] for c in SMOOTH_CASES])
def test_derivatives_where_smooth_match_finite_differences(phi, rng):
    c = SympyPointConstraint(phi, name="C")
    h = 1e-5
    e = np.eye(3)
    for _ in range(4):
        p = rng.uniform([0.3, 0.2, 0.1], [0.9, 0.8, 0.6])     # away from every singular set
        t = float(rng.uniform(0.0, 2.0))
        phi0, grad, hess, phi_t, grad_t, phi_tt = c.local_terms(p, t)

        def value(pp, tt):
            return c.local_terms(pp, tt)[0]
        fd_grad = [(value(p + h * e[k], t) - value(p - h * e[k], t)) / (2 * h) for k in range(3)]
        fd_hess = [[(c.local_terms(p + h * e[k], t)[1][j] - c.local_terms(p - h * e[k], t)[1][j])
                    / (2 * h) for j in range(3)] for k in range(3)]
        fd_phi_t = (value(p, t + h) - value(p, t - h)) / (2 * h)
        fd_grad_t = (c.local_terms(p, t + h)[1] - c.local_terms(p, t - h)[1]) / (2 * h)
        fd_phi_tt = (c.local_terms(p, t + h)[3] - c.local_terms(p, t - h)[3]) / (2 * h)
        np.testing.assert_allclose(grad, fd_grad, rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose(hess, fd_hess, rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(hess, hess.T, rtol=1e-12, atol=1e-12)
        assert phi_t == pytest.approx(fd_phi_t, rel=1e-7, abs=1e-8)
        np.testing.assert_allclose(grad_t, fd_grad_t, rtol=1e-6, atol=1e-7)
        assert phi_tt == pytest.approx(fd_phi_tt, rel=1e-6, abs=1e-7)
        assert np.isfinite(phi0)


@pytest.mark.parametrize("expr", ["sqrt(1 - t)", "1/(t + 2)", "log(t + 1)*sin(3*t)"])
def test_time_function_derivatives_where_smooth(expr, rng):
    f = SympyTimeFunction(expr)
    h = 1e-5
    for t in rng.uniform(0.0, 0.9, size=4):
        v, r, a = f.derivatives(t)
        assert (v, r, a) == (f.value(t), f.rate(t), f.acceleration(t))
        assert r == pytest.approx((f(t + h) - f(t - h)) / (2 * h), rel=1e-7, abs=1e-9)
        assert a == pytest.approx((f.rate(t + h) - f.rate(t - h)) / (2 * h), rel=1e-6, abs=1e-8)


# ============================================================ model files
def model_text(constraint='phi = "z - (0.2 - 0.05*sin(2*pi*t))"', programme='q = "0.2*sin(3*t)"',
               extra="", t_end=0.05):
    """A model file of the small arm3 (tests/data/modelfiles/arm3.toml) with its constraint
    and programme expressions replaced."""
    return (f'[model]\nname = "arm3_bad"\nurdf = "{ARM3_URDF.as_posix()}"\n'
            'gravity = [0.0, 0.0, -9.81]\n\n[chain]\nroot = "base_link"\ntip = "tool"\n\n'
            f'[[constraint]]\nname = "tool_height"\nframe = "tool"\n{constraint}\n\n'
            f'[[programme]]\nname = "yaw_q"\njoint = "yaw"\n{programme}\n\n{extra}'
            '[initial]\nq = { shoulder = 0.3, elbow = -0.6 }\non_constraints = true\n\n'
            f'[run]\nt_end = {t_end}\ndt = 1e-3\noutput_dt = 0.01\n')


def write(tmp_path, text, name="bad.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_model_text_is_a_good_model(tmp_path):
    s = load_model_file(write(tmp_path, model_text()))
    assert s.system.constraint_names == ("tool_height", "yaw_q")


FILE_REFUSED = [
    ("abs", dict(constraint='phi = "abs(z - 0.2)"'),
     r"constraint\[0\]\.phi: 'abs\(z - 0\.2\)': abs\(\) is not smooth: its derivative jumps"),
    ("real-part-from-the-shared-table", dict(constraint='phi = "re(z) - 0.2"'),
     r"constraint\[0\]\.phi: 're\(z\) - 0\.2': re\(\) is not smooth: it is a part of a complex "
     r"number"),
    ("constant-not-real", dict(constraint='phi = "z - 0.2 + asin(2)"'),
     r"constraint\[0\]\.phi: 'z - 0\.2 \+ asin\(2\)' = .*: the constant asin\(2\) = .* is not "
     r"a real number"),
    ("dirac-programme", dict(programme='q = "0.1*DiracDelta(t - 0.01)"'),
     r"programme\[0\]\.q: .*DiracDelta\(\) is not smooth: it is a distribution"),
    ("heaviside-drive", dict(extra='[[drive]]\njoint = "elbow"\ntype = "expression"\n'
                                   'f = "Heaviside(t - 0.01)"\n\n'),
     r"drive\[0\]\.f: .*Heaviside\(\) is not smooth: it jumps at 0"),
]


@pytest.mark.parametrize("parts, message", [c[1:] for c in FILE_REFUSED],
                         ids=[c[0] for c in FILE_REFUSED])
def test_model_file_refuses_bad_expressions(tmp_path, parts, message):
    with pytest.raises(ModelFileError, match=message):
        load_model_file(write(tmp_path, model_text(**parts)))


# the tool starts at x, y, z = 0.669, 0, 0.170 m (yaw = 0: y is exactly 0)
FILE_NOT_FINITE = [
    ("sqrt-of-negative-at-start", dict(constraint='phi = "sqrt(z - 5)"'),
     r"'tool_height'.*t = 0 s.*0\.668736, 0, 0\.170448 m\)?: phi = nan, grad\[z\] = nan, "
     r"Hessian\[z, z\] = nan.*sqrt: where z - 5 <= 0"),
    ("pole-at-start", dict(constraint='phi = "z - 0.2 + 0.001/y"'),
     r"'tool_height'.*t = 0 s.*phi = inf, grad\[y\] = -inf.*division: where y = 0"),
    ("log-of-negative-at-start", dict(constraint='phi = "log(z - 1) + 1"'),
     r"'tool_height'.*t = 0 s.*phi = nan.*log: where z - 1 <= 0"),
    ("programme-pole-within-the-run", dict(programme='q = "0.2*sin(3*t) + 0.001/(t - 0.025)"'),
     r"(programme\[0\]\.q: not finite at t = 0\.025 s|time function f\(t\) = 0\.2\*sin\(3\*t\) "
     r"\+ 0\.001/\(t - 0\.025\) is not finite at t = 0\.025 s: f = inf).*division: where "
     r"t - 0\.025 = 0"),
]


@pytest.mark.parametrize("parts, message", [c[1:] for c in FILE_NOT_FINITE],
                         ids=[c[0] for c in FILE_NOT_FINITE])
def test_model_file_expression_not_finite_is_found_before_the_run(tmp_path, parts, message):
    # ModelFileError once gpme_io.modelfile lists it with its key; a ConstraintError from the
    # expression itself until then: either names the constraint, t, the point and quantity
    with pytest.raises((ModelFileError, ConstraintError), match=message):
        load_model_file(write(tmp_path, model_text(**parts)))


CLI = [
    ("sqrt-at-start", dict(constraint='phi = "sqrt(z - 5)"'),
     ("'tool_height'", "t = 0 s", "phi = nan", "sqrt: where z - 5 <= 0")),
    # the file's run ends before the programme leaves its domain; --t-end runs past it
    ("programme-out-of-domain-mid-run", dict(programme='q = "0.2*sin(3*t) + 0.1*sqrt(0.03 - t)"',
                                             t_end=0.02),
     ("programme 'yaw_q' (yaw = f(t), at yaw = ", "not finite at t = 0.03 s: f = nan",
      "sqrt: where 0.03 - t <= 0")),
]


@pytest.mark.parametrize("parts, words", [c[1:] for c in CLI], ids=[c[0] for c in CLI])
def test_cli_exits_2_with_the_message(tmp_path, parts, words):
    path = write(tmp_path, model_text(**parts))
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "gpme.cli", "simulate", "--model", str(path),
                          "--t-end", "0.05", "--out", str(out), "--no-progress"],
                         capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr
    assert run.stderr.startswith("error: ")
    for w in words:
        assert w in run.stderr
    assert "Warning" not in run.stderr

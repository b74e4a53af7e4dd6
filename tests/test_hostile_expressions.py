"""Hostile expressions, axes and constraint sets (issue 24): bounded work, no silent
non-smooth result, and messages that name the cause.

By class:

- explosive expressions (powers, factorials, nesting, derivative size): refused before
  SymPy evaluates or differentiates them, with the bound and why, in well under a second
  (the time asserts are hang guards only);
- disguised non-smooth constraints and programmes (sqrt of a square, log of a square
  root): the run's smoothness check (gpme_core.smoothness, a row of
  crosscheck.run_checks) fails naming the expression, the time and "not smooth"; smooth
  expressions, with and without sqrt and log, pass;
- poles crossed mid-run: the failure names the expression, its singular set and the time
  it is reached, not an unstable step;
- degenerate joint axes (URDF and Python API): refused where they are read, with the
  joint, the axis and its length;
- constraints dependent at the start: named as dependent, with the rows' relation.

Three cases run through ``python -m gpme.cli simulate`` in a subprocess (status, words, no
traceback, a timeout).
"""
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from crosscheck.run_checks import run_rows
from gpme_core import expression_bounds as bounds
from gpme_core.constraints import SympyPointConstraint
from gpme_core.errors import (ConstraintError, GpmeError, ModelError, ModelFileError,
                              SimulationError, UnstableStepError)
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.integrate import simulate
from gpme_core.model import REVOLUTE, ChainBuilder
from gpme_core.smoothness import KINK_TOL, check_run, kink_measures
from gpme_core.time_functions import SympyTimeFunction
from gpme_io import expressions as file_expressions
from gpme_io.modelfile import load_model_file
from gpme_io.urdf_reader import read_urdf

ROOT = Path(__file__).resolve().parents[1]
MY_ARM = ROOT / "examples" / "my_arm"
POINT = {"x": "m", "y": "m", "z": "m", "t": "s"}
HANG_GUARD_S = 5.0          # a refusal takes milliseconds; this only catches a hang


def _timed(f):
    start = time.perf_counter()
    out = f()
    return out, time.perf_counter() - start


# ============================================================ explosive expressions
# (text, words of the model-file message)
EXPLOSIVE = [
    ("9**9**9", ["'9**9**9'", "a constant power with about 3.7e8 digits",
                 "limited to results of 400 digits"]),
    ("9**9**8", ["about 4.1e7 digits"]),
    ("x + 9**9**9", ["'x + 9**9**9': 9**9**9: a constant power"]),
    ("z - 10**9**9/10**9**9", ["10**9**9: a constant power with about 3.9e8 digits"]),
    ("2**10**5*x", ["2**10**5: a constant power with about 3.0e4 digits"]),
    ("0.5**(9**9) + x", ["a constant power"]),
    ("(2*x)**10**6", ["the exponent 1000000 of a coordinate or time is above 1000"]),
    ("(123456789*x)**1000", ["distributes onto the constant factor 123456789",
                             "about 8092 digits"]),
    ("1" * 500 + "*x", ["a constant of about 499 digits", "limited to 400 digits"]),
    ("sin(" * 150 + "x" + ")" * 150, ["nested more than 100 deep", "bound on expression depth"]),
    ("-" * 4000 + "x", ["nested more than 100 deep"]),
    ("x**" * 1500 + "x", ["nested more than 100 deep"]),
    ("*".join(f"sin(x + {k}*y + z)" for k in range(1, 30)),
     ["its second derivatives would have about", "at most 50,000",
      "fewer nested functions or factors"]),
    ("sin(" * 40 + "x*y*z*t" + ")" * 40, ["its second derivatives would have about"]),
    ("x*sin(exp(exp(exp(5))))", ["sin(exp(exp(exp(5)))): sin() of a constant of about "
                                 "10**1.2e64; constant arguments are limited to 10**400"]),
    ("x*exp(exp(exp(10)))", ["exp() of a constant of about 10**9566"]),
]


@pytest.mark.parametrize("text,words", EXPLOSIVE, ids=[f"file-{k}" for k in range(len(EXPLOSIVE))])
def test_model_file_parser_refuses_explosive_expressions_at_once(text, words):
    (expr, problems), seconds = _timed(lambda: file_expressions.parse_expression(text, POINT))
    assert seconds < HANG_GUARD_S
    assert expr is None and len(problems) == 1
    for word in words:
        assert word in problems[0], (word, problems[0])


# (value given to SympyPointConstraint, words of the ModelError)
API_EXPLOSIVE = [
    ("9**9**9", ["constraint 'C': '9**9**9': 9**(9**9): a constant power with about 3.7e8"]),
    ("x + 9**9**8", ["9**(9**8): a constant power with about 4.1e7 digits"]),
    ("x*factorial(10**7)", ["factorial(10**7): factorial() of a number about 10**7",
                            "evaluated only up to 1000"]),
    ("x + gamma(10**8)", ["gamma() of a number about 10**8"]),
    ("x + binomial(10**9, 10**8)", ["binomial() of a number"]),
    ("(x + 1)**1001", ["the exponent 1001 of a coordinate or time is above 1000"]),
    ("E**(10**9)*x", ["E**(10**9): a constant power with about 4.3e8 digits"]),
    ("x*cos(exp(exp(exp(5))))", ["cos() of a constant of about 10**1.2e64"]),
    ("-" * 3000 + "x", ["nested more than 100 deep"]),
    ("sin(" * 2000 + "x" + ")" * 2000, ["cannot read", "too many nested parentheses"]),
    ("*".join(f"cos(x + {k}*y - z)" for k in range(1, 25)),
     ["its second derivatives would have about"]),
]


@pytest.mark.parametrize("value,words", API_EXPLOSIVE,
                         ids=[f"api-{k}" for k in range(len(API_EXPLOSIVE))])
def test_python_api_reads_strings_without_evaluating_explosions(value, words):
    def build():
        with pytest.raises(ModelError) as exc:
            SympyPointConstraint(value, name="C")
        return str(exc.value)
    message, seconds = _timed(build)
    assert seconds < HANG_GUARD_S
    for word in words:
        assert word in message, (word, message)


def test_python_api_refuses_a_deep_sympy_expression_without_printing_it():
    x = sp.Symbol("x")
    deep = x
    for _ in range(150):            # SymPy builds this; printing it would recurse deeply
        deep = sp.sin(deep)
    with pytest.raises(ModelError, match="'C': the expression: nested more than 100 deep"):
        SympyPointConstraint(deep, name="C")


def test_time_function_refuses_a_power_tower():
    with pytest.raises(ModelError, match=r"time function 'f': '2\*\*2\*\*2\*\*2\*\*2\*\*2"
                                         r"\*t': 2\*\*\(2\*\*\(2\*\*\(2\*\*2\)\)\): a "
                                         r"constant power with about 2\.0e4 digits"):
        SympyTimeFunction("2**2**2**2**2**2*t", name="f")


def test_bounds_accept_what_models_need():
    """Powers, roots and products that stay small are built as SymPy builds them."""
    for text in ("x**(1/3) + (x + 1)**1000 - 2**0.5", "9**9*x", "(x/3)**100",
                 "x**x**x", "1**9**9*z", "sqrt(" * 60 + "x**2 + 1" + ")" * 60,
                 "(y - 0.11)*cos(2*pi*t/4) - (x - 0.5)*sin(2*pi*t/4)",
                 " + ".join(f"{k}*x**2" for k in range(1, 400)),    # a flat sum, not nested
                 "x" + "*y/2" * 200):
        (expr, problems), seconds = _timed(lambda: file_expressions.parse_expression(text, POINT))
        assert problems == [] and expr is not None, (text, problems)
        assert seconds < HANG_GUARD_S
    assert SympyPointConstraint("9**9*x - 1").expr == 387420489 * sp.Symbol("x") - 1


def test_derivative_estimate_bounds_the_real_derivatives():
    """The product-rule estimate is above the size SymPy's second derivatives really have
    (so the bound holds the real work), on the shapes that grow fastest."""
    x, y, z = sp.symbols("x y z")
    for expr in (sp.Mul(*[sp.sin(x + k * y + z) for k in range(1, 6)]),
                 sp.sin(sp.sin(sp.sin(sp.sin(x * y)))), ((x ** 2 + y) ** 2 + z) ** 3):
        real = sum(sp.count_ops(sp.diff(expr, a, b), visual=False) + 1
                   for a in (x, y, z) for b in (x, y, z))
        assert bounds.derivative_nodes(expr) >= real


def test_model_file_names_the_key_of_an_explosive_expression(tmp_path):
    model = _my_arm(tmp_path, {'phi = "z - 0.3"': 'phi = "z - 9**9**9"'})
    start = time.perf_counter()
    with pytest.raises(ModelFileError, match=r"constraint\[1\]\.phi: 'z - 9\*\*9\*\*9': "
                                             r"9\*\*9\*\*9: a constant power"):
        load_model_file(model)
    assert time.perf_counter() - start < HANG_GUARD_S


# ============================================================ disguised non-smooth
def _my_arm(tmp_path, replace):
    """examples/my_arm with text replaced ({old: new}) in its model file."""
    text = (MY_ARM / "my_arm.toml").read_text()
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    shutil.copy(MY_ARM / "my_arm.urdf", tmp_path / "my_arm.urdf")
    path = tmp_path / "my_arm.toml"
    path.write_text(text)
    return path


def _run(tmp_path, replace, t_end=0.5):
    """(scenario, history) of examples/my_arm changed by ``replace``: RK4 at 1 ms in the
    Python loop (no compilation: a fraction of a second)."""
    scenario = load_model_file(_my_arm(tmp_path, replace))
    df = simulate(scenario.system, t_end, scenario.q0, scenario.q_dot0, dt=1e-3,
                  compiled=False)
    return scenario, df


def _smoothness_rows(scenario, df):
    return {r["quantity"]: r for r in run_rows(scenario, df)
            if r["quantity"].startswith("smoothness of ")}


# (id, replacements in my_arm.toml, the row that fails, words of its entry)
NOT_SMOOTH = [
    ("sqrt-of-square-on-the-kink", {'phi = "z - 0.3"': 'phi = "sqrt((z - 0.3)**2)"'},
     "smoothness of constraint 'height'",
     ["phi = sqrt((z - 0.3)**2) is not smooth where the run goes",
      "sqrt: where (z - 0.3)**2 <= 0 is reached at t = 0.0000 s"]),
    ("sqrt-of-square-approached", {'phi = "z - 0.3"': 'phi = "sqrt((z - 0.3)**2)"',
                                   "on_constraints = true": "on_constraints = false",
                                   "shoulder = -0.3": "shoulder = -0.25"},
     "smoothness of constraint 'height'",
     ["phi = sqrt((z - 0.3)**2) is not smooth", "sqrt: where (z - 0.3)**2 <= 0 is reached "
      "at t = 0.4"]),
    ("programme-sqrt-of-square", {'q = "0.8*sin(pi*t)"': 'q = "0.5*sqrt((t - 0.2513)**2)"'},
     "smoothness of programme 'Phi_yaw' (yaw = f(t))",
     ["f(t) = 0.5*sqrt((t - 0.2513)**2) is not smooth where the run goes",
      "its gradient jumps between t = 0.2510 s and the next sample"]),
    ("programme-log-of-square-root",
     {'q = "0.8*sin(pi*t)"': 'q = "0.3*log(1 + sqrt((t - 0.2513)**2))"'},
     "smoothness of programme 'Phi_yaw' (yaw = f(t))",
     ["f(t) = 0.3*log(sqrt((t - 0.2513)**2) + 1) is not smooth",
      "its gradient jumps between t = 0.2510 s"]),
    ("constraint-kink-in-time", {'phi = "z - 0.3"': 'phi = "z - 0.3 - 0.05*sqrt((t - 0.2013)**2)"'},
     "smoothness of constraint 'height'",
     ["is not smooth where the run goes", "its gradient jumps between t = 0.2010 s"]),
]


@pytest.mark.parametrize("replace,quantity,words", [c[1:] for c in NOT_SMOOTH],
                         ids=[c[0] for c in NOT_SMOOTH])
def test_a_run_through_a_kink_fails_its_smoothness_check(tmp_path, replace, quantity, words):
    scenario, df = _run(tmp_path, replace)
    rows = _smoothness_rows(scenario, df)
    row = rows[quantity]
    assert row["status"] == "fail" and row["abs_error"] == np.inf
    for word in words:
        assert word in row["entry"], (word, row["entry"])
    others = [r for q, r in rows.items() if q != quantity]
    assert all(r["status"] == "pass" for r in others), others


# (id, replacements) of smooth expressions, some with sqrt and log, that must pass
SMOOTH = [
    ("my-arm", {}),
    ("circle-with-sqrt", {'phi = "x**2 + y**2 - 0.45**2"': 'phi = "sqrt(x**2 + y**2) - 0.45"'}),
    ("height-with-log", {'phi = "z - 0.3"': 'phi = "log(z/0.3)"'}),
    ("programme-with-division", {'q = "0.8*sin(pi*t)"': 'q = "0.8*sin(pi*t)/(1 + t**2)"'}),
    ("programme-smoothed-abs", {'q = "0.8*sin(pi*t)"':
                                'q = "0.5*sqrt((t - 0.2513)**2 + 0.05**2)"'}),
]


@pytest.mark.parametrize("replace", [c[1] for c in SMOOTH], ids=[c[0] for c in SMOOTH])
def test_smooth_expressions_pass_with_a_margin(tmp_path, replace):
    scenario, df = _run(tmp_path, replace)
    rows = _smoothness_rows(scenario, df)
    assert len(rows) == 3
    for quantity, row in rows.items():
        assert row["status"] == "pass", (quantity, row["entry"])
        assert row["abs_error"] < KINK_TOL / 1000, (quantity, row["abs_error"])
    assert all(c.smooth for c in check_run(scenario.system, df))


def test_kink_measure_falls_as_the_cube_for_smooth_and_stays_for_a_kink():
    """The measure's justification: smooth, halving the sample step divides it by ~8
    (r = -g''''/12 ~ step^4 over a first derivative ~ step); a kink keeps it at 1."""
    def measure(f, df, d2f, step, t0=0.3):
        t = np.array([t0, t0 + step])
        return float(kink_measures(t[:, None], df(t)[:, None], d2f(t)[:, None, None])[0])
    smooth = [measure(np.sin, np.cos, lambda t: -np.sin(t), h) for h in (0.1, 0.05)]
    assert 7 < smooth[0] / smooth[1] < 9
    kink = [measure(None, lambda t: np.sign(t - 0.31), lambda t: 0 * t, h) for h in (0.1, 0.05)]
    assert kink == pytest.approx([1.0, 1.0], rel=1e-12)


def test_cli_simulate_fails_a_disguised_absolute_value(tmp_path):
    model = _my_arm(tmp_path, {'phi = "z - 0.3"': 'phi = "sqrt((z-0.3)**2)"'})
    run = subprocess.run([sys.executable, "-m", "gpme.cli", "simulate", "--model", str(model),
                          "--quick", "--out", str(tmp_path / "out"), "--no-progress"],
                         capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert "Traceback" not in run.stderr
    assert run.returncode == 1, (run.returncode, run.stdout[-2000:], run.stderr)
    assert re.search(r"smoothness of constraint 'height': inf at t = 0\.0000 s \(phi = "
                     r"sqrt\(\(z - 0\.3\)\*\*2\) is not smooth where the run goes: sqrt: "
                     r"where \(z - 0\.3\)\*\*2 <= 0 is reached", run.stdout), run.stdout
    assert "FAIL: checks:" in run.stdout


# ============================================================ poles crossed mid-run
# (id, replacements, method, who, words)
POLES = [
    ("constraint-pole-in-time", {'phi = "z - 0.3"': 'phi = "z - 0.3 - 0.01/(t - 1)"'}, "RK4",
     ["constraint 'height' (phi = z - 0.3 - 0.01/(t - 1)) runs into its singular set, "
      "division: where t - 1 = 0, reached at t = 1 s", "no step size helps",
      "The failure it caused: the run diverged"]),
    ("programme-pole-between-samples", {'q = "0.8*sin(pi*t)"': 'q = "0.01/(t - 1.0005)"'},
     "RK4", ["programme 'Phi_yaw' (f(t) = 0.01/(t - 1.0005)) runs into its singular set, "
             "division: where t - 1.0005 = 0, reached at t = 1.0005 s",
             "The failure it caused: at t = 0.998 s the motion reaches yaw"]),
    ("constraint-pole-adaptive", {'phi = "z - 0.3"': 'phi = "z - 0.3 - 0.01/(t - 1)"'},
     "RK45", ["constraint 'height'", "division: where t - 1 = 0, reached at t = 1 s"]),
    ("log-pole-in-time", {'q = "0.8*sin(pi*t)"': 'q = "0.01*log((t - 1.0003)**2)"'}, "RK4",
     ["programme 'Phi_yaw' (f(t) = 0.01*log((t - 1.0003)**2)) runs into its singular set, "
      "log: where (t - 1.0003)**2 <= 0, reached at t = 1.0003 s"]),
]


@pytest.mark.parametrize("replace,method,words", [c[1:] for c in POLES],
                         ids=[c[0] for c in POLES])
def test_a_pole_met_mid_run_is_named_with_its_time(tmp_path, replace, method, words):
    scenario = load_model_file(_my_arm(tmp_path, replace))
    with pytest.raises(GpmeError) as exc:
        simulate(scenario.system, 1.5, scenario.q0, scenario.q_dot0,
                 dt=1e-3 if method == "RK4" else None, method=method, compiled=False)
    assert not isinstance(exc.value, UnstableStepError), str(exc.value)
    assert str(exc.value).startswith("the run failed near t = ")
    for word in words:
        assert word in str(exc.value), (word, str(exc.value))


def test_a_failure_far_from_any_singular_set_keeps_its_own_message(tmp_path):
    """The diagnosis names an expression only when the run is running into its singular
    set: a run that fails for another reason (a step far above the stability limit) is
    still an unstable step, though the model has a division."""
    scenario = load_model_file(_my_arm(tmp_path, {'q = "0.8*sin(pi*t)"':
                                                  'q = "0.8*sin(pi*t)/(1 + t**2)"'}))
    with pytest.raises(UnstableStepError, match="the RK4 step dt = 0.2 s is unstable at t = "
                                                "0.2 s") as exc:
        simulate(scenario.system, 1.0, scenario.q0, scenario.q_dot0, dt=0.2, check_step=False,
                 compiled=False)
    assert "singular set" not in str(exc.value)


def test_cli_simulate_names_a_pole_not_the_step(tmp_path):
    model = _my_arm(tmp_path, {'phi = "z - 0.3"': 'phi = "z - 0.3 - 0.01/(t-1)"'})
    run = subprocess.run([sys.executable, "-m", "gpme.cli", "simulate", "--model", str(model),
                          "--out", str(tmp_path / "out"), "--no-progress"],
                         capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert "Traceback" not in run.stderr
    assert run.returncode == 2, (run.returncode, run.stderr)
    assert run.stderr.startswith("error: the run failed near t = 0.98 s because constraint "
                                 "'height' (phi = z - 0.3 - 0.01/(t - 1)) runs into its "
                                 "singular set, division: where t - 1 = 0, reached at t = 1 s")
    assert "unstable" not in run.stderr.split("The failure it caused")[0]


def test_cli_simulate_refuses_a_power_tower_at_once(tmp_path):
    model = _my_arm(tmp_path, {'phi = "z - 0.3"': 'phi = "9**9**9"'})
    start = time.perf_counter()
    run = subprocess.run([sys.executable, "-m", "gpme.cli", "simulate", "--model", str(model),
                          "--out", str(tmp_path / "out"), "--no-progress"],
                         capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert time.perf_counter() - start < 60      # the interpreter's start and imports
    assert "Traceback" not in run.stderr
    assert run.returncode == 2, (run.returncode, run.stderr)
    assert "constraint[1].phi: '9**9**9': a constant power with about 3.7e8 digits" in run.stderr


# ============================================================ degenerate joint axes
URDF = """<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><mass value="1"/><origin xyz="0.2 0 0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="{axis}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
"""


@pytest.mark.parametrize("axis,length", [("1e-12 0 0", "1e-12"), ("1e-7 1e-7 0", "1.41e-07"),
                                         ("0 -3e-9 4e-9", "5e-09")])
def test_urdf_degenerate_axis_is_named_with_its_length(tmp_path, axis, length):
    path = tmp_path / "r.urdf"
    path.write_text(URDF.format(axis=axis))
    with pytest.raises(ModelFileError) as exc:
        read_urdf(path)
    message = str(exc.value)
    for word in (f"joint 'shoulder': <axis xyz> is degenerate: its length {length} is below "
                 "1e-06", "normalising it would multiply its round-off by 1/|axis|",
                 f"got '{axis}'", "e.g. '0 0 1'"):
        assert word in message, (word, message)
    assert "rank" not in message


def test_urdf_axis_of_another_length_is_normalised(tmp_path):
    path = tmp_path / "r.urdf"
    path.write_text(URDF.format(axis="0 0 2e-5"))
    model = read_urdf(path)
    assert np.allclose(model.joints[0].axis, (0, 0, 1))


def test_model_file_with_degenerate_urdf_axis_names_the_joint(tmp_path):
    model = _my_arm(tmp_path, {})
    urdf = tmp_path / "my_arm.urdf"
    text = urdf.read_text()
    assert text.count('<axis xyz="0 0 1"/>') >= 1
    urdf.write_text(text.replace('<axis xyz="0 0 1"/>', '<axis xyz="1e-12 0 0"/>', 1))
    with pytest.raises(ModelFileError, match=r"joint 'yaw': <axis xyz> is degenerate: its "
                                             r"length 1e-12 is below 1e-06"):
        load_model_file(model)


@pytest.mark.parametrize("axis,words", [
    ((1e-12, 0, 0), ["joint 'j': axis must be a unit 3-vector, got [1e-12, 0.0, 0.0], which is "
                     "degenerate: its length 1e-12 is below 1e-06"]),
    ((0, 0, 2), ["joint 'j': axis must be a unit 3-vector, got [0.0, 0.0, 2.0] of length 2",
                 "divide it by its length"]),
    ((0, np.nan, 1), ["joint 'j': axis must be a unit 3-vector, got [0.0, nan, 1.0]"]),
])
def test_python_api_degenerate_axis_is_named_with_its_length(axis, words):
    b = ChainBuilder("m")
    b.add_joint("j", REVOLUTE, axis)
    with pytest.raises(ModelError) as exc:
        b.build()
    for word in words:
        assert word in str(exc.value), (word, str(exc.value))


# ============================================================ dependent constraints
def test_dependent_constraints_of_a_model_file_are_named(tmp_path):
    model = _my_arm(tmp_path, {'phi = "x**2 + y**2 - 0.45**2"': 'phi = "x - 0.3"',
                               'phi = "z - 0.3"': 'phi = "2*x - 0.6"'})
    with pytest.raises(ConstraintError) as exc:
        scenario = load_model_file(model)
        simulate(scenario.system, 0.1, scenario.q0, scenario.q_dot0, dt=1e-3, compiled=False)
    message = str(exc.value)
    for word in ("at t = 0 s", "the constraint Jacobian has rank 2 < 3 constraints",
                 "the constraints 'circle' and 'height' are dependent: "
                 "row('circle') - 0.5 x row('height') = 0",
                 "no choice of dependent coordinates can realise them"):
        assert word in message, (word, message)
    assert "unstable" not in message


def _arm_with(constraints):
    from conftest import spatial_arm
    arm = spatial_arm()
    return ProgrammedMotion(arm, constraints), np.zeros(arm.n_coordinates)


@pytest.mark.parametrize("dependent", [None, ("q0", "q1", "q2")],
                         ids=["pivoted", "given-partition"])
def test_dependent_constraints_are_named_whatever_the_partition(dependent):
    system, zero = _arm_with([SympyPointConstraint("x - 0.3", name="a"),
                              SympyPointConstraint("y + z", name="b"),
                              SympyPointConstraint("-2*x + 0.6 + 3*y + 3*z", name="c")])
    if dependent is not None:
        system = system.with_dependent(dependent)
    with pytest.raises(ConstraintError) as exc:
        simulate(system, 0.01, zero, zero, dt=1e-3, compiled=False)
    message = str(exc.value)
    assert "rank 2 < 3 constraints" in message, message
    assert re.search(r"the constraints 'a', 'b' and 'c' are dependent: .*row\('a'\).*"
                     r"row\('b'\).*row\('c'\) = 0", message), message


def test_a_constraint_no_coordinate_moves_is_named():
    """A constraint on a point of a revolute joint's axis: no coordinate moves it, so its
    Jacobian row is zero (not 'dependent')."""
    b = ChainBuilder("m")
    b.add_joint("j", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.2, 0.1, 0.1), com=(0.1, 0, 0)))
    b.add_frame("hub")                       # on the joint's axis
    system = ProgrammedMotion(b.build(), [SympyPointConstraint("x - 0.1*t", frame="hub",
                                                               name="still")])
    with pytest.raises(ConstraintError, match="at t = 0 s, q = \\[0.0\\] the constraint "
                                              "Jacobian has rank 0 < 1 constraints .*: "
                                              "constraint 'still' has a zero Jacobian row: "
                                              "no coordinate moves it"):
        simulate(system, 0.01, np.zeros(1), np.zeros(1), dt=1e-3, compiled=False)

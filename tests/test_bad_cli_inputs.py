"""Bad input to `gpme simulate`, `gpme crosscheck` and `gpme verify` and to
gpme_core.integrate.simulate: every case ends in one clear error (exit status 2 on the command
line, a GpmeError in Python) that names the value and what would be valid, before any work,
and never in a traceback.

The command cases call gpme.cli.main in this process: an exception escaping main (what a
user would see as a traceback) fails the test, and stderr is checked for "Traceback" too.
"""
import shutil
from pathlib import Path

import numpy as np
import pytest

from gpme.cli import main
from gpme_io.out_lock import exclusive_output
from gpme_core.errors import GpmeError, ModelError, UnstableStepError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_examples.crane import CraneParameters, crane_system, initial_state

ROOT = Path(__file__).resolve().parents[1]
RIGID_TOML = ROOT / "models" / "crane_rigid.toml"


def _run(argv, capsys):
    code = main(argv)
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err and "Traceback" not in captured.out
    return code, captured.err


def _model_copy(tmp_path, **run):
    """models/crane_rigid.toml with [run] keys replaced (the URDF path made absolute)."""
    text = RIGID_TOML.read_text()
    for key, value in run.items():
        lines = [ln for ln in text.splitlines() if not ln.strip().startswith(f"{key} ")]
        text = "\n".join(lines) + "\n"
        text = text.replace("[run]\n", f"[run]\n{key} = {value}\n", 1)
    path = tmp_path / "model.toml"
    path.write_text(text)
    for side in RIGID_TOML.parent.glob("*.urdf"):
        shutil.copy(side, tmp_path / side.name)
    if (RIGID_TOML.parent / "urdf").is_dir():
        shutil.copytree(RIGID_TOML.parent / "urdf", tmp_path / "urdf", dirs_exist_ok=True)
    return path


# (id, argv after "simulate", words that must all be in the message)
SIMULATE_CASES = [
    ("t_end_absurd", ["--t-end", "1e12"], ["1e+12", "rows", "GiB", "shorten t_end"]),
    ("t_end_negative", ["--t-end", "-1"], ["--t-end must be a positive, finite duration", "-1.0"]),
    ("t_end_zero", ["--t-end", "0"], ["--t-end must be a positive, finite duration", "0.0"]),
    ("t_end_nan", ["--t-end", "nan"], ["--t-end must be a positive, finite duration", "nan"]),
    ("t_end_inf", ["--t-end", "inf"], ["--t-end must be a positive, finite duration", "inf"]),
    ("dt_zero", ["--dt", "0"], ["--dt must be a positive, finite step", "0.0"]),
    ("dt_negative", ["--dt=-1e-3"], ["--dt must be a positive, finite step", "-0.001"]),
    ("dt_nan", ["--dt", "nan"], ["--dt must be a positive, finite step", "nan"]),
    ("dt_inf", ["--dt", "inf", "--t-end", "1"], ["--dt must be a positive, finite step", "inf"]),
    ("dt_longer_than_run", ["--dt", "1", "--t-end", "0.5"], ["--dt 1.0 s is longer than "
                                                             "--t-end 0.5 s"]),
    ("dt_unstable", ["--case", "flexible", "--dt", "0.01", "--t-end", "1"],
     ["dt = 0.01 s is unstable at the start", "stiffest mode", "Hz", "use dt <="]),
    ("n_rfe_negative", ["--case", "flexible", "--n-rfe", "-1"],
     ["--n-rfe must be 0", "-1"]),
    # refused from the number, before any model is built (it took a minute of building)
    ("n_rfe_huge", ["--case", "flexible", "--n-rfe", "100000"],
     ["--n-rfe must be 0", "up to 1000", "got 100000"]),
    # every problem of the options in one message, not only the first
    ("t_end_nan_dt_inf", ["--t-end", "nan", "--dt", "inf"],
     ["2 problems", "--dt must be a positive, finite step", "--t-end must be a positive"]),
    ("three_problems", ["--t-end", "-1", "--dt", "0", "--case", "rigid", "--n-rfe", "3"],
     ["3 problems", "--dt must", "--t-end must", "--case rigid has none"]),
    ("n_rfe_over_budget", ["--case", "flexible", "--n-rfe", "40", "--t-end", "1"],
     ["estimated wall time", "above the limit of 1 h", "--force", "fewer RFEM segments"]),
    ("history_over_memory", ["--case", "rigid", "--t-end", "1e5", "--dt", "1e-3"],
     ["1e+08 rows", "GiB of state in memory", "limit 4 GiB"]),
    ("model_missing", ["--model", "/nonexistent/model.toml"],
     ["/nonexistent/model.toml", "cannot read the model file", "No such file"]),
    ("model_is_directory", ["--model", "/tmp"], ["/tmp", "cannot read the model file",
                                                 "directory"]),
    ("model_with_crane_flags", ["--model", str(RIGID_TOML), "--case", "flexible"],
     ["--case, --n-rfe, --on-manifold and --static-arm choose the built-in crane runs"]),
    ("model_dt_unstable", ["--model", str(RIGID_TOML), "--dt", "0.5", "--t-end", "1"],
     ["dt = 0.5 s is unstable at the start", "stiffest mode", "use dt <= 0.049 s"]),
    ("model_t_end_absurd", ["--model", str(RIGID_TOML), "--t-end", "1e9"],
     ["1e+09 s", "rows", "GiB"]),
    ("urdf_as_model", ["--model", str(ROOT / "examples" / "my_arm" / "my_arm.urdf")],
     ["not valid TOML", "this looks like a URDF", "[model] urdf"]),
    ("same_model_twice", ["--model", str(RIGID_TOML), "--model", str(RIGID_TOML)],
     ["both name their model 'crane_rigid'", "overwrite each other"]),
    ("static_arm_rigid", ["--case", "rigid", "--static-arm"],
     ["--static-arm and --n-rfe set the flexible arm", "--case rigid has none"]),
    ("n_rfe_rigid", ["--case", "rigid", "--n-rfe", "5"],
     ["--static-arm and --n-rfe set the flexible arm"]),
]


@pytest.mark.parametrize("argv,words", [c[1:] for c in SIMULATE_CASES],
                         ids=[c[0] for c in SIMULATE_CASES])
def test_simulate_refuses(argv, words, tmp_path, capsys):
    out = tmp_path / "out"
    code, err = _run(["simulate", *argv, "--out", str(out), "--no-progress"], capsys)
    assert code == 2, err
    assert err.startswith("error: ") and err.count("\n") >= 1
    for word in words:
        assert word in err, (word, err)
    assert not list(out.glob("*.csv")), "nothing written for a refused run"


def test_simulate_out_is_a_file(tmp_path, capsys):
    target = tmp_path / "a_file"
    target.write_text("keep me")
    code, err = _run(["simulate", "--case", "rigid", "--t-end", "0.01", "--out", str(target),
                      "--no-progress"], capsys)
    assert code == 2 and "exists and is not a directory; give a directory" in err
    assert target.read_text() == "keep me"


@pytest.mark.parametrize("command", [["simulate"], ["verify"], ["crosscheck", "mujoco"]])
def test_out_empty(command, capsys):
    code, err = _run([*command, "--out", "", "--no-progress"], capsys)
    assert code == 2 and "--out is empty; give a directory" in err


def test_simulate_out_unwritable(capsys):
    code, err = _run(["simulate", "--case", "rigid", "--t-end", "0.01", "--out",
                      "/proc/gpme_cannot_be_here", "--no-progress"], capsys)
    assert code == 2 and "--out '/proc/gpme_cannot_be_here' cannot be created in '/proc'" in err


def test_simulate_out_being_written_by_another_run(tmp_path, capsys):
    with exclusive_output(tmp_path):
        code, err = _run(["simulate", "--case", "rigid", "--t-end", "0.01", "--out",
                          str(tmp_path), "--no-progress"], capsys)
    assert code == 2 and "is being written by another gpme run (pid" in err
    assert "give another --out" in err


def test_simulate_model_file_with_absurd_t_end(tmp_path, capsys):
    model = _model_copy(tmp_path, t_end="1e9")
    code, err = _run(["simulate", "--model", str(model), "--out", str(tmp_path / "o"),
                      "--no-progress"], capsys)
    assert code == 2 and "1e+09 s" in err and "rows" in err


@pytest.mark.parametrize("argv,words", [
    (["simulate", "--method", "Euler"], ["invalid choice: 'Euler'", "RK4"]),
    (["simulate", "--t-end", "ten"], ["invalid float value: 'ten'"]),
    (["simulate", "--n-rfe", "2.5"], ["invalid int value: '2.5'"]),
    (["verify", "--only", "bullet"], ["invalid choice: 'bullet'", "exudyn"]),
    (["crosscheck", "bullet"], ["invalid choice: 'bullet'"]),
    (["verify", "--keep", "many"], ["invalid int value: 'many'"]),
], ids=["method", "t_end_text", "n_rfe_float", "only", "engine", "keep_text"])
def test_argument_parser_errors(argv, words, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "usage: gpme" in err and "Traceback" not in err
    for word in words:
        assert word in err


@pytest.mark.parametrize("argv,words", [
    (["verify", "--keep", "0"], ["--keep must be at least 1", "got 0"]),
    (["verify", "--model", "/nonexistent.toml"], ["/nonexistent.toml",
                                                  "cannot read the model file"]),
    (["crosscheck", "mujoco", "--model", "/nonexistent.toml"], ["cannot read the model file"]),
], ids=["keep_zero", "verify_model_missing", "crosscheck_model_missing"])
def test_verify_and_crosscheck_refuse(argv, words, tmp_path, capsys):
    code, err = _run([*argv, "--out", str(tmp_path / "r"), "--no-progress"], capsys)
    assert code == 2
    for word in words:
        assert word in err
    assert not any((tmp_path / "r").glob("2*")), "no run directory for a refused run"


@pytest.mark.parametrize("command", [["verify"], ["crosscheck", "pinocchio"]])
def test_report_out_is_a_file(command, tmp_path, capsys):
    target = tmp_path / "a_file"
    target.write_text("x")
    code, err = _run([*command, "--out", str(target), "--no-progress"], capsys)
    assert code == 2 and "exists and is not a directory" in err


@pytest.mark.parametrize("run_keys,words", [
    ({"t_end": "1e9"}, ["1e+09 s", "rows", "GiB"]),
    ({"dt": "0.5"}, ["dt = 0.5 s is unstable at the start", "stiffest mode"]),
], ids=["t_end_absurd", "dt_unstable"])
def test_verify_refuses_a_bad_model_run_before_any_work(run_keys, words, tmp_path, capsys):
    model = _model_copy(tmp_path, **run_keys)
    root = tmp_path / "reports"
    code, err = _run(["verify", "--model", str(model), "--out", str(root), "--no-progress"],
                     capsys)
    assert code == 2
    for word in words:
        assert word in err
    assert not list(root.iterdir()) if root.exists() else True


# ---- Python API ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def crane():
    params = CraneParameters()
    system = crane_system(0, params)
    return system, *initial_state(system.model, params)


@pytest.mark.parametrize("kwargs,error,words", [
    ({"dt": 0.0}, ModelError, ["dt must be a positive step in s, got 0.0"]),
    ({"dt": "1e-3"}, ModelError, ["dt must be a number of seconds, got '1e-3'"]),
    ({"t_end": "1"}, ModelError, ["t_end must be a number of seconds, got '1'"]),
    ({"q0": ["a", "b", "c", "d"]}, ModelError, ["q0 and q_dot0 must be arrays of numbers",
                                                "'z1', 'psi2', 'psi3', 'z4'"]),
    ({"dt": 2.0}, ModelError, ["dt = 2.0 s is longer than the run"]),
    ({"output_dt": 0.0}, ModelError, ["output_dt must be a positive spacing"]),
    ({"output_dt": np.nan}, ModelError, ["output_dt must be a positive spacing"]),
    ({"t_end": 1e10}, ModelError, ["rows", "GiB of state in memory",
                                   "MAX_HISTORY_BYTES"]),
    ({"method": "Euler"}, ModelError, ["method must be one of", "'Euler'"]),
    ({"dt": 0.5}, UnstableStepError, ["dt = 0.5 s is unstable", "stiffest mode"]),
    ({"switch_rcond": -1.0}, ModelError, ["switch_rcond must be a positive number or None"]),
], ids=["dt_zero", "dt_text", "t_end_text", "q0_text", "dt_too_long", "output_dt_zero", "output_dt_nan",
        "t_end_memory", "method", "dt_unstable", "switch_rcond"])
def test_simulate_api_refuses(crane, kwargs, error, words):
    system, q0, q_dot0 = crane
    args = {"t_end": 1.0, "q0": q0, "q_dot0": q_dot0, **kwargs}
    with pytest.raises(error) as exc:
        simulate(system, **args)
    assert isinstance(exc.value, GpmeError)
    for word in words:
        assert word in str(exc.value)


def test_simulate_api_lists_every_problem_at_once(crane):
    system, q0, _ = crane
    with pytest.raises(ModelError) as exc:
        simulate(system, -1.0, q0[:2], [np.nan] * len(q0), dt=-1.0, method="Euler",
                 output_dt=0.0)
    text = str(exc.value)
    for word in ("q0 must have shape", "q_dot0 must be finite", "method must be one of",
                 "t_end must be positive", "dt must be a positive step",
                 "output_dt must be a positive spacing"):
        assert word in text


def test_radau_run_of_the_flexible_crane_prints_no_warnings():
    """The Pinocchio step's states come from a Radau run; SciPy's finite-difference Jacobian
    used to overflow on the work columns and print RuntimeWarnings on a passing run (the
    Jacobian's sparsity now says they feed back into nothing)."""
    import warnings
    params = CraneParameters()
    system = crane_system(3, params)
    q0, q_dot0 = initial_state(system.model, params)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        df = simulate(system, 0.1, q0, q_dot0, method="Radau", output_dt=0.02, rtol=1e-4,
                      atol=1e-6)
    assert np.isfinite(df.to_numpy(float)).all()


def test_crane_parameters_listed_with_their_combinations(tmp_path, capsys):
    """A key's own problem (a negative yield strength) and a combination of keys (an arm
    wall thicker than the arm's radius) in one message, not one after the other."""
    text = (ROOT / "models" / "crane_flexible.toml").read_text().replace(
        "n_rfe = 3 ", "arm_yield_strength = -5.0\narm_wall_thickness = 0.5\nn_rfe = 3 ", 1)
    model = tmp_path / "crane.toml"
    model.write_text(text)
    code, err = _run(["simulate", "--model", str(model), "--out", str(tmp_path / "o"),
                      "--no-progress"], capsys)
    assert code == 2 and "2 problems" in err
    assert "model.crane.arm_yield_strength: must be > 0 (Pa), got -5.0" in err
    assert "wall_thickness 0.5 m must be smaller than the outer radius 0.01 m" in err


@pytest.mark.parametrize("call,words", [
    (lambda m, s, q, qd: simulate(m, 1.0, q, qd), ["system must be a gpme_core.gpme."
                                                   "ProgrammedMotion", "got Model"]),
    (lambda m, s, q, qd: ProgrammedMotion(m, (), baumgarte="fast"),
     ["baumgarte must be two numbers (alpha, beta) in 1/s, got 'fast'"]),
    (lambda m, s, q, qd: s.solve(0.0, q[:2], qd), ["q and q_dot must have shape (4,)",
                                                   "got (2,) and (4,)"]),
    (lambda m, s, q, qd: simulate(s, "2", q, qd, dt="x", output_dt=0.0),
     ["t_end must be a number of seconds", "dt must be a number of seconds",
      "output_dt must be a positive spacing"]),
], ids=["model_for_system", "baumgarte_text", "solve_shape", "several_at_once"])
def test_api_misuse_named(crane, call, words):
    system, q0, q_dot0 = crane
    with pytest.raises(ModelError) as exc:
        call(system.model, system, q0, q_dot0)
    for word in words:
        assert word in str(exc.value)


@pytest.mark.parametrize("method", ["RK4", "RK45"])
def test_a_pole_stepped_over_is_named(method, tmp_path):
    """A programme with a pole at t = 0.0301 s, between the steps: the values stay finite but
    huge, the run stops on a coordinate's range, and the message names the pole."""
    from gpme_io.modelfile import load_model_file
    text = (ROOT / "examples" / "my_arm" / "my_arm.toml").read_text()
    text = text.replace('q = "0.8*sin(pi*t)"', 'q = "0.001/(t - 0.0301)"').replace(
        'urdf = "my_arm.urdf"', f'urdf = "{ROOT / "examples" / "my_arm" / "my_arm.urdf"}"')
    path = tmp_path / "pole.toml"
    path.write_text(text)
    scenario = load_model_file(path)
    with pytest.raises(GpmeError) as exc:
        simulate(scenario.system, 0.1, scenario.q0, scenario.q_dot0, method=method,
                 dt=1e-3 if method == "RK4" else None)
    assert "division: where t - 0.0301 = 0" in str(exc.value)


@pytest.mark.parametrize("method", ["RK4", "RK45", "Radau"])
def test_wall_time_limit_stops_a_run(crane, method):
    """The guard of the runs whose cost is not known before: every method looks at the clock
    every WALL_CHECK_EVERY evaluations and stops with the rate it reached."""
    from gpme_core.errors import SimulationError
    system, q0, q_dot0 = crane
    with pytest.raises(SimulationError, match=r"stopped after .* s of wall time \(the limit "
                                              r"is 1e-09 s\) at t = .* of t_end = 1 s "
                                              rf"\({method}\).*--force"):
        simulate(system, 1.0, q0, q_dot0, method=method, max_wall_s=1e-9)


def test_flexible_section_and_urdf_problems_in_one_message(tmp_path):
    """A [[flexible]] section that cannot be (a wall thicker than the tube's radius) and a
    broken URDF inertial: both listed at once."""
    from gpme_core.errors import ModelFileError
    from gpme_io.modelfile import load_model_file
    arm = ROOT / "examples" / "my_arm"
    (tmp_path / "my_arm.urdf").write_text((arm / "my_arm.urdf").read_text().replace(
        '<mass value="1.5"/>', '<mass value="abc"/>', 1))
    text = (arm / "my_arm.toml").read_text().replace("[initial]", """[[flexible]]
link = "forearm"
section = { shape = "tube", outer_diameter = 0.02, wall_thickness = 0.05 }
youngs_modulus = 70.0e9
shear_modulus = 26.0e9
density = 2700.0
segments = 2

[initial]""")
    (tmp_path / "my_arm.toml").write_text(text)
    with pytest.raises(ModelFileError) as exc:
        load_model_file(tmp_path / "my_arm.toml")
    message = str(exc.value)
    assert "flexible[0].section" in message and "wall_thickness" in message
    assert "<mass value>" in message and "'abc'" in message


def test_crane_run_shorter_than_its_default_step(tmp_path, capsys):
    """--t-end below the paper's default step (1e-4 s): the step is the run, not an error
    about a dt the user never gave."""
    code, err = _run(["simulate", "--case", "rigid", "--t-end", "1e-5", "--out",
                      str(tmp_path), "--no-progress"], capsys)
    assert code == 0, err
    assert (tmp_path / "crane_rigid.csv").is_file()


def test_crosscheck_mujoco_refuses_names_mujoco_cannot_take_before_any_work(tmp_path, capsys):
    """Two drives on one joint give two MuJoCo actuators of one name: refused before the
    estimate and any run, naming the joint."""
    text = (ROOT / "examples" / "my_arm" / "my_arm.toml").read_text().replace(
        'urdf = "my_arm.urdf"', f'urdf = "{ROOT / "examples" / "my_arm" / "my_arm.urdf"}"')
    text += '\n[[drive]]\njoint = "shoulder"\ntype = "constant"\nlevel = 1.0\n' * 2
    model = tmp_path / "two_drives.toml"
    model.write_text(text)
    code, err = _run(["crosscheck", "mujoco", "--model", str(model), "--out",
                      str(tmp_path / "r"), "--no-progress"], capsys)
    assert code == 2 and "actuator name" in err and "shoulder" in err, err
    assert not list((tmp_path / "r").glob("*.csv"))

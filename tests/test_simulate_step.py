"""`gpme simulate`'s default RK4 step is chosen for the accuracy its own checks demand
(crosscheck/accurate_step.py, docs/runs.md), and the command exits 1 with a one-line summary when
a check fails.

The model: examples/my_arm/my_arm.urdf without constraints, its elbow on a stiff, nearly
undamped spring (3e5 N m/rad, 0.01 N m s/rad) and its yaw driven by a sine torque.  Half the RK4 stability limit of
the elbow mode (the scenario's step, below output_dt) keeps the run stable but damps the
mode's oscillation: the energy balance fails there (measured 4.5x its tolerance), and two
halvings pass it (measured 0.07 of it).  Each run takes ~0.1 s; the file ~15 s on two cores.
"""
import math
from pathlib import Path

import pandas as pd
import pytest

from crosscheck.run_checks import run_rows
from gpme import cli
from crosscheck.accurate_step import MARGIN, ORDER, Outcome, halvings_needed, run_accurately
from gpme_io.budget import MAX_STEP_HALVINGS, MAX_WALL_S
from gpme_io.runs import simulate_scenario
from gpme_core.run_cost import RunCost
from gpme_core.stability import STEP_SAFETY, rk4_limit
from gpme_io.modelfile import load_model_file

REPO = Path(__file__).resolve().parent.parent
URDF = REPO / "examples" / "my_arm" / "my_arm.urdf"

STIFF_ELBOW = f"""
[model]
name = "stiff_elbow"
urdf = "{URDF}"
gravity = [0.0, 0.0, -9.81]

[[joint]]
name = "elbow"
stiffness = 300000.0
spring_reference = 1.2
damping = 0.01

[[joint]]
name = "shoulder"
stiffness = 800.0
spring_reference = -0.3
damping = 0.01

[[drive]]
joint = "yaw"
type = "sine"
offset = 0.0
amplitude = 2.0
period = 0.5

[initial]
q = {{ yaw = 0.0, shoulder = -0.3, elbow = 1.2 }}

[run]
t_end = 0.5
"""


@pytest.fixture
def model_file(tmp_path):
    path = tmp_path / "stiff_elbow.toml"
    path.write_text(STIFF_ELBOW)
    return path


def _energy(rows):
    (row,) = [r for r in rows if r["quantity"] == "energy balance"]
    return row


def test_stability_bound_step_fails_the_energy_check_and_the_default_step_passes(
        model_file, tmp_path, capsys):
    scenario = load_model_file(model_file)
    limit, _ = rk4_limit(scenario.system, 0.0, scenario.q0, scenario.q_dot0, how="springs")
    # the premise: the scenario's step is the stability bound (not output_dt) ...
    assert scenario.dt == pytest.approx(STEP_SAFETY * limit) and scenario.dt < scenario.output_dt
    # ... and a run at it is stable but fails its own energy check
    at_bound = simulate_scenario(scenario)
    assert _energy(run_rows(scenario, at_bound))["status"] == "fail"

    choice = run_accurately(lambda dt: simulate_scenario(scenario, dt=dt),
                            lambda df: run_rows(scenario, df))
    assert choice.outcome is Outcome.REFINED
    h0 = at_bound.attrs["dt"]
    halvings = choice.trials[-1].halvings
    assert 1 <= halvings <= MAX_STEP_HALVINGS
    assert choice.dt == pytest.approx(h0 / 2 ** halvings)
    assert choice.df.attrs["dt"] == choice.dt
    assert _energy(choice.rows)["status"] == "pass"
    assert all(r["status"] != "fail" for r in choice.rows)

    out = tmp_path / "out"
    assert cli.main(["simulate", "--no-progress", "--model", str(model_file), "--out",
                     str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert any(f"{halvings} halvings of the model's step" in line for line in lines), lines
    assert any(line.startswith("  energy balance:") and "(ok," in line for line in lines)
    assert lines[-1] == "checks: 1 pass, 0 fail, 0 information"
    history = pd.read_csv(out / "stiff_elbow.csv")
    assert history["t"].iloc[-1] == pytest.approx(0.5)


def test_a_given_dt_that_fails_a_check_exits_1_with_a_one_line_summary(model_file, tmp_path,
                                                                       capsys):
    # 4e-4 s is fitted to 1e-3 / 3 s: stable (the scenario's step), inaccurate; used as given
    code = cli.main(["simulate", "--no-progress", "--model", str(model_file), "--dt", "4e-4",
                     "--out", str(tmp_path / "out")])
    assert code == 1
    lines = capsys.readouterr().out.splitlines()
    assert sum("estimate:" in line for line in lines) == 1       # one run: no halving
    assert not any("halving" in line for line in lines)
    assert lines[-1].startswith("FAIL: checks: 0 pass, 1 fail, 0 information: stiff_elbow: "
                                "energy balance ")
    assert "at t = " in lines[-1] and "(tolerance " in lines[-1]
    assert sum("FAIL" in line for line in lines) == 2            # the check's line, the summary
    assert (tmp_path / "out" / "stiff_elbow.csv").is_file()      # the run is written all the same


def test_the_paper_step_is_kept_when_its_checks_pass(tmp_path, capsys):
    assert cli.main(["simulate", "--case", "rigid", "--t-end", "0.3", "--no-progress",
                     "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "RK4 step 0.0001 s (the paper's step): every check within its tolerance" in out
    assert out.count("estimate:") == 1


# --- the rule's bounds, on runs whose checks' errors follow error = C dt^p exactly ---------

H0 = 1e-3


def _model_runs(ratio0, order, wall_s=1.0):
    """(run, checks, made): a stand-in for a model whose one gated check has
    error / tolerance = ratio0 (dt / H0)^order; ``made`` lists the steps run."""
    made = []

    def run(dt):
        dt = H0 if dt is None else dt
        made.append(dt)
        df = pd.DataFrame({"t": [0.0]})
        df.attrs.update(dt=dt, wall_time_s=wall_s)
        return df

    def checks(df):
        ratio = ratio0 * (df.attrs["dt"] / H0) ** order
        return [{"quantity": "energy balance", "abs_error": ratio * 1e-6, "tol_abs": 1e-6,
                 "tol_rel": 0.0, "scale": 1.0, "entry": "t = 1.0000 s",
                 "status": "pass" if ratio <= 1 else "fail"},
                {"quantity": "peak bending angle (arm)", "abs_error": 0.0,
                 "tol_abs": math.inf, "tol_rel": 0.0, "scale": 0.0, "entry": "",
                 "status": "info"}]
    return run, checks, made


@pytest.mark.parametrize("ratio0, order", [(0.5, 4), (3.0, 4), (50.0, 4), (1e4, 4), (1e9, 4),
                                           (20.0, 2), (100.0, 1.2), (1e3, 1.5), (10.0, 0.3),
                                           (5.0, 0.0)],
                         ids=lambda v: f"{v:g}")
def test_halving_is_bounded(ratio0, order):
    run, checks, made = _model_runs(ratio0, order)
    choice = run_accurately(run, checks)
    assert len(made) <= 1 + MAX_STEP_HALVINGS
    assert min(made) >= H0 / 2 ** MAX_STEP_HALVINGS
    assert made == sorted(made, reverse=True) and len(set(made)) == len(made)
    assert choice.dt == made[-1]                       # the last run is the one kept
    final = ratio0 * (choice.dt / H0) ** order
    if choice.outcome in (Outcome.KEPT, Outcome.REFINED):
        assert final <= 1.0
    else:
        assert final > 1.0 and choice.outcome in (Outcome.OUT_OF_BUDGET,
                                                  Outcome.NOT_FROM_STEP)
    if choice.outcome is Outcome.OUT_OF_BUDGET:
        # one line: the step reached, the error, the step predicted to pass, the remedy
        assert "\n" not in choice.note
        for words in ("budget reached at RK4 step", "x its tolerance", "predicted to pass",
                      "give --dt"):
            assert words in choice.note, choice.note
    if order >= ORDER and ratio0 > 1 and halvings_needed(ratio0, 1.0) <= MAX_STEP_HALVINGS:
        assert choice.outcome is Outcome.REFINED and len(made) == 2   # one prediction
    if order < 1:
        assert choice.outcome is Outcome.NOT_FROM_STEP and len(made) == 2
    if ratio0 <= 1:
        assert choice.outcome is Outcome.KEPT and made == [H0]


def test_the_prediction_aims_at_a_tenth_of_the_tolerance():
    run, checks, made = _model_runs(3.0, ORDER)
    choice = run_accurately(run, checks)
    assert made == [H0, H0 / 4]                        # 3 / 16 > 0.1, 3 / 256 <= 0.1
    assert 3.0 / 4 ** ORDER <= MARGIN < 3.0 / 2 ** ORDER
    assert choice.outcome is Outcome.REFINED


def test_a_search_over_the_cost_limit_stops_unless_forced():
    def estimate(dt):                                  # an hour per run beyond the first
        return RunCost("RK4", 1, 4, MAX_WALL_S / 4, 1, 1, 0.0, 0.0, True)
    run, checks, made = _model_runs(3.0, ORDER)
    choice = run_accurately(run, checks, estimate=estimate)
    assert made == [H0] and choice.outcome is Outcome.OUT_OF_BUDGET
    assert "above the limit of" in choice.note and "--force" in choice.note
    run, checks, made = _model_runs(3.0, ORDER)
    assert run_accurately(run, checks, estimate=estimate, force=True).outcome \
        is Outcome.REFINED

"""Programmed runs realised exactly in Pinocchio and MuJoCo agree with gpme within gpme's
own RK4 error (crosscheck.run_gates), on the crane (rigid, RFEM n = 1), on a small arm
with a time-dependent SymPy constraint and a joint programme, and on the UR5 example with its
flexible forearm (models/ur5_flexible_forearm.toml); a 1 % mass change in one
engine's model fails the gate; the gates rest on an observed order ~4."""
from dataclasses import replace

import numpy as np
import pytest

from crosscheck import run_gates
from crosscheck.mujoco import runs as mj_runs
from crosscheck.pinocchio import runs as pin_runs
from crosscheck.pinocchio.model import from_gpme
from gpme_core import transforms as tf
from gpme_core.constraints import JointProgramme, SympyPointConstraint
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.model import REVOLUTE, ChainBuilder
from gpme_core.time_functions import Cosine
from gpme_io.scenario import Scenario, ToleranceOverride, crane_scenario

OUTPUT_DT = 1e-2
LABEL = "exact programmed run"


def arm_scenario(dt=2e-3):
    """3-joint arm: E stays on a vertical plane that turns about z at 1 rad/s and moves
    0.3 cos(2t) m along its normal (the gradient turns with time), the elbow follows a
    cosine programme; the shoulder has a spring and a cosine drive."""
    b = ChainBuilder("arm3")
    b.add_joint("q1", REVOLUTE, (0, 0, 1), damping=0.2)
    b.add_body(cuboid(3.0, (0.2, 0.2, 0.3), com=(0.0, 0.0, 0.15)))
    b.add_joint("q2", REVOLUTE, (0, 1, 0), origin=tf.translation(0, 0, 0.3), stiffness=40.0,
                spring_reference=-0.4, damping=0.3)
    b.add_body(cuboid(2.0, (0.5, 0.08, 0.08), com=(0.25, 0.0, 0.0)))
    b.add_joint("q3", REVOLUTE, (0, 1, 0), origin=tf.translation(0.5, 0, 0))
    b.add_body(cuboid(1.0, (0.4, 0.06, 0.06), com=(0.2, 0.0, 0.0)))
    b.add_frame("E", tf.translation(0.4, 0, 0))
    b.add_drive("q2", Cosine(0.0, 2.0, 1.5))
    model = b.build()
    cons = (SympyPointConstraint("-x*sin(t) + y*cos(t) - 0.3*cos(2*t)", frame="E", name="plane"),
            JointProgramme("q3", Cosine(0.6, 0.3, 2.0), name="elbow"))
    system = ProgrammedMotion(model, cons, dependent=("q1", "q3"))
    q0, qd0 = system.consistent_state(0.0, np.array([0.4, -0.3, 0.9]), np.zeros(3))
    return Scenario(name="arm3", model=model, constraints=cons, system=system, q0=q0,
                    q_dot0=qd0, t_end=1.0, quick_t_end=1.0, dt=dt, output_dt=OUTPUT_DT,
                    on_constraints=True)


# (scenario factory, run length s): the crane at the paper's steps (1e-4 s rigid,
# 5e-5 s RFEM), the arm at 2e-3 s, where its RK4 error is well above round-off
def ur5_scenario():
    """models/ur5_flexible_forearm.toml (UR5 from example-robot-data, forearm an aluminium
    tube in 4 RFEM segments, tool0 on a circle on a moving table), at its suggested step."""
    from gpme_core.errors import ModelFileError
    from gpme_io.modelfile import load_model_file
    try:
        return load_model_file(REPO / "models" / "ur5_flexible_forearm.toml")
    except ModelFileError as exc:
        if "example-robot-data" in str(exc):
            pytest.skip(f"optional extra missing: {exc}")
        raise


REPO = __import__("pathlib").Path(__file__).resolve().parent.parent
CASES = {"crane_rigid": (lambda: crane_scenario(0, on_constraints=True), 0.2),
         "crane_n1": (lambda: crane_scenario(1, on_constraints=True), 0.2),
         "arm3": (arm_scenario, 1.0),
         "ur5_flexible_forearm": (ur5_scenario, 0.05)}


@pytest.fixture(scope="module")
def exact():
    """{case: (scenario, gpme RefinedRuns, Pinocchio run, MuJoCo run)}, built on demand."""
    cache = {}

    def get(case):
        if case not in cache:
            make, t_end = CASES[case]
            s = make()
            refined = run_gates.refined_gpme_runs(s.system, s.q0, s.q_dot0, t_end, s.dt,
                                                  OUTPUT_DT)
            cache[case] = (s, refined,
                           pin_runs.programmed_run(s, t_end, refined.dt, OUTPUT_DT),
                           mj_runs.programmed_run(s, t_end, refined.dt, OUTPUT_DT))
        return cache[case]
    return get


def _rows(engine, s, refined, df):
    return run_gates.run_rows(engine, s, refined, df, pin_runs.exact_columns(s), LABEL, "test")


@pytest.mark.parametrize("engine", ["pinocchio", "mujoco"])
@pytest.mark.parametrize("case", list(CASES))
def test_exact_run_agrees_with_gpme_within_its_integration_error(exact, case, engine):
    s, refined, pin_df, mj_df = exact(case)
    rows = _rows(engine, s, refined, pin_df if engine == "pinocchio" else mj_df)
    columns = rows[:-1]
    bad = [(r["quantity"], r["abs_error"], r["tol_abs"]) for r in columns if r["status"] != "pass"]
    assert not bad
    # the gate is far below the signal: 1e-6 of the largest entry of its kind (coordinates,
    # velocities) and 1e-3 of the column's own |x|max (the round-off floor includes a
    # random-walk cross-talk term relative to the whole state, which matters for tiny
    # columns such as an RFEM torsion angle of 5e-10 rad); multipliers 1e-6 of their own
    # size.  The constraint values are ~0 by design and excluded.
    cons = set(s.system.constraint_names)
    df = pin_df if engine == "pinocchio" else mj_df
    names = list(s.model.coordinate_names)
    for r in columns:
        column = r["quantity"][len(LABEL) + 1:]
        if column in cons:
            continue
        kind = names if column in names else [f"{c}_dot" for c in names] \
            if column.endswith("_dot") else [column]
        state = float(np.abs(df[kind].to_numpy(float)).max())
        assert r["tol_abs"] < 1e-6 * max(state, r["scale"]), (column, r["tol_abs"], state)
        if r["scale"] > 1e-6 * state:
            # a column below 1e-6 of its kind (e.g. a torsion angle of 1e-11 rad beside
            # psi3 ~ 1 rad) sits near the round-off cross-talk of the whole state, which
            # sets its floor; the line above decides for it
            assert r["tol_abs"] < 1e-3 * r["scale"], (column, r["tol_abs"], r["scale"])
    assert rows[-1]["status"] in ("pass", "info")


@pytest.mark.parametrize("case", ["crane_n1", "arm3"])
def test_observed_order_is_four(exact, case):
    s, refined, _, mj_df = exact(case)
    row = _rows("mujoco", s, refined, mj_df)[-1]
    assert row["status"] == "pass"
    # measured 4.00 on both (least resolved column: psi_arm_1, q2); the row's own gate is
    # |p - 4| <= 1, here the stronger statement that the regime is cleanly asymptotic
    assert 3.8 <= row["gpme_value"] <= 4.2


def test_richardson_estimate_is_gpmes_actual_error():
    """16/15 (x(dt) - x(dt/2)) against gpme at dt/16 as truth, arm, 0.5 s: the estimate is
    the error to within 10 % (O(dt) relative correction: the next term of RK4's series)."""
    s = arm_scenario()
    refined = run_gates.refined_gpme_runs(s.system, s.q0, s.q_dot0, 0.5, s.dt, OUTPUT_DT)
    from gpme_core.integrate import simulate
    truth = simulate(s.system, 0.5, s.q0, s.q_dot0, dt=s.dt / 16, output_dt=OUTPUT_DT)
    for c in ("q1", "q2", "q3_dot", "lambda_plane"):
        est = np.abs(run_gates.richardson_error(refined, c)).max()
        actual = np.abs(refined.coarse[c] - truth[c]).max()
        assert est == pytest.approx(actual, rel=0.1), c


def test_order_row_fails_outside_the_asymptotic_regime():
    """The arm at dt = 0.125 s, 2 s: Baumgarte's double eigenvalue -20 1/s puts h lambda =
    -2.5 near RK4's stability limit (-2.79), far from its asymptotic regime (measured
    p = 6.8 at dt = 0.125 s, 4.1 at 0.1 s): without step halving the order row fails; with
    it (the default) the step is halved into the asymptotic regime and the row passes."""
    s = arm_scenario(dt=0.125)
    refined = run_gates.refined_gpme_runs(s.system, s.q0, s.q_dot0, 2.0, s.dt, 0.125,
                                          max_halvings=0)
    df = mj_runs.programmed_run(s, 2.0, refined.dt, 0.125)
    row = _rows("mujoco", s, refined, df)[-1]
    assert row["status"] == "fail" and "meaningless" in row["reason"]
    halved = run_gates.refined_gpme_runs(s.system, s.q0, s.q_dot0, 2.0, s.dt, 0.125)
    assert halved.dt < refined.dt
    df = mj_runs.programmed_run(s, 2.0, halved.dt, 0.125)
    assert _rows("mujoco", s, halved, df)[-1]["status"] == "pass"


def _heavier(model, link, factor=1.01):
    """``model`` with the body of ``link`` 1 % denser (mass and inertia x factor)."""
    ine = model.links[[lk.name for lk in model.links].index(link)].inertia
    heavier = replace(ine, mass=ine.mass * factor,
                      inertia=tuple(tuple(factor * v for v in row) for row in ine.inertia))
    return model.with_changes(link_inertias={link: heavier})


@pytest.mark.parametrize("engine", ["pinocchio", "mujoco"])
@pytest.mark.parametrize("case, link", [("arm3", "q2"), ("crane_rigid", "slider")])
def test_one_percent_mass_in_the_engine_only_fails(exact, case, link, engine):
    s, refined, _, _ = exact(case)
    changed = _heavier(s.model, link)
    t_end = refined.t_end
    if engine == "pinocchio":
        df = pin_runs.programmed_run(s, t_end, refined.dt, OUTPUT_DT, pin_system=from_gpme(changed))
    else:
        df = mj_runs.programmed_run(s, t_end, refined.dt, OUTPUT_DT,
                                    mj_model=mj_runs.load(changed, refined.dt))
    rows = _rows(engine, s, refined, df)
    failed = {r["quantity"][len(LABEL) + 1:] for r in rows[:-1] if r["status"] == "fail"}
    lams = {f"lambda_{c}" for c in s.system.constraint_names}
    assert lams <= failed
    assert set(s.model.coordinate_names) & failed


def test_mujoco_callback_runs_at_every_stage(exact):
    """Constraint forces frozen over each step's stages are far worse than per stage."""
    s, refined, _, mj_df = exact("crane_rigid")
    frozen = mj_runs.programmed_run(s, refined.t_end, refined.dt, OUTPUT_DT, per_stage=False)
    g = refined.coarse
    for c in ("psi3", "z4", "lambda_Phi_1"):
        per_stage = np.abs(mj_df[c] - g[c]).max()
        worse = np.abs(frozen[c] - g[c]).max()
        assert worse > 1e4 * max(per_stage, 1e-16), c
    # 4 stages per step plus one refresh per recorded sample
    assert mj_df.attrs["stages"] == 4 * mj_df.attrs["steps"] + len(mj_df)


def test_forward_dynamics_sign_convention_against_kkt():
    """pin.forwardDynamics against our KKT solve with crba's M, seeded states of the arm:
    8 eps cond(M) (two solves, margin 4)."""
    s = arm_scenario()
    rng = np.random.default_rng(7)
    for _ in range(5):
        t, q, qd = rng.uniform(0, 2), rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
        da, dl, cond, a_max, l_max = pin_runs.kkt_residual(s, t, q, qd)
        tol = 8 * np.finfo(float).eps * cond
        assert da <= tol * a_max and dl <= tol * l_max


def test_model_file_override_replaces_the_gate(exact):
    s, refined, _, mj_df = exact("arm3")
    quantity = f"{LABEL} q2"
    over = replace(s, tolerances={f"mujoco/{quantity}": ToleranceOverride(
        f"mujoco/{quantity}", 0.0, 0.0, "a zero tolerance, to see it used")})
    rows = run_gates.run_rows("mujoco", over, refined, mj_df, ["q2"], LABEL, "test")
    assert rows[0]["reason"] == "override from the model file: a zero tolerance, to see it used"
    assert rows[0]["tol_abs"] == 0.0 and rows[0]["status"] == "fail"


def test_pinocchio_run_section_rows(exact):
    s, refined, _, _ = exact("arm3")
    rows = pin_runs.run_section(s, quick=True)
    assert all(r["status"] == "pass" for r in rows), [(r["quantity"], r["status"]) for r in rows]
    assert rows[-1]["quantity"].startswith("forwardDynamics sign convention")


def test_step_is_halved_until_the_run_is_in_rk4s_asymptotic_regime():
    """A flexible arm at half its RK4 stability limit (a model file's default step) is not
    in the asymptotic regime (observed order ~2.6 measured); refined_gpme_runs halves the
    step until gpme's own order is within 1 of 4, so the Richardson gate means something."""
    from gpme_io.modelfile import load_model_file
    scenario = load_model_file(REPO / "tests" / "data" / "runs" / "flexible_free_arm.toml")
    model, system = scenario.model, scenario.system
    q0, qd0, dt = scenario.q0, scenario.q_dot0, scenario.dt
    names = list(model.coordinate_names)
    columns = names + [f"{c}_dot" for c in names]
    once = run_gates.refined_gpme_runs(system, q0, qd0, 0.1, dt, OUTPUT_DT, max_halvings=0)
    refined = run_gates.refined_gpme_runs(system, q0, qd0, 0.1, dt, OUTPUT_DT)
    floors = {c: run_gates.roundoff_floor(float(np.abs(refined.coarse[c]).max()),
                                          refined.n_steps) for c in columns}
    p_once, _, _ = run_gates.observed_order(once, columns, floors)
    p, _, resolved = run_gates.observed_order(refined, columns, floors)
    assert refined.dt < once.dt
    assert abs(p_once - 4.0) > 1.0 and resolved and abs(p - 4.0) <= 1.0, (p_once, p)


def test_consistent_state_without_constraints_returns_the_state():
    s = arm_scenario()
    free = ProgrammedMotion(s.model, ())
    q, qd = free.consistent_state(0.0, s.q0, s.q_dot0)
    assert np.array_equal(q, s.q0) and np.array_equal(qd, s.q_dot0)


def test_a_run_beyond_the_step_budget_is_reported_not_run():
    """The crane at n_rfe = 10 needs dt ~4e-6 s for RK4 (Kelvin-Voigt torsion modes): 2 s is
    ~5e5 steps, above run_gates.MAX_RUN_STEPS; the section says so in an information row."""
    s = crane_scenario(10)
    assert s.dt < 1e-5
    rows = pin_runs.run_section(s, quick=False)
    assert len(rows) == 1 and rows[0]["status"] == "info"
    assert "above the budget" in rows[0]["reason"]

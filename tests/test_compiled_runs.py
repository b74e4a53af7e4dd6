"""Runs in the compiled loops (gpme_core.compiled_runs, gpme_core.kernels) against the
Python path of gpme_core.integrate.simulate (compiled=False: the Python RK4).

* compiled RK4 = Python RK4 (the same steps of the same ODE) to round-off;
* RadauIIA (compiled only) against an RK4 reference at a small step: its error, its
  order (step halving), the energy balance and the work integrals;
* the error paths: a run that diverges, a programmed motion out of reach, a SymPy
  constraint leaving its domain, a singular partition, RadauIIA on a system that does not
  compile, and the switch of the dependent coordinates, each with the error class and
  message of the Python path (and the same recorded events).

The models are the crane of gpme_examples, the SymPy crane and the driven spatial arm of
tests/test_compiled.py, and the two-link arm on a line of tests/test_dependent_switch.py.
"""
import numpy as np
import pytest

from gpme_core import compiled_runs, fast
from gpme_core.constraints import EllipseConstraint, JointProgramme
from gpme_core.errors import (ConstraintError, GpmeError, ModelError, SimulationError,
                              UnstableStepError)
from gpme_core.gpme import SWITCH_RCOND, ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_core.time_functions import Sine
from gpme_examples.crane import build_crane, crane_system, initial_state
from conftest import spatial_arm
from test_compiled import ARM, SINGULAR_AT, Ring, _arm_constraints, sympy_crane
from test_dependent_switch import DT as SWITCH_DT
from test_dependent_switch import T_END as SWITCH_T_END
from test_dependent_switch import _state_on_line
from test_dependent_switch import _system as line_system

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: no compiled path")


def _both(system, t_end, q0, q_dot0, **options):
    """(compiled run, Python run) of simulate with the same arguments."""
    return (simulate(system, t_end, q0, q_dot0, compiled=True, **options),
            simulate(system, t_end, q0, q_dot0, compiled=False, **options))


def _errors(system, t_end, q0, q_dot0, **options):
    """(compiled, Python): the GpmeError each path raises (pytest.fail if one does not;
    any other exception goes up as it is)."""
    out = []
    for flag in (True, False):
        try:
            simulate(system, t_end, q0, q_dot0, compiled=flag, **options)
        except GpmeError as exc:
            out.append(exc)
        else:
            pytest.fail(f"the {'compiled' if flag else 'Python'} run did not fail")
    return out


def assert_same_error(system, t_end, q0, q_dot0, **options):
    """Both paths fail with the same class and message; returns the compiled one."""
    fast_exc, python_exc = _errors(system, t_end, q0, q_dot0, **options)
    assert type(fast_exc) is type(python_exc), (fast_exc, python_exc)
    assert str(fast_exc) == str(python_exc)
    return fast_exc


def assert_same_unstable_step(system, t_end, q0, q_dot0, **options):
    """Both paths fail with UnstableStepError naming the same step and stability limit
    (computed at the same last recorded state); what the step then caused may be told at
    another stage of the failing step, but as a user's error, never as the compiled
    path's internal one ('please report')."""
    fast_exc, python_exc = _errors(system, t_end, q0, q_dot0, **options)
    assert isinstance(python_exc, UnstableStepError), python_exc
    assert type(fast_exc) is UnstableStepError, fast_exc
    cause = ". The failure it caused: "
    assert str(fast_exc).split(cause)[0] == str(python_exc).split(cause)[0]
    assert cause in str(fast_exc) and "please report" not in str(fast_exc), str(fast_exc)


# ---------------------------------------------------------------- 3. compiled RK4 = Python RK4
def _crane(n_rfe):
    system = crane_system(n_rfe)
    return (system, *initial_state(system.model))


def _arm_combined():
    system = ProgrammedMotion(ARM, _arm_constraints()["combined"])
    q0 = np.array([0.3, -0.2, 0.5, 0.4, 0.1])                  # off the four constraints
    return system, q0, np.zeros(5)


def _sympy():
    system = sympy_crane()
    return (system, *initial_state(system.model))


RK4_RUNS = {    # name: (system, q0, q_dot0), t_end s, dt s (below every stability limit)
    "crane_rigid": (lambda: _crane(0), 0.2, 1e-3),
    "crane_n2": (lambda: _crane(2), 0.05, 1e-4),
    "arm_combined_drives": (_arm_combined, 0.2, 1e-3),
    "crane_sympy": (_sympy, 0.045, 1e-3),            # stops before PHI_HEIGHT's edge
}


@pytest.mark.parametrize("name", list(RK4_RUNS))
def test_compiled_rk4_run_equals_python_rk4(name):
    build, t_end, dt = RK4_RUNS[name]
    system, q0, q_dot0 = build()
    fast_df, python_df = _both(system, t_end, q0, q_dot0, dt=dt, output_dt=5 * dt)
    assert fast_df.attrs["compiled"] is True and fast_df.attrs["compiled_reason"] == ""
    assert python_df.attrs["compiled"] is False
    assert python_df.attrs["compiled_reason"] == "compiled=False"
    assert fast_df.attrs["rhs_evaluations"] == python_df.attrs["rhs_evaluations"]
    assert list(fast_df.columns) == list(python_df.columns)
    np.testing.assert_array_equal(fast_df.t, python_df.t)
    # The same RK4 steps of the same ODE: only the evaluations' round-off differs (<= 1e-11
    # relative on the flexible crane, whose N^T M N has condition ~1e7; test_compiled),
    # summed in another order.  Carried through <= 2000 steps by a stable integration it
    # stays far below 1e-9 of each column's scale (measured <= 5e-13 of it).  Every column
    # is compared: coordinates, velocities, constraints, multipliers, drive torques, frame
    # positions, energies and the three work integrals.
    for col in fast_df.columns:
        scale = max(1.0, np.abs(python_df[col]).max())
        np.testing.assert_allclose(fast_df[col], python_df[col], rtol=0, atol=1e-9 * scale,
                                   err_msg=col)


def test_system_that_does_not_compile_runs_in_python_and_says_why():
    system = ProgrammedMotion(spatial_arm(), [Ring()])
    q0 = np.array([0.2, 0.1, -0.3, 0.4, 0.0])
    fast_df, python_df = _both(system, 0.05, q0, np.zeros(5), dt=1e-3)
    assert fast_df.attrs["compiled"] is False
    assert fast_df.attrs["compiled_reason"].startswith("constraint 'ring' is a Ring,")
    # both ran the Python RK4: the same arithmetic
    np.testing.assert_array_equal(fast_df.to_numpy(), python_df.to_numpy())


# ---------------------------------------------------------------- 4. RadauIIA accuracy
@pytest.fixture(scope="module")
def flexible_runs():
    """RK4 reference and RadauIIA runs of the flexible crane (n_rfe = 2, on the manifold,
    0.2 s): {"reference": df, 1e-3: df, 5e-4: df}.

    The reference: compiled RK4 (equal to the Python RK4, above) at dt = 2e-5 s (its
    stability limit is 1.6e-4 s); against dt = 1e-5 s it differs by 2.2e-13 in every
    coordinate, so its own error (16/15 of that for an order-4 method) is far below the
    RadauIIA errors measured here (>= 1e-9)."""
    system = crane_system(2)
    q0, q_dot0 = initial_state(system.model)
    common = dict(output_dt=0.01, on_manifold=True)
    runs = {"reference": simulate(system, 0.2, q0, q_dot0, dt=2e-5, **common)}
    for dt in (1e-3, 5e-4):
        runs[dt] = simulate(system, 0.2, q0, q_dot0, dt=dt, method="RadauIIA", **common)
    return system, runs


def test_radau_iia_error_and_order_on_the_flexible_crane(flexible_runs):
    system, runs = flexible_runs
    names = list(system.model.coordinate_names)
    ref = runs["reference"][names].to_numpy()
    errors = {dt: np.abs(runs[dt][names].to_numpy() - ref).max(axis=0) for dt in (1e-3, 5e-4)}
    for dt in (1e-3, 5e-4):
        df = runs[dt]
        assert df.attrs["method"] == "RadauIIA" and df.attrs["compiled"] is True
        assert df.attrs["dt"] == pytest.approx(dt, rel=1e-12)
        np.testing.assert_allclose(df.t, runs["reference"].t, rtol=0, atol=1e-12)
    # dt = 1 ms resolves the crane's motion (arm bending at 22 Hz: 45 steps a period) to
    # 6.4e-8 (m or rad) measured; 1e-6 on every coordinate leaves a factor ~15
    assert errors[1e-3].max() < 1e-6, errors[1e-3]
    # Halving the step: Radau IIA is of order 5 (stage order 3, to which stiff components
    # may reduce it).  Measured log2 ratios 4.5 (1 ms -> 0.5 ms) and 4.9-5.0 (0.5 -> 0.25
    # ms): this pair is in the asymptotic range; an order below 3 fails here.
    rate = np.log2(errors[1e-3].max() / errors[5e-4].max())
    assert rate >= 3.0, (rate, errors)


def test_radau_iia_energy_balance_and_work_integrals(flexible_runs):
    _, runs = flexible_runs
    ref = runs["reference"]
    # RK4 at 2e-5 s holds the balance to 1e-13 J: the check itself is exact to round-off
    assert np.abs(ref.E_balance_error).max() < 1e-11
    balance = {dt: np.abs(runs[dt].E_balance_error).max() for dt in (1e-3, 5e-4)}
    # E_kin reaches ~10 J; the balance error is the integrator's error in the energies and
    # the work integrals: measured 7.9e-10 J at 1 ms.  1e-7 J is 1e-8 of the energy.
    assert balance[1e-3] < 1e-7, balance
    # and it shrinks with the step at least as order 3 (measured 28x per halving)
    assert balance[1e-3] / balance[5e-4] >= 2.0 ** 3, balance
    # the work integrals (dissipated ~0.11 J, reaction ~0.42 J) agree with RK4's to the
    # integrator's error: measured 4.9e-9 J (W_reaction) at 1 ms
    for col in ("W_dissipated", "W_drive", "W_reaction"):
        np.testing.assert_allclose(runs[1e-3][col], ref[col], rtol=0, atol=1e-6, err_msg=col)


# ---------------------------------------------------------------- 5. error paths
DIVERGING = {    # RK4 steps far above the stability limit (1.6e-4 s at n_rfe = 2)
    "crane_n1_dt5ms": (lambda: _crane(1), 5e-3),
    "crane_n2_dt2ms": (lambda: _crane(2), 2e-3),
    "crane_n2_no_constraints_dt2ms": (
        lambda: (ProgrammedMotion(build_crane(2)), *initial_state(build_crane(2))), 2e-3),
}


@pytest.mark.parametrize("name", list(DIVERGING))
def test_diverging_run_fails_as_on_the_python_path(name):
    build, dt = DIVERGING[name]
    system, q0, q_dot0 = build()
    exc = assert_same_error(system, 1.0, q0, q_dot0 + 0.1, dt=dt, output_dt=dt,
                            check_step=False)
    assert isinstance(exc, UnstableStepError)
    assert "The failure it caused: the run diverged at t = " in str(exc)


class Livelock(AssertionError):
    """The compiled loop kept switching the dependent coordinates at one step."""


def test_diverging_run_that_switches_partitions_within_a_step(monkeypatch):
    """The flexible crane (n_rfe = 2) at dt = 10 ms: its stages leave any sensible state.
    The Python RK4 switches once (t = 0.015 s, psi3, z4 -> theta_arm_2, phi_arm_1) and
    then stops with UnstableStepError (A of rank < 2 at the next stage).  The compiled loop
    switches at the same stage, restarts the step at t = 0.01 s, finds the new partition
    bad there, switches to (z4, z1), reaches the stage at 0.015 s again, switches back, and
    so on.  A guard stops it after 200 switches (the Python run needs one)."""
    switch = compiled_runs._switch
    calls = []

    def guarded(*args):
        calls.append(args[1])
        if len(calls) > 200:
            raise Livelock(f"200 partition switches, the last at t = {args[1]} s")
        return switch(*args)
    monkeypatch.setattr(compiled_runs, "_switch", guarded)
    system, q0, q_dot0 = _crane(2)
    assert_same_unstable_step(system, 1.0, q0, q_dot0 + 0.1, dt=1e-2, output_dt=1e-2,
                              check_step=False)


def test_diverging_run_whose_stage_loses_positive_definiteness():
    """The flexible crane without constraints at dt = 10 ms: the Python RK4 says the run
    diverged at the end of the step (t = 0.02 s); the compiled loop meets a stage there
    whose mass matrix is no longer positive definite in floating point."""
    system = ProgrammedMotion(build_crane(2))
    q0, q_dot0 = initial_state(system.model)
    assert_same_unstable_step(system, 1.0, q0, q_dot0 + 0.1, dt=1e-2, output_dt=1e-2,
                              check_step=False)


def _z4_programme():
    """The rigid crane with its ellipse and z4 programmed to 0.2 + 0.5 sin(2 pi t / 0.4) m:
    beyond the slider's stroke (0.5 m) from t* = 0.4 asin(0.6) / (2 pi) = 0.04097 s."""
    model = build_crane(0)
    system = ProgrammedMotion(model, [EllipseConstraint(0.375, 0.75, name="Phi_1"),
                                      JointProgramme("z4", Sine(0.2, 0.5, 0.4), name="z4_prog")],
                              dependent=("psi3", "z4"))
    return system, *initial_state(model)


@pytest.mark.parametrize("method", ["RK4", "RadauIIA"])
def test_programmed_motion_out_of_reach(method):
    system, q0, q_dot0 = _z4_programme()
    options = dict(dt=1e-3, on_manifold=True)
    # the first step end past t* = 0.04097 s is 0.041 s; z4 follows the programme there to
    # the integrator's error (< 1e-9 m at 1 ms), far inside the 6 digits printed
    t_star = 0.4 * np.arcsin(0.6) / (2 * np.pi)
    assert 0.040 < t_star < 0.041
    z4 = 0.2 + 0.5 * np.sin(2 * np.pi * 0.041 / 0.4)
    expected = (f"at t = 0.041 s the motion reaches z4 = {z4:.6g} m outside its range "
                "[-0.3, 0.5]: the mechanism cannot follow it")
    if method == "RK4":
        exc = assert_same_error(system, 0.2, q0, q_dot0, **options)
    else:
        with pytest.raises(ConstraintError) as info:
            simulate(system, 0.2, q0, q_dot0, method=method, **options)
        exc = info.value
    assert isinstance(exc, ConstraintError) and str(exc).startswith(expected), str(exc)


def test_sympy_constraint_leaving_its_domain_fails_as_on_the_python_path():
    """PHI_HEIGHT's sqrt(0.05 - t) is not real after 0.05 s.  With dt = 3 ms the stage
    times are multiples of 1.5 ms: the first past 0.05 s is 0.051 s (0.05 s is never
    evaluated), where the compiled kernel finds NaN and the Python reference raises."""
    system, q0, q_dot0 = _sympy()
    exc = assert_same_error(system, 0.09, q0, q_dot0, dt=3e-3, output_dt=3e-3)
    assert isinstance(exc, ConstraintError)
    assert str(exc).startswith("constraint 'Phi_2s': phi = ")
    assert "is not finite at t = 0.051 s" in str(exc) and "sqrt: where 0.05 - t <= 0" in str(exc)


def test_sympy_constraint_at_its_pole_fails_as_on_the_python_path():
    """With dt = 1 ms the run evaluates t = 0.05 s exactly, where PHI_HEIGHT's time
    derivatives divide by zero."""
    system, q0, q_dot0 = _sympy()
    assert 50 * 1e-3 == SINGULAR_AT
    exc = assert_same_error(system, 0.09, q0, q_dot0, dt=1e-3, output_dt=1e-3)
    assert "is not finite at t = 0.05 s" in str(exc)


@pytest.mark.parametrize("method", ["RK4", "RadauIIA"])
def test_singular_partition_without_switching(method):
    """The two-link arm on the line x = 1.2 m started with link 2 horizontal: the q2 column
    of A is 0, so the given partition (q2) is singular at t = 0; switch_rcond=None keeps
    it and the run must stop with the Python path's message."""
    q0, q_dot0 = _state_on_line(0.0, 2.0)
    system = line_system(("q2",))
    options = dict(dt=SWITCH_DT, switch_rcond=None)
    if method == "RK4":
        exc = assert_same_error(system, 0.2, q0, q_dot0, check_step=False, **options)
        assert isinstance(exc, ConstraintError)
        assert str(exc).startswith("at t = 0 s the dependent block K_dc of the constraint "
                                   "Jacobian (columns ['q2']) is singular")
    else:
        python_exc = _errors(system, 0.2, q0, q_dot0, check_step=False, **options)[1]
        with pytest.raises(ConstraintError) as info:
            simulate(system, 0.2, q0, q_dot0, method=method, **options)
        assert str(info.value) == str(python_exc)


def test_radau_iia_starting_on_a_singular_partition_switches_at_once():
    """As the RK4 run of tests/test_dependent_switch.py: started with the q2 column of A
    zero, the run switches to q1 at t = 0 and moves as the run given q1 from the start."""
    q0, q_dot0 = _state_on_line(0.0, 2.0)
    df = simulate(line_system(("q2",)), 0.2, q0, q_dot0, method="RadauIIA", dt=SWITCH_DT)
    first = df.attrs["events"][0]
    assert (first["t"], first["old_dependent"], first["new_dependent"], first["rcond"]) == (
        0.0, ["q2"], ["q1"], 0.0)
    ref = simulate(line_system(("q1",)), 0.2, q0, q_dot0, method="RadauIIA", dt=SWITCH_DT,
                   switch_rcond=None)
    # the same fixed steps of the same ODE; the partitions differ only in round-off
    # (amplified at most 1/SWITCH_RCOND = 1e3 in a solve) over 200 steps: 1e-9 rad
    np.testing.assert_allclose(df[["q1", "q2"]].to_numpy(), ref[["q1", "q2"]].to_numpy(),
                               rtol=0, atol=1e-9)


def test_radau_iia_refuses_a_system_that_does_not_compile():
    system = ProgrammedMotion(spatial_arm(), [Ring()])
    with pytest.raises(ModelError, match=r"method 'RadauIIA' runs compiled only, and this "
                                         r"system cannot be compiled: constraint 'ring' is a "
                                         r"Ring, .*use method='Radau' \(SciPy\) or 'RK4'"):
        simulate(system, 0.05, np.zeros(5), np.zeros(5), method="RadauIIA")


def test_dependent_switch_in_a_compiled_run():
    """The falling two-link arm of tests/test_dependent_switch.py crosses the configurations
    where its q2 and then its q1 partition become singular: the compiled RK4 run switches
    at the same evaluations as the Python one and moves the same."""
    q0, q_dot0 = _state_on_line(0.5, -2.0)
    fast_df, python_df = _both(line_system(("q2",)), SWITCH_T_END, q0, q_dot0, dt=SWITCH_DT,
                               output_dt=SWITCH_DT)
    assert fast_df.attrs["compiled"] is True
    events, python_events = fast_df.attrs["events"], python_df.attrs["events"]
    assert [(e["old_dependent"], e["new_dependent"]) for e in events] == [
        (["q2"], ["q1"]), (["q1"], ["q2"])]
    assert len(python_events) == len(events)
    for e, p in zip(events, python_events):
        assert set(e) == set(p) and e["event"] == p["event"] == "dependent_switch"
        assert (e["old_dependent"], e["new_dependent"]) == (p["old_dependent"],
                                                              p["new_dependent"])
        # the same evaluation (stage time k dt + dt/2 or k dt, up to one rounding of t)
        assert e["t"] == pytest.approx(p["t"], rel=0, abs=1e-12)
        # the same state up to round-off; the vanishing column (~3e-4 of the largest) has
        # an absolute error ~1e-15: relative 1e-8 bounds it
        assert e["rcond"] == pytest.approx(p["rcond"], rel=1e-8)
        assert e["new_rcond"] == pytest.approx(p["new_rcond"], rel=1e-12)
        assert e["rcond"] < SWITCH_RCOND
    assert fast_df.attrs["dependent_final"] == python_df.attrs["dependent_final"] == ["q2"]
    # same steps, same ODE: round-off amplified at most 1/SWITCH_RCOND = 1e3 in the reduced
    # solves near the switches, over 500 steps: 1e-9 bounds it (measured 2.6e-15)
    cols = ["q1", "q2", "q1_dot", "q2_dot", "Phi_x", "lambda_Phi_x"]
    for col in cols:
        scale = max(1.0, np.abs(python_df[col]).max())
        np.testing.assert_allclose(fast_df[col], python_df[col], rtol=0, atol=1e-9 * scale,
                                   err_msg=col)


def test_dependent_switch_in_a_radau_iia_run():
    """The same crossing with RadauIIA: both switches recorded, and the motion within the
    step's error of the RK4 run at the same dt."""
    q0, q_dot0 = _state_on_line(0.5, -2.0)
    system = line_system(("q2",))
    radau = simulate(system, SWITCH_T_END, q0, q_dot0, dt=SWITCH_DT, output_dt=SWITCH_DT,
                     method="RadauIIA")
    rk4 = simulate(system, SWITCH_T_END, q0, q_dot0, dt=SWITCH_DT, output_dt=SWITCH_DT,
                   compiled=False)
    assert radau.attrs["compiled"] is True
    events = radau.attrs["events"]
    assert [(e["old_dependent"], e["new_dependent"]) for e in events] == [
        (["q2"], ["q1"]), (["q1"], ["q2"])]
    for e, p in zip(events, rk4.attrs["events"]):
        # Radau's stages are at t + c_i dt (c = 0.155, 0.645, 1), RK4's at t, t + dt/2,
        # t + dt: both switch within the step where rcond falls below SWITCH_RCOND
        assert abs(e["t"] - p["t"]) <= SWITCH_DT, (e, p)
        assert e["rcond"] < SWITCH_RCOND
    # RK4 and Radau IIA at 1 ms each have errors ~1e-10 rad here (steps of 1e-3 s on a
    # motion of ~10 rad/s^2): 1e-8 rad bounds their difference
    np.testing.assert_allclose(radau[["q1", "q2"]].to_numpy(), rk4[["q1", "q2"]].to_numpy(),
                               rtol=0, atol=1e-8)

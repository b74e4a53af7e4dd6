"""Re-choosing the dependent coordinates during a run (gpme_core.integrate.simulate).

The mechanism: a planar two-link arm (revolute joints about z, uniform rods of length
L1 = L2 = 1 m and mass 1 kg, gravity -9.81 m/s^2 along y) whose end point E slides on the
vertical line x = C = 1.2 m (one constraint, one degree of freedom: a slider-crank).  With
theta2 = q1 + q2 the absolute angle of link 2, by hand:

    x_E = L1 cos q1 + L2 cos theta2,
    A   = [dx_E/dq1, dx_E/dq2] = [-L1 sin q1 - L2 sin theta2, -L2 sin theta2].

So the column of q2 vanishes where link 2 is horizontal (theta2 = 0) and the column of q1
where q1 = -theta2.  Started with link 2 pointing up-right and falling, the arm crosses
theta2 = 0 (q2 partition singular) and later q1 = -theta2 (q1 partition singular).  For
one constraint the partition's reciprocal condition (gpme_core.gpme.partition_rcond) is
|a_dc| / max(|a_1|, |a_2|), evaluated here from the hand formula above.

The reference is integrated independently of any partition: the same classical RK4 on the
Lagrange-multiplier (KKT) form, ProgrammedMotion.kkt_accelerations.
"""
import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline
from scipy.optimize import brentq

from gpme_core import transforms as tf
from gpme_core.constraints import CoordinateProgramme
from gpme_core.errors import ConstraintError
from gpme_core.gpme import SWITCH_RCOND, ProgrammedMotion, partition_rcond
from gpme_core.inertia import RigidBodyInertia
from gpme_core.integrate import simulate
from gpme_core.model import REVOLUTE, ChainBuilder
from gpme_core.time_functions import Constant

L1 = L2 = 1.0      # m
MASS = 1.0         # kg, each rod
C = 1.2            # m, the line x = C
DT = 1e-3          # s, RK4 step
T_END = 0.5        # s: both crossings happen before (about 0.17 s and 0.40 s)


def _rod(length):
    """Uniform thin rod along +x from the joint: I_yy = I_zz = m l^2 / 12 about its centre."""
    i = MASS * length ** 2 / 12.0
    return RigidBodyInertia(MASS, (0.5 * length, 0.0, 0.0), np.diag([0.0, i, i]))


def _arm_model():
    b = ChainBuilder("two_link_on_a_line", gravity=(0.0, -9.81, 0.0))
    b.add_joint("q1", REVOLUTE, (0, 0, 1))
    b.add_body(_rod(L1))
    b.add_joint("q2", REVOLUTE, (0, 0, 1), origin=tf.translation(L1))
    b.add_body(_rod(L2))
    b.add_frame("E", tf.translation(L2))
    return b.build()


MODEL = _arm_model()
CONSTRAINTS = (CoordinateProgramme(Constant(C), axis=0, frame="E", name="Phi_x"),)


def _system(dependent):
    return ProgrammedMotion(MODEL, CONSTRAINTS, dependent=dependent)


def _state_on_line(theta2, theta2_dot):
    """(q (2,), q_dot (2,)) with E on x = C, link 1 above the x axis (q1 > 0), by hand:
    cos q1 = (C - L2 cos theta2) / L1 and, from d x_E / dt = 0,
    q1_dot = -L2 sin(theta2) theta2_dot / (L1 sin q1)."""
    q1 = np.arccos((C - L2 * np.cos(theta2)) / L1)
    q1_dot = -L2 * np.sin(theta2) * theta2_dot / (L1 * np.sin(q1))
    return np.array([q1, theta2 - q1]), np.array([q1_dot, theta2_dot - q1_dot])


def _jacobian_by_hand(q):
    th2 = q[..., 0] + q[..., 1]
    return np.stack([-L1 * np.sin(q[..., 0]) - L2 * np.sin(th2), -L2 * np.sin(th2)], axis=-1)


def _rcond_by_hand(q, k):
    """partition_rcond of dependent coordinate k (0: q1, 1: q2) for one constraint."""
    a = np.abs(_jacobian_by_hand(q))
    return a[..., k] / a.max(axis=-1)


def _kkt_rk4(q0, q_dot0, t_end, dt):
    """(t (k,), q (k, 2), q_dot (k, 2)): classical RK4 on the KKT form, every step."""
    system = _system(("q1",))      # the partition is not used by kkt_accelerations
    y = np.concatenate([q0, q_dot0])

    def f(t, y):
        return np.concatenate([y[2:], system.kkt_accelerations(t, y[:2], y[2:])[0]])
    n_steps = int(round(t_end / dt))
    ys = [y]
    for k in range(n_steps):
        t = k * dt
        k1 = f(t, y)
        k2 = f(t + dt / 2, y + dt / 2 * k1)
        k3 = f(t + dt / 2, y + dt / 2 * k2)
        k4 = f(t + dt, y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        ys.append(y)
    ys = np.array(ys)
    return dt * np.arange(n_steps + 1), ys[:, :2], ys[:, 2:]


def _window_entry(t, q, q_dot, k, threshold):
    """(t_window, t_crossing) s: on the reference trajectory, the time the partition with
    dependent coordinate k first has partition_rcond = threshold and the time its column
    vanishes.  Between the RK4 samples q(t) is the cubic Hermite interpolant of (q, q_dot)
    (error ~ dt^4 |d4q/dt4| / 384 ~ 1e-13 rad), so the window (narrower than one step) is
    resolved; the signed column divided by the largest is solved for by brentq."""
    spline = CubicHermiteSpline(t, q, q_dot)

    def signed(tt):
        a = _jacobian_by_hand(spline(tt))
        return a[k] / np.abs(a).max()
    col = _jacobian_by_hand(q)[:, k]
    j = np.flatnonzero(np.sign(col[1:]) != np.sign(col[:-1]))[0]    # first sign change
    t_cross = brentq(signed, t[j], t[j + 1], xtol=1e-14)
    side = np.sign(col[j])
    t_win = brentq(lambda tt: side * signed(tt) - threshold, t[j] - 0.05, t_cross, xtol=1e-14)
    return t_win, t_cross


@pytest.fixture(scope="module")
def falling_arm():
    q0, q_dot0 = _state_on_line(0.5, -2.0)     # link 2 up-right, swinging down at 2 rad/s
    return q0, q_dot0, _kkt_rk4(q0, q_dot0, T_END, DT)


@pytest.mark.both_computation_paths
def test_rk4_run_switches_where_each_partition_becomes_singular(falling_arm):
    q0, q_dot0, (t_ref, q_ref, qd_ref) = falling_arm
    given = _system(("q2",))
    assert 0.0 < _window_entry(t_ref, q_ref, qd_ref, 1, SWITCH_RCOND)[1] < \
        _window_entry(t_ref, q_ref, qd_ref, 0, SWITCH_RCOND)[1] < T_END
    df = simulate(given, T_END, q0, q_dot0, dt=DT, output_dt=DT)
    events = df.attrs["events"]
    assert [(e["old_dependent"], e["new_dependent"]) for e in events] == [
        (["q2"], ["q1"]), (["q1"], ["q2"])]
    assert df.attrs["dependent"] == ["q2"] and df.attrs["dependent_final"] == ["q2"]
    for k, e in zip((1, 0), events):          # the column that vanished: q2, then q1
        assert 0.0 <= e["rcond"] < SWITCH_RCOND
        assert e["new_rcond"] == pytest.approx(1.0, rel=1e-12)   # the largest column
        # the configuration the run avoided, on the reference trajectory
        t_window, t_crossing = _window_entry(t_ref, q_ref, qd_ref, k, SWITCH_RCOND)
        # RK4 evaluates at t, t + dt/2 (twice) and t + dt: the first evaluation after the
        # reference enters the window switches.  Slack 1e-5 s: the stage states differ
        # from the trajectory by ~dt^2/8 |theta2_ddot| ~ 1e-6 rad, and the interpolated
        # entry time by ~1e-7 s, at |theta2_dot| > 1 rad/s.
        assert t_window - 1e-5 <= e["t"] <= t_window + DT / 2 + 1e-5, (e, t_window)
        assert e["t"] < t_crossing
    # the same motion as the partition-free reference: the same RK4 steps on the same ODE;
    # they differ by round-off amplified at most 1/SWITCH_RCOND = 1e3 in the reduced solve
    # (~1e-13 per evaluation) over 500 steps, far inside 1e-9
    q = df[["q1", "q2"]].to_numpy()
    qd = df[["q1_dot", "q2_dot"]].to_numpy()
    np.testing.assert_allclose(df.t, t_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(q, q_ref, rtol=0, atol=1e-9)
    np.testing.assert_allclose(qd, qd_ref, rtol=0, atol=1e-8)
    # the constraint residual, by hand from the recorded coordinates: RK4's drift at
    # dt = 1e-3 s (local error ~ dt^5 |d^5 x/dt^5| ~ 1e-12 m) held by Baumgarte's
    # 1/20 s time constant (~50 steps) stays near 1e-10 m; 1e-8 m bounds it
    x_e = L1 * np.cos(q[:, 0]) + L2 * np.cos(q.sum(axis=1))
    assert np.abs(x_e - C).max() < 1e-8
    np.testing.assert_allclose(df.Phi_x, x_e - C, rtol=0, atol=1e-14)


def test_without_switching_the_run_reads_the_same_but_keeps_the_partition(falling_arm):
    q0, q_dot0, (t_ref, q_ref, _) = falling_arm
    df = simulate(_system(("q2",)), 0.3, q0, q_dot0, dt=DT, output_dt=DT, switch_rcond=None)
    assert df.attrs["events"] == [] and df.attrs["dependent_final"] == ["q2"]
    # it went through theta2 = 0 between two evaluations, losing digits near it (the
    # nearest stage has rcond ~ |theta2| ~ 1e-4, eps / 1e-4 ~ 1e-12): 1e-9 as above
    np.testing.assert_allclose(df[["q1", "q2"]].to_numpy(), q_ref[:301], rtol=0, atol=1e-9)


@pytest.mark.parametrize("method", ["RK4", "RK45", "Radau"])
def test_run_starting_on_a_singular_partition_switches_at_once(method):
    q0, q_dot0 = _state_on_line(0.0, 2.0)      # link 2 horizontal: the q2 column is 0
    given = _system(("q2",))
    a = given.constraints(0.0, q0, q_dot0)[2]
    np.testing.assert_allclose(a, [_jacobian_by_hand(q0)], rtol=0, atol=1e-15)
    assert partition_rcond(a, [1]) == 0.0
    with pytest.raises(ConstraintError, match=r"at t = 0 s the dependent block K_dc .*"
                                              r"\['q2'\]\) is singular"):
        simulate(given, 0.2, q0, q_dot0, method=method, dt=DT, switch_rcond=None)
    df = simulate(given, 0.2, q0, q_dot0, method=method, dt=DT)
    first = df.attrs["events"][0]
    assert (first["t"], first["old_dependent"], first["new_dependent"], first["rcond"]) == (
        0.0, ["q2"], ["q1"], 0.0)
    # the other partition from the start, same method: the same ODE and the same error
    # control; differences only from round-off steering the step choices, far below the
    # per-step tolerances (rtol 1e-8, atol 1e-10) over the ~0.2 s run: 1e-8 rad
    ref = simulate(_system(("q1",)), 0.2, q0, q_dot0, method=method, dt=DT,
                   switch_rcond=None)
    np.testing.assert_allclose(df[["q1", "q2"]].to_numpy(), ref[["q1", "q2"]].to_numpy(),
                               rtol=0, atol=1e-8)
    q = df[["q1", "q2"]].to_numpy()
    # constraint residual: Radau at rtol 1e-8 is the loosest of the three (its local error
    # per step ~ rtol |x| ~ 1e-8 m, held by Baumgarte); 1e-7 m bounds all of them
    assert np.abs(L1 * np.cos(q[:, 0]) + L2 * np.cos(q.sum(axis=1)) - C).max() < 1e-7


def test_solve_switches_only_when_asked_and_never_changes_the_system():
    q, qd = _state_on_line(1e-5, 2.0)           # partition_rcond of q2 ~ 1e-5 < 1e-3
    system = _system(("q2",))
    kept = system.solve(0.0, q, qd)
    assert kept.dependent == ("q2",)
    assert kept.partition_rcond == pytest.approx(_rcond_by_hand(q, 1), rel=1e-9)
    switched = system.solve(0.0, q, qd, switch_below=SWITCH_RCOND)
    assert switched.dependent == ("q1",) and system.dependent == ("q2",)
    assert switched.partition_rcond == pytest.approx(1.0, rel=1e-12)
    kkt, lam = system.kkt_accelerations(0.0, q, qd)
    # q_ddot ~ 10 rad/s^2; the kept partition loses ~5 digits (rcond 1e-5), the switched
    # one none: both agree with the KKT form to their round-off
    np.testing.assert_allclose(switched.q_ddot, kkt, rtol=0, atol=1e-12)
    np.testing.assert_allclose(kept.q_ddot, kkt, rtol=0, atol=1e-8)
    np.testing.assert_allclose(switched.multipliers, lam, rtol=0, atol=1e-11)


def test_bad_switch_threshold_is_rejected():
    q0, q_dot0 = _state_on_line(0.5, 0.0)
    with pytest.raises(Exception, match="switch_rcond must be a positive number or None"):
        simulate(_system(("q2",)), 0.1, q0, q_dot0, switch_rcond=-1.0)


def test_events_are_written_with_the_run_outputs(falling_arm):
    import json
    from gpme_io.runs import events_json
    q0, q_dot0, _ = falling_arm
    df = simulate(_system(("q2",)), 0.2, q0, q_dot0, dt=DT, output_dt=0.01)
    doc = json.loads(events_json(df))
    assert doc["dependent"] == ["q2"] and doc["dependent_final"] == ["q1"]
    assert doc["events"] == df.attrs["events"] and len(doc["events"]) == 1
    assert set(doc["events"][0]) == {"event", "t", "old_dependent", "new_dependent", "rcond",
                                     "new_rcond"}

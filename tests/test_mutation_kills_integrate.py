"""Kill tests for gpme_core.integrate (docs/mutation.md): RK4 runs of a forced, damped,
programmed x-y table compared step by step with classical RK4 written out here on the
closed-form ODE (agreement to round-off), the step plan when dt does not divide the
output step, the RK4 stability constants, every recorded column by hand, the solve_ivp
path against the exact oscillator, and the run's input and divergence checks."""
import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.constraints import CoordinateProgramme
from gpme_core.errors import ConstraintError, ModelError, SimulationError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.integrate import rk4_step_plan, simulate
from gpme_core.stability import rk4_stability_step, suggest_rk4_step
from gpme_core.model import PRISMATIC, ChainBuilder
from gpme_core.time_functions import Sine

pytestmark = pytest.mark.both_computation_paths

M, KX, KY, DX, DY = 2.0, 30.0, 50.0, 0.4, 0.7
EX = (0.1, 0.2, 0.3)
FORCE = Sine(0.0, 0.5, 1.5, 0.35)             # drive on y, N
PROG = Sine(0.12, 0.05, 0.8, 0.4)           # x_E(t), m
ALPHA, BETA = 5.0, 6.0


def table(programmed=True, limits_y=(-np.inf, np.inf)):
    b = ChainBuilder("xy", gravity=(0, 0, -9.81))
    b.add_joint("x", PRISMATIC, (1, 0, 0), stiffness=KX, damping=DX)
    b.add_joint("y", PRISMATIC, (0, 1, 0), stiffness=KY, damping=DY, limits=limits_y)
    b.add_body(cuboid(M, (0.1, 0.1, 0.1)))
    b.add_frame("E", tf.translation(*EX))
    b.add_drive("y", FORCE)
    model = b.build()
    cons = [CoordinateProgramme(PROG, axis=0, name="P")] if programmed else []
    return ProgrammedMotion(model, cons, dependent=["x"] if programmed else None,
                            baumgarte=(ALPHA, BETA))


def prog(t):
    w = 2 * np.pi / 0.8
    return (0.12 + 0.05 * np.sin(w * t + 0.4), 0.05 * w * np.cos(w * t + 0.4),
            -0.05 * w * w * np.sin(w * t + 0.4))


def force(t):
    return 0.5 * np.sin(2 * np.pi * t / 1.5 + 0.35)


def ode(t, s, programmed):
    """Closed form of the table: s = (x, y, x_dot, y_dot, W_diss, W_drive, W_reaction)."""
    x, y, xd, yd = s[:4]
    qx = -KX * x - DX * xd
    qy = -KY * y - DY * yd + force(t)
    if programmed:
        f, fd, fdd = prog(t)
        xdd = fdd - 2 * ALPHA * (xd - fd) - BETA ** 2 * (x + EX[0] - f)
        lam = M * xdd - qx
    else:
        xdd, lam = qx / M, 0.0
    ydd = qy / M
    return np.array([xd, yd, xdd, ydd, DX * xd ** 2 + DY * yd ** 2, yd * force(t), xd * lam])


def rk4_reference(s0, h, n_steps, programmed):
    """Classical RK4 (Kutta 1901), written out independently of gpme_core."""
    out = [np.array(s0, float)]
    s = out[0]
    for k in range(n_steps):
        t = k * h
        k1 = ode(t, s, programmed)
        k2 = ode(t + h / 2, s + h / 2 * k1, programmed)
        k3 = ode(t + h / 2, s + h / 2 * k2, programmed)
        k4 = ode(t + h, s + h * k3, programmed)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(s)
    return np.array(out)


@pytest.mark.parametrize("programmed", [False, True])
def test_rk4_run_equals_hand_written_rk4_when_dt_does_not_divide_the_output_step(programmed):
    """t_end = 0.1 s, dt = 0.003 s, output every 0.01 s: 0.003 does not divide 0.01, so the
    step is shortened to 0.01 / ceil(0.01 / 0.003) = 0.0025 s (40 steps, a row every 4).
    Every recorded state and work integral equals the hand-written RK4 with that step to
    round-off (1e-12 relative to the state's scale: ~40 steps of 1e-16 errors)."""
    system = table(programmed)
    q0, qd0 = np.array([0.03, -0.02]), np.array([0.4, 0.3])
    df = simulate(system, 0.1, q0, qd0, dt=0.003, output_dt=0.01)
    ref = rk4_reference([*q0, *qd0, 0, 0, 0], 0.0025, 40, programmed)[::4]
    np.testing.assert_allclose(df["t"], np.arange(11) * 0.01, rtol=0, atol=1e-15)
    cols = ["x", "y", "x_dot", "y_dot", "W_dissipated", "W_drive", "W_reaction"]
    np.testing.assert_allclose(df[cols].to_numpy(), ref, rtol=1e-12, atol=1e-13)
    assert df.attrs["dt"] == pytest.approx(0.0025, rel=1e-15)
    assert df.attrs["rhs_evaluations"] == 160
    assert df.attrs["method"] == "RK4" and df.attrs["dependent"] == (["x"] if programmed else [])
    # recorded columns by hand
    x, y, xd, yd = ref[:, 0], ref[:, 1], ref[:, 2], ref[:, 3]
    t = df["t"].to_numpy()
    np.testing.assert_allclose(df["E_kin"], 0.5 * M * (xd ** 2 + yd ** 2), rtol=1e-12)
    # gravity along -z; the carriage's centre stays at z = 0: only the springs store energy
    np.testing.assert_allclose(df["E_pot"], 0.5 * KX * x ** 2 + 0.5 * KY * y ** 2, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(df["x_E"], x + EX[0], rtol=1e-12)
    np.testing.assert_allclose(df["y_E"], y + EX[1], rtol=1e-12)
    np.testing.assert_allclose(df["z_E"], EX[2], rtol=1e-12)
    np.testing.assert_allclose(df["tau_y"], force(t), rtol=1e-12, atol=1e-15)
    e = df["E_kin"] + df["E_pot"]
    np.testing.assert_allclose(df["E_balance_error"],
                               (e - e[0]) - (ref[:, 5] + ref[:, 6] - ref[:, 4]), rtol=1e-9, atol=1e-15)
    if programmed:
        f, fd, fdd = prog(t)
        np.testing.assert_allclose(df["P"], x + EX[0] - f, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(df["P_dot"], xd - fd, rtol=1e-12, atol=1e-14)
        lam = np.array([ode(tk, s, True)[6] / s[2] for tk, s in zip(t, ref)])
        np.testing.assert_allclose(df["lambda_P"], lam, rtol=1e-10)


def test_step_plan_by_hand():
    """(step, steps per row): whole number of rows -> output_dt / ceil(output_dt / dt);
    otherwise t_end / ceil(t_end / dt) and the nearest whole number of steps per row."""
    assert rk4_step_plan(1.0, 0.003, 0.01) == (pytest.approx(0.0025), 4)
    assert rk4_step_plan(1.0, 0.002, 0.01) == (pytest.approx(0.002), 5)
    step, per = rk4_step_plan(1.005, 0.003, 0.01)              # 100.5 rows: not whole
    assert step == pytest.approx(1.005 / 335) and per == 3
    step, per = rk4_step_plan(1.0, 0.003, 0.001)               # rows closer than dt
    assert step == pytest.approx(1 / 334) and per == 1
    assert rk4_step_plan(0.5, 0.01, 0.1) == (pytest.approx(0.01), 10)


def test_rk4_stability_constants():
    """|R(z)| = 1 on the negative real axis at z = -2.785293563405282 and on the imaginary
    axis at |z| = 2 sqrt(2) (classical RK4 stability region); inf for lambda = 0 and for
    growing modes.  Bisection to 2^-60: 1e-12 relative is safe."""
    assert rk4_stability_step(-10.0) == pytest.approx(0.2785293563405282, rel=1e-12)
    assert rk4_stability_step(5j) == pytest.approx(2 * np.sqrt(2) / 5, rel=1e-12)
    assert rk4_stability_step(0.0) == np.inf
    assert rk4_stability_step(3.0) == np.inf
    # a slowly growing oscillation (Re lambda > 0 below 1 % of |lambda|: physically 0.1 % per
    # radian, or finite-difference round-off of an undamped mode) still needs the step of
    # its frequency, or RK4 amplifies it by orders of magnitude per step; a fast-growing
    # mode (Re lambda > 1 % of |lambda|) limits no step
    assert rk4_stability_step(0.001 + 1j) == pytest.approx(2 * np.sqrt(2), rel=1e-12)
    assert rk4_stability_step(0.5 + 1j) == np.inf


def test_suggested_step_of_undamped_and_overdamped_sliders():
    """One slider, mass m, spring k: lambda = +-i sqrt(k/m) -> h = 0.5 * 2 sqrt(2) / omega.
    With damping c > 2 sqrt(k m): lambda = (-c -+ sqrt(c^2 - 4 k m)) / (2 m), the faster
    one limits: h = 0.5 * 2.78529... / |lambda_fast|."""
    def slider(k, c):
        b = ChainBuilder("s")
        b.add_joint("x", PRISMATIC, (1, 0, 0), stiffness=k, damping=c)
        b.add_body(cuboid(2.0, (0.1, 0.1, 0.1)))
        return b.build()
    assert suggest_rk4_step(slider(50.0, 0.0), np.zeros(1)) == pytest.approx(0.5 * 2 * np.sqrt(2) / 5.0, rel=1e-9)
    lam = (-100.0 - np.sqrt(100.0 ** 2 - 4 * 50.0 * 2.0)) / 4.0
    assert suggest_rk4_step(slider(50.0, 100.0), np.zeros(1), safety=0.8) == pytest.approx(
        0.8 * 2.785293563405282 / abs(lam), rel=1e-9)


@pytest.mark.parametrize("method", ["RK45", "Radau"])
def test_solve_ivp_path_matches_the_exact_oscillator(method):
    """Undamped, unforced x slider: x = x0 cos(w t) + v0/w sin(w t), w = sqrt(k/m); rows at
    the output times; rtol 1e-9 -> errors ~1e-8 over 0.3 s, checked at 1e-6."""
    b = ChainBuilder("s")
    b.add_joint("x", PRISMATIC, (1, 0, 0), stiffness=8.0)
    b.add_body(cuboid(2.0, (0.1, 0.1, 0.1)))
    s = ProgrammedMotion(b.build())
    df = simulate(s, 0.3, [0.1], [0.5], method=method, output_dt=0.05, rtol=1e-9, atol=1e-12)
    t = np.arange(7) * 0.05
    np.testing.assert_allclose(df["t"], t, atol=1e-15)
    np.testing.assert_allclose(df["x"], 0.1 * np.cos(2 * t) + 0.25 * np.sin(2 * t), atol=1e-6)
    np.testing.assert_allclose(df["x_dot"], -0.2 * np.sin(2 * t) + 0.5 * np.cos(2 * t), atol=1e-6)
    assert df.attrs["dt"] is None and df.attrs["rtol"] == 1e-9


def test_default_output_step_is_one_millisecond():
    """simulate(dt = 1e-3) without output_dt records every 1e-3 s: 5 rows over 4 ms."""
    df = simulate(table(False), 0.004, [0.0, 0.0], [0.1, 0.0], dt=1e-3)
    np.testing.assert_allclose(df["t"], [0.0, 0.001, 0.002, 0.003, 0.004], atol=1e-15)


def test_on_manifold_start_and_input_checks():
    """on_manifold places x on the programme at t = 0 (x = f(0) - 0.1, x_dot = f'(0));
    bad t_end, dt, method, shapes and non-finite states are all listed."""
    system = table(True)
    df = simulate(system, 0.01, [0.0, 0.0], [0.0, 0.0], dt=0.005, output_dt=0.005, on_manifold=True)
    f, fd, _ = prog(0.0)
    assert df["x"][0] == pytest.approx(f - EX[0], abs=1e-12)
    assert df["x_dot"][0] == pytest.approx(fd, abs=1e-12)
    assert df.attrs["on_manifold"] is True
    with pytest.raises(ModelError) as err:
        simulate(system, -1.0, [0.0], [np.nan, 0.0], dt=0.0, method="Euler")
    text = str(err.value)
    for word in ("q0 must have shape", "q_dot0 must be finite", "method must be", "t_end must be", "dt must be"):
        assert word in text
    for bad in ({"t_end": np.inf}, {"dt": np.nan}):
        with pytest.raises(ModelError):
            simulate(system, **{"t_end": 0.01, "q0": [0, 0], "q_dot0": [0, 0], **bad})


def test_divergence_and_limits_stop_the_run():
    """A state above 1e6 or non-finite stops the run naming the coordinate; a coordinate
    leaving its stroke raises ConstraintError, on both integrator paths."""
    s = table(False)
    with pytest.raises(SimulationError, match=r"diverged.* y = "):
        simulate(s, 0.01, [0.0, 2e6], [0.0, 0.0], dt=0.005, output_dt=0.005)
    with pytest.raises(SimulationError, match=r"diverged.* x_dot = "):
        simulate(s, 0.01, [0.0, 0.0], [-2e6, 0.0], dt=0.005, output_dt=0.005)
    simulate(s, 0.01, [0.0, 0.0], [0.0, 0.0], dt=0.005, output_dt=0.005)      # 0: fine
    lim = table(False, limits_y=(-0.01, 0.01))
    with pytest.raises(ConstraintError, match="reaches"):
        simulate(lim, 0.1, [0.0, 0.0], [0.0, 1.0], dt=0.005, output_dt=0.005)
    with pytest.raises(ConstraintError, match="reaches"):
        simulate(lim, 0.1, [0.0, 0.0], [0.0, 1.0], method="RK45", output_dt=0.05)

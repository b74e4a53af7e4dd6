"""RK4 stability of a run: the linearised modes, the step limit, the refusal of an unstable
step before the run and the report of an instability met during it.

References are closed forms: a mass m on a spring k has lambda = +-i sqrt(k/m), and RK4 on
the imaginary axis is stable up to h |lambda| = 2 sqrt 2 (Hairer & Wanner, Solving ODE II,
fig. IV.2.1); a mass on a spring k and damper c has lambda = (-c +- sqrt(c^2 - 4 k m)) / 2m.
"""
import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.constraints import CoordinateProgramme
from gpme_core.errors import UnstableStepError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.integrate import simulate
from gpme_core.model import PRISMATIC, ChainBuilder
from gpme_core.stability import STEP_SAFETY, linear_modes, rk4_limit, rk4_step, round_down
from gpme_core.time_functions import Sine

pytestmark = pytest.mark.both_computation_paths

MASS = 2.0
SQRT8 = 2.0 * np.sqrt(2.0)


def two_sliders(k_x, k_y, c_x=0.0, c_y=0.0):
    """Two orthogonal sliders carrying one 2 kg body (no gravity): modes sqrt(k/m) apart."""
    b = ChainBuilder("xy")
    b.add_joint("x", PRISMATIC, (1, 0, 0), stiffness=k_x, damping=c_x)
    b.add_joint("y", PRISMATIC, (0, 1, 0), stiffness=k_y, damping=c_y)
    b.add_body(cuboid(MASS, (0.1, 0.1, 0.1)))
    b.add_frame("E", tf.translation(0.0, 0.0, 0.0))
    return b.build()


@pytest.mark.parametrize("how", ["linearised", "springs"])
def test_stiffest_mode_of_two_sliders(how):
    """k_y = 100 k_x: the y slider's mode (10x the frequency) sets the step and is named."""
    model = two_sliders(8.0, 800.0)
    modes = linear_modes(ProgrammedMotion(model), 0.0, np.zeros(2), np.zeros(2), how=how)
    omega_y = np.sqrt(800.0 / MASS)
    assert modes[0].coordinates == ("y",)
    assert abs(modes[0].eigenvalue.imag) == pytest.approx(omega_y, rel=1e-6)
    assert modes[0].frequency_hz == pytest.approx(omega_y / (2 * np.pi), rel=1e-6)
    assert modes[0].rk4_step == pytest.approx(SQRT8 / omega_y, rel=1e-6)
    assert modes[-1].coordinates == ("x",)
    assert modes[-1].rk4_step == pytest.approx(SQRT8 / np.sqrt(8.0 / MASS), rel=1e-6)


def test_overdamped_mode_limits_on_the_real_axis():
    """c^2 >> 4 k m: the fast real root -c/m (nearly) sets the step at 2.785.../|lambda|."""
    model = two_sliders(50.0, 1.0, c_x=100.0)
    limit, mode = rk4_limit(ProgrammedMotion(model), 0.0, np.zeros(2), np.zeros(2))
    lam = (-100.0 - np.sqrt(100.0 ** 2 - 4 * 50.0 * MASS)) / (2 * MASS)
    assert mode.eigenvalue.real == pytest.approx(lam, rel=1e-6)
    assert "non-oscillating" in mode.describe() and mode.coordinates == ("x",)
    assert limit == pytest.approx(2.785293563405282 / abs(lam), rel=1e-6)


def test_baumgarte_mode_is_named_as_constraint_violation():
    """A programmed x on a soft slider: the only x dynamics left is the Baumgarte error
    equation e'' + 2 alpha e' + beta^2 e = 0; with alpha = 0 its roots are +-i beta."""
    model = two_sliders(1.0, 1.0)
    prog = CoordinateProgramme(Sine(0.0, 0.01, 1.0, 0.0), axis=0, name="P")
    system = ProgrammedMotion(model, [prog], dependent=["x"], baumgarte=(0.0, 300.0))
    limit, mode = rk4_limit(system, 0.0, np.zeros(2), np.zeros(2))
    assert abs(mode.eigenvalue.imag) == pytest.approx(300.0, rel=1e-6)
    assert "constraint violation" in mode.coordinates[0]
    assert limit == pytest.approx(SQRT8 / 300.0, rel=1e-6)


def test_the_one_step_policy_is_half_the_closed_form_limit_at_most_the_cap():
    """gpme_core.stability.rk4_step, the step every run takes where none is given: half of
    the stiffest mode's limit (spring: 2 sqrt 2 / omega; springless and programmed: the
    Baumgarte rate beta, whose roots are +-i beta with alpha = 0), never above the cap."""
    system = ProgrammedMotion(two_sliders(8.0, 800.0))
    half_spring = STEP_SAFETY * SQRT8 / np.sqrt(800.0 / MASS)
    for how in ("springs", "linearised"):
        assert rk4_step(system, np.zeros(2), how=how) == pytest.approx(half_spring, rel=1e-6)
    assert rk4_step(system, np.zeros(2), cap=0.01) == 0.01
    prog = CoordinateProgramme(Sine(0.0, 0.01, 1.0, 0.0), axis=0, name="P")
    free = ProgrammedMotion(two_sliders(0.0, 0.0), [prog], dependent=["x"],
                            baumgarte=(0.0, 300.0))
    assert rk4_step(free, np.zeros(2)) == pytest.approx(STEP_SAFETY * SQRT8 / 300.0, rel=1e-6)


def test_unstable_step_refused_before_the_run_and_stable_one_accepted():
    model = two_sliders(8.0, 800.0)
    system = ProgrammedMotion(model)
    limit = SQRT8 / np.sqrt(800.0 / MASS)
    q0 = np.array([0.01, 0.01])
    with pytest.raises(UnstableStepError, match=r"dt = 0\.2 s is unstable at the start.*"
                                                r"stiffest mode \(3\.183 Hz.*mostly y\); "
                                                r"use dt <= 0\.07 s"):
        simulate(system, 1.0, q0, np.zeros(2), dt=0.2, output_dt=0.2)
    # just below the limit: runs, and the undamped oscillator stays bounded (|R| <= 1)
    dt = 0.99 * limit
    df = simulate(system, 50 * dt, q0, np.zeros(2), dt=dt, output_dt=dt)
    assert np.abs(df["y"]).max() <= 0.01 * (1 + 1e-9)
    # no dt: half the limit, fitted into output_dt (0.1 s / ceil(0.1 / 0.0707) = 0.05 s)
    df = simulate(system, 1.0, q0, np.zeros(2), output_dt=0.1)
    assert df.attrs["dt"] == pytest.approx(0.1 / np.ceil(0.1 / (STEP_SAFETY * limit)),
                                           rel=1e-12)


def test_instability_met_during_the_run_is_reported_as_the_step():
    """Let through (check_step=False), the y mode grows by |R(h lambda)| per step until the
    state leaves its range: the error names the step, not the divergence."""
    model = two_sliders(8.0, 800.0)
    system = ProgrammedMotion(model)
    with pytest.raises(UnstableStepError, match=r"dt = 0\.2 s is unstable at t = .* the last "
                                                r"recorded state.*mostly y.*The failure it "
                                                r"caused: the run diverged"):
        simulate(system, 100.0, [0.01, 0.01], np.zeros(2), dt=0.2, output_dt=0.2,
                 check_step=False)


def test_round_down():
    assert round_down(4.0249e-5) == 4.0e-5
    assert round_down(0.0999) == 0.099
    assert round_down(7.0) == 7.0

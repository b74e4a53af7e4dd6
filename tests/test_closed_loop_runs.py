"""Whole runs of closed loops (a tree closed by two-frame constraints): the compiled loop
equals the Python path, the loop stays closed, and RK4's energy error of the undamped
loop falls at RK4's order (a wrong row or term makes the loop gain or lose energy at any
step size)."""
import numpy as np
import pytest

from gpme_core import dynamics as dy
from gpme_core import fast
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_core.pair_constraints import coincident, weld
from test_pair_constraints import two_arms

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: no compiled loop")

T_END = 0.5        # s
STEPS = (2e-3, 1e-3)


def _energy(model, run):
    """(n_samples,) J: kinetic plus potential energy along a run."""
    names = list(model.coordinate_names)
    return np.array([dy.kinetic_energy(model, row[names].to_numpy(),
                                       row[[f"{c}_dot" for c in names]].to_numpy())
                     + dy.potential_energy(model, row[names].to_numpy())
                     for _, row in run.iterrows()])


@pytest.mark.parametrize("kind", ["coincident", "weld"])
def test_closed_loop_run(kind):
    """Measured (0.5 s, dt = 2e-3 and 1e-3 s): compiled and Python runs equal to 4e-16;
    energy errors 1.3e-7 -> 7.9e-9 J (coincident), 2.6e-8 -> 1.6e-9 J (weld), ratio 16 =
    2^4; the loop's largest residual 1.0e-8 m at 2e-3 s.  Gates: equal to 1e-12 (round-off
    of 500 steps), energy-error ratio above 8 (order above 3), residual below 1e-6 m on
    this 1 m loop (Baumgarte holds RK4's O(dt^4) drift: a wrong row opens the loop by
    its own error, orders of magnitude more)."""
    model = two_arms()
    model = model.with_changes(joint_changes={j.name: {"stiffness": 0.0, "damping": 0.0}
                                              for j in model.joints})
    specs = {"coincident": coincident("tool_a", "tool_b"),
             "weld": weld("tool_a", "tool_b")}[kind]
    q0 = np.full(model.n_coordinates, 0.05)
    system = ProgrammedMotion(model, specs).with_pivoted_dependent(0.0, q0)
    q, q_dot = system.consistent_state(0.0, q0, np.linspace(1.0, -1.0, model.n_coordinates))
    names = list(model.coordinate_names)
    swings = []
    for dt in STEPS:
        runs = {c: simulate(system, T_END, q, q_dot, dt=dt, output_dt=0.05, compiled=c)
                for c in (True, False)}
        assert runs[True].attrs["compiled"] and not runs[False].attrs["compiled"]
        np.testing.assert_allclose(runs[True][names].to_numpy(),
                                   runs[False][names].to_numpy(), rtol=0, atol=1e-12)
        residual = np.abs(runs[True][list(system.constraint_names)].to_numpy()).max()
        assert residual < 1e-6, f"loop opens by {residual:.3g} at dt = {dt} s"
        energy = _energy(model, runs[True])
        swings.append(energy.max() - energy.min())
    assert swings[0] / swings[1] > 8.0, f"energy errors {swings} J do not fall at order 4"


def test_closed_loop_radau_converges_to_the_rk4_motion():
    """RadauIIA (compiled loop) on the welded two arms (a tree closed by six rows): at
    dt = 2e-3 s it is within its own halving difference (dt = 4e-3 s against 2e-3 s) of
    RK4 at 2.5e-4 s, whose error is far smaller; the loop stays closed.  Measured: 1.9e-13
    rad from RK4, halving difference 3.2e-12, residual 1.6e-13 m."""
    model = two_arms()
    q0 = np.full(model.n_coordinates, 0.05)
    system = ProgrammedMotion(model, weld("tool_a", "tool_b")).with_pivoted_dependent(0.0, q0)
    q, q_dot = system.consistent_state(0.0, q0, np.linspace(1.0, -1.0, model.n_coordinates))
    names = list(model.coordinate_names)
    reference = simulate(system, 0.2, q, q_dot, dt=2.5e-4, output_dt=0.02)[names].to_numpy()
    radau = {dt: simulate(system, 0.2, q, q_dot, dt=dt, method="RadauIIA", output_dt=0.02)
             for dt in (4e-3, 2e-3)}
    assert radau[2e-3].attrs["compiled"]
    fine, coarse = radau[2e-3][names].to_numpy(), radau[4e-3][names].to_numpy()
    assert np.abs(fine - reference).max() <= np.abs(coarse - fine).max()
    assert np.abs(radau[2e-3][list(system.constraint_names)].to_numpy()).max() < 1e-9

"""crosscheck.convergence: the step-halving error bound must hold at every compared time;
runs that converge slowly at a few samples (a start transient) are refined, within a
budget, and a run set that does not converge is a failed order row, never a pass.

Synthetic runs with known errors: x(t; h) = sin 3t + C h^2 t (order 2, the smooth part)
plus a start transient a h^3 / (h + H0)^2.6 (t/tau) e^(1 - t/tau), which converges at
order 0.4 while h >> H0 and at order 3 once h << H0 (a pre-asymptotic start, as
generalized-alpha's first steps on an index-3 DAE)."""
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from crosscheck import halving_gates
from crosscheck.convergence import (FINEST, RefinementBudget, convergence, local_point,
                                    refine)

T = np.linspace(0.0, 1.0, 101)       # s, compared samples every 0.01 s
H = 1e-3                             # s, first coarsest step
H0 = 2e-5                            # s, below which the transient is asymptotic
TAU = 0.01                           # s, the transient's time constant
FLOOR = {"x": 1e-15}


def exact(t):
    return np.sin(3.0 * t)


def run(h, transient=0.0, offset=0.0):
    x = exact(T) + 50.0 * h ** 2 * T + offset
    x = x + transient * h ** 3 / (h + H0) ** 2.6 * (T / TAU) * np.exp(1.0 - T / TAU)
    df = pd.DataFrame({"t": T, "x": x})
    df.attrs["wall_time_s"] = 0.01
    return df


def three(transient=0.0, h=H):
    return [run(h / k, transient) for k in (1, 2, 4)]


def test_asymptotic_runs_pass_everywhere():
    conv = convergence(three(), ["x"], FLOOR, 2.0, FINEST)
    assert conv.converged and conv.resolved
    assert conv.order == pytest.approx(2.0, abs=1e-6)
    assert conv.worst.ratio <= 1.0


def test_a_start_transient_passes_run_wide_but_fails_at_its_time():
    runs = three(transient=5e-4)
    conv = convergence(runs, ["x"], FLOOR, 2.0, FINEST)
    # the run-wide order alone (the guard before) lets it through
    assert conv.band_ok and conv.order == pytest.approx(2.0, abs=0.05)
    assert not conv.local_ok and not conv.converged
    assert conv.worst.time == pytest.approx(0.01)
    assert conv.worst.order < conv.worst.needed
    # and rightly: the finest run's true error there exceeds the run-wide bound
    bound = np.abs(runs[1]["x"] - runs[2]["x"]).max() / (2.0 ** 1 - 1.0)
    true = np.abs(runs[2]["x"] - exact(T))
    assert true[1] > bound


def test_refinement_reaches_the_asymptotic_regime_and_the_bound_then_holds():
    runs, h, conv, record = refine(lambda step: run(step, 5e-4), H, ["x"], lambda r: FLOOR,
                                   2.0, FINEST, RefinementBudget(8, 60.0))
    assert record.converged and conv.converged and record.halvings >= 1
    assert h == pytest.approx(H / 2 ** record.halvings)
    assert len(record.reasons) == record.halvings and "t = 0.01" in record.reasons[0]
    bound = np.abs(runs[1]["x"] - runs[2]["x"]).max() / (2.0 ** 1 - 1.0)
    true = np.abs(runs[2]["x"] - exact(T))
    assert np.all(true <= bound)


def test_the_budget_runs_out_and_says_what_to_do():
    runs, h, conv, record = refine(lambda step: run(step, 5e-4), H, ["x"], lambda r: FLOOR,
                                   2.0, FINEST, RefinementBudget(1, 60.0))
    assert not record.converged and not conv.converged and record.halvings == 1
    assert "1 halvings are spent" in record.stopped_by
    assert "[[engine_step]]" in record.remedy("exudyn", "[run] quick_t_end")
    # and the wall-time part of the budget: the next run would take 2 x 0.01 s > 0.015 s
    *_, slow = refine(lambda step: run(step, 5e-4), H, ["x"], lambda r: FLOOR, 2.0, FINEST,
                      RefinementBudget(8, 0.015))
    assert not slow.converged and slow.halvings == 0 and "projected" in slow.stopped_by


def rk4_like(h):
    """gpme's side: order-4 error 5e3 h^4 t."""
    return pd.DataFrame({"t": T, "x": exact(T) + 5e3 * h ** 4 * T})


def _halved(engine, order, runs, h=H):
    return halving_gates.HalvedRuns(engine, "scheme", order, tuple(runs), h)


SCENARIO = SimpleNamespace(name="synthetic", model=None, tolerance=lambda e, q: None)


def test_a_not_converged_engine_fails_once_and_its_columns_are_not_judged():
    gpme = _halved("gpme", 4.0, [rk4_like(H / k) for k in (1, 2, 4)])
    slow = _halved("exudyn", 2.0, three(transient=5e-4))
    rows = halving_gates.run_rows("exudyn", SCENARIO, gpme, slow, ["x"], "run", "case")
    column, gpme_order, exu_order = rows
    assert column["status"] == "info" and "not judged" in column["reason"]
    assert gpme_order["engine"] == "gpme" and gpme_order["status"] == "pass"
    assert exu_order["engine"] == "exudyn" and exu_order["status"] == "fail"
    assert "t=0.01" in exu_order["entry"]


def test_refinement_does_not_hide_a_real_disagreement():
    """After refinement the gates are tighter, so an offset of 1e-5 (a fault of the
    equations, the same at every step) fails, in the column row, judged."""
    gpme = _halved("gpme", 4.0, [rk4_like(H / k) for k in (1, 2, 4)])
    runs, h, _, record = refine(lambda step: run(step, 5e-4, offset=1e-5), H, ["x"],
                                lambda r: FLOOR, 2.0, FINEST, RefinementBudget(8, 60.0))
    other = halving_gates.HalvedRuns("exudyn", "scheme", 2.0, runs, h, refinement=record)
    rows = halving_gates.run_rows("exudyn", SCENARIO, gpme, other, ["x"], "run", "case")
    assert rows[0]["status"] == "fail" and rows[2]["status"] == "pass"


def test_a_zero_crossing_of_the_error_is_not_a_failure():
    """A smooth error C(t) h^p whose C changes sign: at the crossing single-sample ratios
    are meaningless; the window keeps the verdict of the neighbours."""
    def crossing(h):
        df = pd.DataFrame({"t": T, "x": exact(T) + 30.0 * h ** 2 * np.cos(7.0 * T)
                           + 1e3 * h ** 3 * np.sin(5.0 * T)})
        return df
    conv = convergence([crossing(H / k) for k in (1, 2, 4)], ["x"], FLOOR, 2.0, FINEST)
    assert conv.converged, conv.describe()


def test_local_point_refuses_an_unknown_comparison():
    with pytest.raises(ValueError, match="compared"):
        local_point("x", T, T, T, 2.0, 0.0, "middle")


def test_a_held_constraints_floor_does_not_grow_with_the_step_count():
    """Phi is held (Baumgarte pulls a rounding back within 1/r), not integrated: its floor
    is the same for a run of 1e3 and of 1e6 steps once both are longer than 1/(r h)."""
    from crosscheck.run_gates import baumgarte_memory_steps, phi_floor, phi_term_scale
    h, rates = 1e-4, (20.0, 20.0)
    assert baumgarte_memory_steps(h, rates) == pytest.approx(500.0)
    assert phi_floor(0.5, 1_000, h, rates) == phi_floor(0.5, 1_000_000, h, rates)
    assert phi_floor(0.5, 100, h, rates) < phi_floor(0.5, 1_000, h, rates)
    # the memory is a time, 1/r = 50 ms: a finer step rounds more often within it
    assert baumgarte_memory_steps(h / 2, rates) == pytest.approx(2 * 500.0)
    # without Baumgarte nothing pulls Phi back: linear in the steps, as the coordinates
    assert phi_floor(0.5, 10_000, h) > 10 * phi_floor(0.5, 1_000, h, rates)
    # the size of Phi's terms does not vanish at a zero posture (a tool 0.3 m up at q = 0)
    a = np.array([[0.0, 0.3, 0.45]])        # m/rad: lever arms of the joints
    assert phi_term_scale(a, np.zeros(3))[0] == pytest.approx(0.75)


def _noisy(h, amplitude, seed):
    """A run whose discretisation error (order 2) lives in t <= 0.5 s and which carries
    round-off-like noise that grows as the step shrinks (amplitude * H / h, as eps times
    the step count) at t > 0.5 s, where nothing else differs between the runs."""
    rng = np.random.default_rng(seed)
    late = T > 0.5
    x = exact(T) + 50.0 * h ** 2 * T * ~late
    x = x + amplitude * (H / h) * rng.standard_normal(len(T)) * late
    df = pd.DataFrame({"t": T, "x": x})
    df.attrs["wall_time_s"] = 0.01
    return df


def test_noise_below_the_bound_in_a_converging_column_passes():
    """Differences that grow as h shrinks (r < 1) at some samples, while the column
    converges at order 2 run-wide: noise, judged by its size (the case of Exudyn's
    flexible crane at 250,000 steps), not an infinite error."""
    runs = [_noisy(H / k, 2e-8, seed=k) for k in (1, 2, 4)]
    conv = convergence(runs, ["x"], FLOOR, 2.0, FINEST)
    assert conv.band_ok and conv.converged, conv.describe()
    # the noisy samples are judged (resolved above the floor) and do not shrink
    late = T > 0.5
    d1, d2 = (np.abs(runs[k]["x"] - runs[k + 1]["x"]).to_numpy()[late] for k in (0, 1))
    assert np.median(d1 / d2) < 1.0 and d2.min() > 10 * FLOOR["x"]
    # without the noise rule they would read as an infinite error
    point = local_point("x", T, np.abs(runs[0]["x"] - runs[1]["x"]).to_numpy(),
                        np.abs(runs[1]["x"] - runs[2]["x"]).to_numpy(), 2.0, FLOOR["x"],
                        FINEST, converges=False)
    assert point.ratio == np.inf and point.time > 0.5


def test_noise_above_the_bound_still_fails():
    """The same noise 1000 x larger: above what the run-wide bound allows, a failure."""
    runs = [_noisy(H / k, 2e-6, seed=k) for k in (1, 2, 4)]
    conv = convergence(runs, ["x"], FLOOR, 2.0, FINEST)
    assert not conv.converged
    assert conv.worst.time > 0.5 and conv.worst.ratio > 1.0


def test_a_column_that_does_not_converge_gives_its_non_shrinking_samples_no_credit():
    """A column with no order (differences the same at every step: an error of order 0)
    keeps the infinite extrapolated error of a sample that does not shrink."""
    d = np.full(len(T), 1e-6)
    point = local_point("x", T, d, d, 2.0, 1e-15, FINEST, converges=False)
    assert point.ratio == np.inf
    assert local_point("x", T, d, d, 2.0, 1e-15, FINEST, converges=True).ratio <= 1.0


def _shifted_crossing(h, shift=40.0, omega=30.0):
    """An order-2 error whose zero crossings move with the step (an h^3 phase term:
    sin(omega (t - shift h))), so x_h - x_h/2 and x_h/2 - x_h/4 vanish ~2-3 samples apart."""
    return pd.DataFrame({"t": T, "x": exact(T) + 1e3 * h ** 2 * np.sin(omega * (T - shift * h))})


def test_a_crossing_that_moves_with_the_step_is_not_a_failure(monkeypatch):
    """The case of Exudyn's flexible crane (z4 at 6.75 s): near a crossing the +-1 sample
    window sees D1 ~ D2; the window spanning the crossings sees the converging error, and
    the bound does hold there (the true error of the finest run)."""
    from crosscheck import convergence as conv_module
    runs = [_shifted_crossing(H / k) for k in (1, 2, 4)]
    conv = convergence(runs, ["x"], FLOOR, 2.0, FINEST)
    assert conv.converged, conv.describe()
    bound = np.abs(runs[1]["x"] - runs[2]["x"]).max() / (2.0 ** 1 - 1.0)
    assert np.all(np.abs(runs[2]["x"] - exact(T)) <= bound)
    monkeypatch.setattr(conv_module, "CROSSING_WINDOW", 1)
    assert not convergence(runs, ["x"], FLOOR, 2.0, FINEST).converged


def test_a_solver_failure_at_the_first_step_halves_it():
    """An engine whose solver gives up at a step too coarse for the model (SimulationError)
    is run again at half the step, within the budget, and then converges; past the budget
    the failure is raised with the halvings tried."""
    from gpme_core.errors import SimulationError

    def fails_above(limit):
        def run_at(step):
            if step > limit:
                raise SimulationError(f"Newton failed at h = {step:g} s")
            return run(step)
        return run_at

    runs, h, conv, record = refine(fails_above(H / 3.0), H, ["x"], lambda r: FLOOR, 2.0,
                                   FINEST, RefinementBudget(8, 60.0))
    assert conv.converged and h == pytest.approx(H / 4.0)
    assert len(record.reasons) == 2 and "a run failed" in record.reasons[0]
    with pytest.raises(SimulationError, match="after 2 halvings of the first step"):
        refine(fails_above(H / 100.0), H, ["x"], lambda r: FLOOR, 2.0, FINEST,
               RefinementBudget(2, 60.0))

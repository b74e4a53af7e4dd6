"""crosscheck.halving_gates: gates of two engines with different integrators, on synthetic
runs whose errors are known in closed form (x(t; h) = x*(t) + C h^p t)."""
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from crosscheck.halving_gates import HalvedRuns, order_row, run_rows

T = np.linspace(0.0, 1.0, 11)           # s, output times
H = 1e-2                                 # s, coarsest step


def exact(t):
    return np.sin(3.0 * t)


def runs(order, c, offset=0.0, noise=0.0):
    """Three runs at H, H/2, H/4 with global error c h^order t (+ an offset, + seeded noise)."""
    rng = np.random.default_rng(7)
    out = []
    for k in range(3):
        h = H / 2 ** k
        x = exact(T) + c * h ** order * T + offset + noise * rng.standard_normal(len(T))
        out.append(pd.DataFrame({"t": T, "x": x}))
    return tuple(out)


SCENARIO = SimpleNamespace(name="synthetic", model=None, tolerance=lambda engine, q: None)


def test_error_estimate_bounds_the_true_error_across_the_accepted_orders():
    # true order anywhere in [p - 1, p + 1] (what the order row accepts): the estimate at
    # the lowest accepted order p - 1 is >= the finest run's true error c (h/4)^p_true t_max
    for p_true in (1.2, 2.0, 2.9):
        r = HalvedRuns("exudyn", "generalized-alpha", 2.0, runs(p_true, 5.0), H)
        true = 5.0 * (H / 4) ** p_true * T[-1]
        assert r.error("x") >= true * (1 - 1e-9)
        assert r.error("x") <= 8.0 * true          # and not absurdly loose


def test_agreeing_engines_pass_and_a_planted_discrepancy_fails():
    gpme = HalvedRuns("gpme", "RK4", 4.0, runs(4.0, 50.0), H)
    good = HalvedRuns("exudyn", "generalized-alpha", 2.0, runs(2.0, -3.0), H)
    rows = run_rows("exudyn", SCENARIO, gpme, good, ["x"], "run", "case")
    assert [r["status"] for r in rows] == ["pass", "pass", "pass"]
    # an offset 5x the gate: not explained by either integrator
    gate = rows[0]["tol_abs"]
    bad = HalvedRuns("exudyn", "generalized-alpha", 2.0, runs(2.0, -3.0, offset=5 * gate), H)
    assert run_rows("exudyn", SCENARIO, gpme, bad, ["x"], "run", "case")[0]["status"] == "fail"


def test_order_row_fails_outside_the_asymptotic_regime():
    # nominally order 4 but converging at order 2: the error estimate would be wrong
    wrong = HalvedRuns("drake", "RK5", 5.0, runs(2.0, 1.0), H)
    row = order_row("drake", "synthetic", wrong, ["x"], "free run", "case")
    assert row["status"] == "fail"
    right = HalvedRuns("drake", "RK5", 5.0, runs(5.0, 1e4), H)
    assert order_row("drake", "synthetic", right, ["x"], "free run", "case")["status"] == "pass"


def test_unresolved_order_is_information_only():
    flat = HalvedRuns("drake", "RK5", 5.0, runs(5.0, 0.0), H)     # no truncation error at all
    row = order_row("drake", "synthetic", flat, ["x"], "free run", "case")
    assert row["status"] == "info"


def test_bad_inputs_are_refused_with_the_value():
    with pytest.raises(ValueError, match="order 1.0"):
        HalvedRuns("x", "Euler", 1.0, runs(1.0, 1.0), H)
    with pytest.raises(ValueError, match="3 runs"):
        HalvedRuns("x", "RK4", 4.0, runs(4.0, 1.0)[:2], H)
    shifted = list(runs(4.0, 1.0))
    shifted[2] = shifted[2].assign(t=shifted[2]["t"] + 1e-3)
    with pytest.raises(ValueError, match="other output times"):
        HalvedRuns("x", "RK4", 4.0, tuple(shifted), H)
    with pytest.raises(ValueError, match="positive step"):
        HalvedRuns("x", "RK4", 4.0, runs(4.0, 1.0), -1.0)


def test_a_coordinate_left_at_zero_is_gated_by_the_round_off_of_the_whole_state():
    """A coordinate the motion leaves at ~0 (an RFEM torsion of a planar motion) differs
    between engines by the round-off of the solve that mixes it with the large ones:
    eps sqrt(N) max|q| (here ~4e-15 rad), not eps N |q_torsion| (~1e-31)."""
    names = ["big", "torsion"]
    model = SimpleNamespace(coordinate_names=names, is_revolute=[True, True], index=names.index)

    def engine(name, order, c, noise_seed):
        rng = np.random.default_rng(noise_seed)
        out = []
        for k in range(3):
            big = exact(T) + c * (H / 2 ** k) ** order * T
            out.append(pd.DataFrame({"t": T, "big": big, "torsion": 1e-18 * rng.standard_normal(len(T)),
                                     "big_dot": 3 * np.cos(3 * T), "torsion_dot": 0 * T}))
        return HalvedRuns(name, "scheme", order, tuple(out), H)

    gpme, other = engine("gpme", 4.0, 50.0, 1), engine("drake", 5.0, 1e3, 2)
    scenario = SimpleNamespace(name="synthetic", model=model, tolerance=lambda e, q: None)
    rows = run_rows("drake", scenario, gpme, other, ["torsion"], "free run", "case")
    assert rows[0]["status"] == "pass"
    assert 1e-16 < rows[0]["tol_abs"] < 1e-13
    # without the model's coordinates the floor is the column's own round-off only: the
    # round-off noise then counts as resolved truncation error that does not converge, so
    # an order row fails (the estimate is not the error) and the column is not judged
    plain = SimpleNamespace(name="synthetic", model=None, tolerance=lambda e, q: None)
    rows = run_rows("drake", plain, gpme, other, ["torsion"], "free run", "case")
    assert rows[0]["status"] == "info" and "not judged" in rows[0]["reason"]
    assert any(r["status"] == "fail" for r in rows[1:])

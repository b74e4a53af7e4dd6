"""The cost estimate of a run: its counts against the run itself (RK4 steps, rows, columns,
CSV size); its wall time is measured (docs/runs.md), never asserted."""
import numpy as np
import pytest

from gpme_core.integrate import estimate_simulation, history_columns, simulate
from gpme_core.run_cost import CSV_BYTES_PER_VALUE, estimate_run, time_evaluation
from gpme_examples.crane import CraneParameters, crane_system, initial_state


@pytest.mark.parametrize("n_rfe", [0, 2])
def test_counts_match_the_run(n_rfe):
    params = CraneParameters()
    system = crane_system(n_rfe, params)
    q0, q_dot0 = initial_state(system.model, params)
    dt = 1e-4 if n_rfe == 0 else 4e-5
    cost = estimate_simulation(system, 0.05, q0, q_dot0, dt=dt, output_dt=1e-3)
    df = simulate(system, 0.05, q0, q_dot0, dt=dt, output_dt=1e-3)
    assert cost.steps * 4 == df.attrs["rhs_evaluations"] and cost.exact
    assert (cost.rows, cost.columns) == df.shape == (51, history_columns(system))
    csv = len(df.to_csv(index=False).encode())
    # 25 bytes per value bounds '%.17g' (at most 24 characters and a separator) from above
    assert csv <= cost.csv_bytes and csv > cost.csv_bytes / 3
    # (its wall time against the run's is measured, not asserted: docs/runs.md)
    assert "RK4: 500 steps" in cost.describe() or "RK4: 1,250 steps" in cost.describe()


def test_adaptive_methods_are_lower_bounds_or_unknown():
    per_eval = 1e-4
    rk45 = estimate_run("RK45", 1.0, 1e-2, 4, 25, per_eval, stable_step=1e-3)
    assert rk45.steps == 1000 and rk45.evaluations == 6000 and not rk45.exact
    assert rk45.describe().startswith("at least")
    radau = estimate_run("Radau", 1.0, 1e-2, 4, 25, per_eval)
    assert radau.wall_s is None and "not known before the run" in radau.describe()
    assert radau.rows == 101 and radau.csv_bytes == 101 * 25 * CSV_BYTES_PER_VALUE


def test_time_evaluation_is_positive_and_finite():
    params = CraneParameters()
    system = crane_system(0, params)
    system = system.with_dependent(system.pivoted_dependent(0.0, *initial_state(system.model,
                                                                                params)))
    first, per_eval = time_evaluation(system, *initial_state(system.model, params))
    assert np.isfinite(per_eval) and 0 < per_eval < 1.0 and first > 0


def test_simulate_returns_a_history_and_estimate_simulation_a_cost():
    """One return type per function (issue 25): simulate has no estimate flag, and
    estimate_simulation takes simulate's settings and refuses others."""
    system = crane_system(0)
    q0, q_dot0 = initial_state(system.model)
    with pytest.raises(TypeError):
        simulate(system, 0.01, q0, q_dot0, estimate_only=True)
    with pytest.raises(TypeError, match="unknown run settings"):
        estimate_simulation(system, 0.01, q0, q_dot0, estimate_only=True)
    cost = estimate_simulation(system, 0.01, q0, q_dot0, dt=1e-4)
    assert cost.steps == 100

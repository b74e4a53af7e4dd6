"""The engine's run as values (issue 25): RunSettings in, a frozen RunResult out, and
simulate's DataFrame exactly its to_frame()."""
import dataclasses

import numpy as np
import pandas as pd
import pytest

from gpme_core.errors import ModelError
from gpme_core.integrate import estimate_simulation, run, simulate
from gpme_core.run_result import RunResult, RunSettings
from gpme_examples.crane import crane_system, initial_state


@pytest.fixture(scope="module")
def crane_run():
    system = crane_system(1)
    q0, q_dot0 = initial_state(system.model)
    settings = RunSettings(dt=5e-5, output_dt=1e-3)
    return system, q0, q_dot0, settings, run(system, 0.01, q0, q_dot0, settings)


def test_the_result_is_frozen_and_its_histories_read_only(crane_run):
    result = crane_run[-1]
    assert isinstance(result, RunResult)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.dt = 1.0
    with pytest.raises(ValueError):
        result["psi3"][0] = 0.0            # read-only arrays
    with pytest.raises(TypeError):
        result.columns["psi3"] = np.zeros(3)
    assert isinstance(result.events, tuple)
    assert result.t[0] == 0.0 and result.t[-1] == pytest.approx(0.01)
    assert result.method == "RK4" and result.dt == pytest.approx(5e-5)
    assert result.dependent == ("psi3", "z4") and isinstance(result.dependent, tuple)


def test_simulate_is_the_frame_of_run(crane_run):
    """Same settings, same history bit for bit (the run is deterministic), and the
    metadata in attrs as fields of the result."""
    system, q0, q_dot0, settings, result = crane_run
    df = simulate(system, 0.01, q0, q_dot0, dt=5e-5, output_dt=1e-3)
    frame = result.to_frame()
    assert list(df.columns) == list(result.columns) == list(frame.columns)
    pd.testing.assert_frame_equal(df, frame, check_exact=True)
    attrs = dict(df.attrs)
    assert attrs.pop("wall_time_s") > 0
    expected = result.metadata()
    expected.pop("wall_time_s")
    assert attrs == expected
    assert frame.attrs["dependent"] == ["psi3", "z4"]
    frame.loc[0, "psi3"] = 99.0               # the frame is a copy
    assert result["psi3"][0] != 99.0


def test_settings_are_named_checked_and_shared_with_the_estimate(crane_run):
    system, q0, q_dot0, settings, _ = crane_run
    assert RunSettings.names()[:3] == ("dt", "method", "output_dt")
    with pytest.raises(TypeError, match=r"unknown run settings \['step'\].*'dt'"):
        settings.with_changes(step=1e-4)
    with pytest.raises(ModelError, match="RunSettings"):
        run(system, 0.01, q0, q_dot0, {"dt": 1e-4})
    cost = estimate_simulation(system, 0.01, q0, q_dot0, settings)
    assert cost.steps == 200
    assert estimate_simulation(system, 0.01, q0, q_dot0, settings, dt=1e-4).steps == 100

"""Smoke test of the benchmark script: it runs, writes its tables, and the three engines
compute the same constrained accelerations it times (speed itself is never asserted)."""
import pandas as pd

from benchmarks.bench import main


def test_quick_benchmark_writes_tables(tmp_path, capsys):
    assert main(["--quick", "--out", str(tmp_path)]) == 0
    evals = pd.read_csv(tmp_path / "evaluation_costs.csv")
    runs = pd.read_csv(tmp_path / "run_costs.csv")
    assert list(evals.n_rfe) == [0, 1, 5]
    assert (evals[["gpme_us", "pinocchio_us", "mujoco_us"]] > 0).all().all()
    # same q_ddot from gpme and Pinocchio at the timed state (round-off, cond(M) ~ 1e7 at n = 5)
    assert (evals["max |qdd gpme - qdd pinocchio|"] < 1e-6).all()
    assert {"gpme", "pinocchio", "mujoco"} <= set(runs.engine)
    assert (tmp_path / "evaluation_costs.png").stat().st_size > 0
    assert "log-log slope" in capsys.readouterr().out

"""Smoke test of the benchmark script (--quick: n_rfe up to 5, 0.2 s runs): it runs, writes
its tables, and the accuracies it prints meet bounds derived from round-off and integrator
order.  Speed is never asserted."""
import re

import numpy as np
import pandas as pd
import pytest

from benchmarks.bench import QUICK, RADAU_DTS, main
from gpme_examples.crane import CraneParameters

EPS = np.finfo(float).eps
# rad: the largest |q| of the crane runs, psi3's range (CraneParameters.arm_pitch_range);
# z1, psi2, z4 and the arm's elastic coordinates stay far smaller
MAX_Q = max(abs(v) for v in CraneParameters().arm_pitch_range)
RADAU_DT, RADAU_COARSE_DT = 1e-3, 2e-3       # s, the RadauIIA steps
assert {RADAU_DT, RADAU_COARSE_DT} <= set(RADAU_DTS)
AGREEMENT = ["compiled-pinocchio", "python-pinocchio", "sympy compiled-sympy pinocchio",
             "sympy-builtin compiled", "sympy-builtin python"]


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    assert main(["--quick", "--out", str(out)]) == 0
    return {name: pd.read_csv(out / f"{name}.csv") for name in
            ("evaluation_costs", "evaluation_agreement", "run_costs", "sweep_throughput")
            } | {"png": out / "evaluation_costs.png"}


def _row(runs, case, role):
    (row,) = runs[(runs.case == case) & (runs.role == role)].itertuples(index=False)
    return row._asdict()


def test_tables_written(quick):
    evals = quick["evaluation_costs"]
    assert list(evals.n_rfe) == list(QUICK.n_values)
    timed = [c for c in evals.columns if c.endswith("_us")]
    assert len(timed) == 7 and (evals[timed] > 0).all().all()
    runs = quick["run_costs"]
    assert {"gpme", "pinocchio", "mujoco"} <= set(runs.engine)
    assert len(quick["sweep_throughput"]) == len(QUICK.sweep_amplitudes)
    assert quick["png"].stat().st_size > 0
    # the "before" ran the Python loop and the "after" runs the compiled loops
    assert not runs[runs.role == "python rk4"].compiled.astype(bool).any()
    fast_roles = ["compiled rk4", *(f"radau {dt:g}" for dt in RADAU_DTS)]
    for case in ("rigid", f"flexible n_rfe={QUICK.flex_n}"):
        assert set(fast_roles) <= set(runs[runs.case == case].role)
    assert runs[runs.role.isin(fast_roles)].compiled.astype(bool).all()


def test_evaluations_agree_to_round_off(quick):
    """gpme compiled, gpme Python and Pinocchio compute the same q_ddot, and the SymPy form
    of the constraints the same as the built-in: a backward-stable solve of M has a relative
    error up to eps cond(M) (cond of Pinocchio's CRBA matrix, an independent value)."""
    agree = quick["evaluation_agreement"]
    bound = agree["eps cond(M) max|qdd|"]
    assert (bound > 0).all()
    for col in AGREEMENT:
        assert (agree[col] <= bound).all(), (col, agree[[col]].T, bound)


def _rk4_steps(method, t_end):
    (dt,) = re.findall(r"dt=([0-9.e+-]+)", method)
    return round(t_end / float(dt))


@pytest.mark.parametrize("case,n_rfe", [("rigid", 0), (f"flexible n_rfe={QUICK.flex_n}",
                                                        QUICK.flex_n)])
def test_same_scheme_runs_agree_to_round_off(quick, case, n_rfe):
    """Compiled RK4 and Pinocchio's RK4 repeat the Python RK4 run (same scheme, same step):
    their q_ddot differ by at most delta = eps cond(M) max|q_ddot| (table (a)), which moves q
    by at most delta T^2 / 2 over T, plus the rounding of q at each of the N steps
    (N eps max|q|)."""
    runs = quick["run_costs"]
    agree = quick["evaluation_agreement"].set_index("n_rfe")
    before = _row(runs, case, "python rk4")
    t_end = QUICK.t_end
    bound = (agree.loc[n_rfe, "eps cond(M) max|qdd|"] * t_end ** 2 / 2
             + _rk4_steps(before["method"], t_end) * EPS * MAX_Q)
    for role in ("compiled rk4", "pinocchio"):
        assert _row(runs, case, role)["q_vs_python_rk4"] <= bound, (role, bound)


def test_radau_converges_and_reference_is_sound(quick):
    """On the flexible crane (in 0.2 s the rigid one's errors are round-off):
    * RadauIIA's error falls at least as dt^3 (its stage order, kept on stiff problems; the
      order is 5 on smooth ones) from dt = 1e-3 s to the reference check at 5e-4 s;
    * the reference agrees with the independent Python path (RK4) to within half of the
      error printed for RadauIIA at 1e-3 s, so that error is a measurement of RadauIIA's
      error (to within a factor 2), not of the reference's."""
    runs = quick["run_costs"]
    case = f"flexible n_rfe={QUICK.flex_n}"
    radau = _row(runs, case, f"radau {RADAU_DT:g}")
    check = _row(runs, case, "reference check")
    ratio = RADAU_DT / float(re.findall(r"dt=([0-9.e+-]+)", check["method"])[0])
    assert radau["q_error"] >= ratio ** 3 * check["q_error"] > 0
    assert _row(runs, case, "python rk4")["q_error"] <= radau["q_error"] / 2


def test_sweep_after_matches_before(quick):
    """Each sweep point's RadauIIA run (dt = 1e-3 s) is within the error RadauIIA has at twice
    that step on the same crane in (b): at 1e-3 s it is >= 2^3 times smaller (stage order 3,
    checked above), which covers the change of the error with the programme amplitude
    (at most 10 % here) and the Python RK4's own error (below the reference's, checked
    above)."""
    sweep = quick["sweep_throughput"]
    coarse = _row(quick["run_costs"], f"flexible n_rfe={QUICK.flex_n}",
                  f"radau {RADAU_COARSE_DT:g}")["q_error"]
    assert (sweep["q_after-before"] <= coarse).all(), (sweep["q_after-before"], coarse)
    assert (sweep[["before_cpu_s", "after_cpu_s"]] > 0).all().all()

"""Published closed-loop benchmarks against gpme: prints the table of issue 26.

    python -m benchmarks.closed_loops

Andrews' squeezing mechanism (Test Set for IVP Solvers, problem "andrews"): gpme's RK4 at
dt and dt/2 (its error estimated by halving), gpme with scipy's DOP853, and the test set's
own equations solved independently (benchmarks.andrews_testset), each against the
published reference solution at t = 0.03 s (positions rad, rates rad/s) in the test set's
mixed error |x - ref| / (1 + |ref|).  docs/benchmarks-closed-loops.md discusses it.
"""
import time

import numpy as np

from benchmarks.andrews_testset import solve
from gpme_core.integrate import simulate
from gpme_examples import andrews as A


def _final(system, **kw):
    model = system.model
    names = list(model.coordinate_names)
    idx = [model.index(c) for c in A.TEST_SET_ORDER]
    q0, q_dot0 = A.start_state(model)
    last = simulate(system, A.T_END, q0, q_dot0, output_dt=A.T_END, **kw).iloc[-1]
    q = last[names].to_numpy(float)[idx]
    q_dot = last[[f"{c}_dot" for c in names]].to_numpy(float)[idx]
    return np.concatenate([q, q_dot])


def main():
    system = A.andrews_system()
    ref = np.concatenate([A.REFERENCE_Q, A.REFERENCE_Q_DOT])
    rows = []
    for label, kw in (("gpme RK4 dt = 4e-6 s", dict(dt=4e-6)),
                      ("gpme RK4 dt = 2e-6 s", dict(dt=2e-6)),
                      ("gpme DOP853 rtol 1e-13", dict(method="DOP853", rtol=1e-13, atol=1e-14))):
        t0 = time.perf_counter()
        rows.append((label, _final(system, **kw), time.perf_counter() - t0))
    t0 = time.perf_counter()
    rows.append(("test set equations, scipy DOP853 (no gpme)", np.concatenate(solve()),
                 time.perf_counter() - t0))
    print("Andrews' squeezing mechanism at t = 0.03 s, against the published reference "
          "(PSIDE, rtol = atol = 1e-14)")
    print(f"{'solution':45s} {'max |dq| rad':>13s} {'max |dq_dot|':>13s} "
          f"{'mixed error':>12s} {'wall s':>7s}")
    for label, x, wall in rows:
        err = np.abs(x - ref)
        mixed = float((err / (1.0 + np.abs(ref))).max())
        print(f"{label:45s} {err[:7].max():13.3e} {err[7:].max():13.3e} {mixed:12.2e} "
              f"{wall:7.1f}")
    rk_fine, indep = rows[1][1], rows[3][1]
    print(f"gpme RK4 (2e-6 s) against the independent solution: angles "
          f"{np.abs(rk_fine - indep)[:7].max():.2e} rad, rates "
          f"{np.abs(rk_fine - indep)[7:].max():.2e} rad/s; RK4 halving estimate "
          f"{np.abs(rows[0][1] - rk_fine)[:7].max() / 15:.2e} rad, "
          f"{np.abs(rows[0][1] - rk_fine)[7:].max() / 15:.2e} rad/s")


if __name__ == "__main__":
    main()

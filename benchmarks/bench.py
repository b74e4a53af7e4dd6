"""Cost of the GPME right-hand side and of a full run, gpme against Pinocchio and MuJoCo.

    python -m benchmarks.bench [--quick] [--out reports/benchmarks]

(a) one evaluation of the constrained accelerations q_ddot(t, q, q_dot) of the crane for
    n_rfe in {0, 1, 2, 5, 10, 20, 50}: gpme (ProgrammedMotion.solve), Pinocchio from Python
    (benchmarks.engines.PinocchioConstrained) and MuJoCo's mj_forward on the MJCF with the
    constraint mechanism; best of 5 repeats, microseconds per call.
(b) wall time of the 10 s programmed run (on-manifold start), rigid and flexible
    (n_rfe = 5): gpme RK4, gpme with an adaptive method at matched accuracy, Pinocchio with
    RK4 (Python loop), MuJoCo with RK4.  Accuracy = max |psi2 - psi2_ref| over the run on a
    0.01 s grid, psi2_ref from gpme RK4 at half the step.
Prints the tables and the ratios, writes CSV and a PNG plot.  All in one process, one
machine, so the ratios compare like with like.
"""
import argparse
import os
import platform
import time
import timeit
from pathlib import Path

import numpy as np
import pandas as pd

from gpme_core.atomic import atomic_save_figure, atomic_write_csv
from gpme_examples.crane import crane_system, initial_state
from gpme_core.errors import GpmeError
from gpme_core.integrate import simulate, suggest_rk4_step

from .engines import PinocchioConstrained, mujoco_forward_setup, mujoco_run, rk4_run

N_RFE = (0, 1, 2, 5, 10, 20, 50)
OUTPUT_DT = 1e-2
RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)


def _per_call_us(fn, min_time=0.2):
    fn()
    number = max(1, int(min_time / max(timeit.timeit(fn, number=1), 1e-7)))
    return 1e6 * min(timeit.repeat(fn, number=number, repeat=5)) / number


def evaluation_costs(n_values):
    """Table (a): microseconds per constrained-acceleration evaluation."""
    rows = []
    for n in n_values:
        system = crane_system(n)
        q, qd = system.consistent_state(0.0, *initial_state(system.model))
        t = 0.37
        pc = PinocchioConstrained(system)
        diff = np.abs(pc.accelerations(t, q, qd) - system.solve(t, q, qd).q_ddot).max()
        mj_forward, _ = mujoco_forward_setup(system, q, qd)
        row = {"n_rfe": n, "n_coordinates": system.model.n_coordinates,
               "gpme_us": _per_call_us(lambda: system.solve(t, q, qd)),
               "pinocchio_us": _per_call_us(lambda: pc.accelerations(t, q, qd)),
               "mujoco_us": _per_call_us(mj_forward),
               "max |qdd gpme - qdd pinocchio|": diff}
        row["gpme/pinocchio"] = row["gpme_us"] / row["pinocchio_us"]
        row["gpme/mujoco"] = row["gpme_us"] / row["mujoco_us"]
        rows.append(row)
        print(f"  n_rfe {n:3d} ({row['n_coordinates']:3d} coordinates): gpme "
              f"{row['gpme_us']:8.1f} us, pinocchio {row['pinocchio_us']:8.1f} us, mujoco "
              f"{row['mujoco_us']:8.1f} us", flush=True)
    return pd.DataFrame(rows)


def loglog_slope(df, n_lo, n_hi, column="gpme_us"):
    """Slope of log(cost) against log(number of coordinates) between two n_rfe values."""
    lo, hi = df[df.n_rfe == n_lo].iloc[0], df[df.n_rfe == n_hi].iloc[0]
    return float(np.log(hi[column] / lo[column]) / np.log(hi.n_coordinates / lo.n_coordinates))


def _psi2_error(df, ref):
    grid = ref.t.to_numpy()
    return float(np.abs(np.interp(grid, df.t.to_numpy(), df.psi2.to_numpy()) - ref.psi2.to_numpy()).max())


def run_costs(t_end, cases, mujoco_dt):
    """Table (b): wall time of full runs at their accuracy."""
    rows = []
    for label, n, dt in cases:
        system = crane_system(n)
        q0, qd0 = system.consistent_state(0.0, *initial_state(system.model))
        ref = simulate(system, t_end, q0, qd0, dt=dt / 2, output_dt=OUTPUT_DT)
        rk4 = simulate(system, t_end, q0, qd0, dt=dt, output_dt=OUTPUT_DT)
        err_rk4 = _psi2_error(rk4, ref)
        rows.append({"case": label, "engine": "gpme", "method": f"RK4 dt={dt:g}",
                     "wall_s": rk4.attrs["wall_time_s"], "psi2_error_rad": err_rk4})
        print(f"  {label}: gpme RK4 {rows[-1]['wall_s']:.1f} s (psi2 error {err_rk4:.1e})",
              flush=True)
        # scipy's Radau (Python Newton iterations, finite-difference Jacobian) did not finish
        # the flexible 10 s run in 12 minutes: the 8 Hz forced motion keeps its steps small,
        # so it is timed on the rigid case only (docs/benchmarks.md)
        for method in ("DOP853", "Radau") if n == 0 else ("DOP853",):
            for rtol in RTOLS:
                try:
                    run = simulate(system, t_end, q0, qd0, method=method, rtol=rtol,
                                   atol=rtol * 1e-2, output_dt=OUTPUT_DT)
                except GpmeError as exc:
                    print(f"    {method} rtol {rtol:g}: {exc}")
                    continue
                err = _psi2_error(run, ref)
                if err <= err_rk4 or rtol == RTOLS[-1]:
                    rows.append({"case": label, "engine": "gpme", "method": f"{method} rtol={rtol:g}",
                                 "wall_s": run.attrs["wall_time_s"], "psi2_error_rad": err})
                    print(f"  {label}: gpme {method} rtol {rtol:g}: {rows[-1]['wall_s']:.1f} s "
                          f"(psi2 error {err:.1e})", flush=True)
                    break
        pc = PinocchioConstrained(system)
        times, qs, wall = rk4_run(pc.accelerations, t_end, q0, qd0, dt, OUTPUT_DT)
        pin_run = pd.DataFrame({"t": times, "psi2": qs[:, system.model.index("psi2")]})
        rows.append({"case": label, "engine": "pinocchio", "method": f"RK4 dt={dt:g} (Python loop)",
                     "wall_s": wall, "psi2_error_rad": _psi2_error(pin_run, ref)})
        print(f"  {label}: pinocchio RK4 {wall:.1f} s", flush=True)
        mdt = mujoco_dt.get(n, dt)
        try:
            mj = mujoco_run(system, t_end, q0, qd0, mdt, OUTPUT_DT)
            rows.append({"case": label, "engine": "mujoco", "method": f"RK4 dt={mdt:g}",
                         "wall_s": mj.attrs["wall_time_s"], "psi2_error_rad": _psi2_error(mj, ref)})
            print(f"  {label}: mujoco RK4 {rows[-1]['wall_s']:.1f} s (psi2 error "
                  f"{rows[-1]['psi2_error_rad']:.1e})", flush=True)
        except GpmeError as exc:
            print(f"  {label}: mujoco at dt {mdt:g}: {exc}")
    return pd.DataFrame(rows)


def plot(evals):
    from matplotlib.figure import Figure
    fig = Figure(figsize=(6.5, 4.2))
    ax = fig.subplots()
    for col, label in (("gpme_us", "gpme"), ("pinocchio_us", "Pinocchio from Python"),
                       ("mujoco_us", "MuJoCo mj_forward")):
        ax.loglog(evals.n_coordinates, evals[col], "o-", label=label)
    x = evals.n_coordinates.to_numpy(float)
    ax.loglog(x, evals.gpme_us.iloc[0] * (x / x[0]) ** 2, "k:", lw=0.8, label="slope 2")
    ax.set_xlabel("number of coordinates")
    ax.set_ylabel("one constrained q_ddot evaluation [us]")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    return fig


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="smoke test: small n, 0.2 s runs")
    parser.add_argument("--out", default="reports/benchmarks")
    args = parser.parse_args(argv)
    out = Path(args.out)
    print(f"machine: {platform.node()}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, {platform.python_version()}")
    n_values = (0, 1, 5) if args.quick else N_RFE
    print("(a) one evaluation of the constrained accelerations")
    evals = evaluation_costs(n_values)
    slope = loglog_slope(evals, 1 if args.quick else 5, 5 if args.quick else 50)
    flex_n = 1 if args.quick else 5
    flex_model = crane_system(flex_n).model
    # 90 % of the RK4 stability limit of the linearised modes, rounded down
    flex_dt = float(f"{suggest_rk4_step(flex_model, initial_state(flex_model)[0], 0.9):.1e}")
    cases = [("rigid", 0, 1e-4), (f"flexible n_rfe={flex_n}", flex_n, flex_dt)]
    t_end = 0.2 if args.quick else 10.0
    print(f"(b) {t_end:g} s programmed runs")
    runs = run_costs(t_end, cases, mujoco_dt={0: 1e-4, 1: 1e-4, 5: flex_dt / 8})
    atomic_write_csv(evals, out / "evaluation_costs.csv")
    atomic_write_csv(runs, out / "run_costs.csv")
    atomic_save_figure(plot(evals), out / "evaluation_costs.png")
    with pd.option_context("display.width", 200, "display.float_format", "{:.4g}".format):
        print(evals.to_string(index=False))
        print(runs.to_string(index=False))
    print(f"log-log slope of gpme cost against coordinates: {slope:.2f}")
    n5 = evals[evals.n_rfe == flex_n].iloc[0]
    print(f"n_rfe {flex_n}: gpme/pinocchio = {n5['gpme/pinocchio']:.2f}, "
          f"gpme/mujoco = {n5['gpme/mujoco']:.2f}")
    print(f"wrote {out}/evaluation_costs.csv, run_costs.csv, evaluation_costs.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

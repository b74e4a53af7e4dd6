"""Cost and accuracy of the GPME right-hand side and of full runs, gpme against Pinocchio
and MuJoCo, the compiled path against the Python path ("before").

    python -m benchmarks.bench [--quick] [--out reports/benchmarks]

(a) one evaluation of the constrained accelerations q_ddot(t, q, q_dot) of the crane for
    n_rfe in {0, 1, 2, 5, 10, 20, 50}, microseconds per call (best of interleaved rounds):
    gpme compiled (gpme_core.compiled.CompiledSystem.accelerator), gpme's Python path
    (ProgrammedMotion.solve), Pinocchio from Python (benchmarks.engines.PinocchioConstrained)
    and MuJoCo's mj_forward on the MJCF with the constraint mechanism; the same with the
    crane's two constraints written as SymPy expressions (MuJoCo has no SymPy constraint: its
    mechanism realises the same ellipse and height programme).  Agreement of the q_ddot
    (gpme against Pinocchio, SymPy against built-in) next to round-off eps cond(M) |q_ddot|.
(b) the 10 s programmed run (on-manifold start), rigid and flexible (n_rfe = 5).  Reference:
    gpme RadauIIA at REF_DT, its own error estimated by RadauIIA at 2 REF_DT.  Runs: gpme RK4
    in Python (the "before", at 90 % of suggest_rk4_step), gpme RK4 compiled at the same step,
    gpme RadauIIA at RADAU_DTS, Pinocchio RK4 (Python loop), MuJoCo RK4; on the rigid crane
    also SciPy's DOP853 and Radau at the loosest rtol as accurate as the Python RK4.
    Accuracy on the 0.01 s output grid: max |psi2 - psi2_ref| (rad), the largest error over
    the arm's elastic coordinates (names with "_arm_", rad) and over every coordinate (m or
    rad); and the largest difference from the Python RK4 run (every coordinate).
(c) n_rfe = 20, 10 s, RadauIIA at 1e-3 s, its accuracy against RadauIIA at 5e-4 s.
(d) sweep throughput: points of a short flexible run (1 s of n_rfe = 5, the programme
    amplitude varied) per core-minute, before (Python RK4 at the stable step) and after
    (RadauIIA at 1e-3 s), in this process pinned to one core; each point end to end
    (system, consistent start, run, output table).
Prints the tables and the ratios, writes CSVs and a PNG plot.  All in one process on one
machine, so the ratios compare like with like; the 1-minute load average is recorded next
to every timing (the machine may be shared).
"""
import argparse
import os
import platform
import time
import timeit
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from gpme_io.atomic import atomic_save_figure, atomic_write_csv
from gpme_core.blas_threads import single_threaded_blas
from gpme_core.compiled import for_system
from gpme_core.constraints import SympyPointConstraint
from gpme_core.errors import GpmeError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_core.stability import suggest_rk4_step
from gpme_examples.crane import CraneParameters, crane_system, initial_state

from .engines import (PinocchioConstrained, mujoco_forward_setup, mujoco_run,
                      pinocchio_run)

OUTPUT_DT = 1e-2            # s, grid on which runs are compared
EVAL_TIME = 0.37            # s, time of the timed evaluation (programme and drive non-trivial)
RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
# s, RadauIIA step of the reference runs, checked against 2 REF_DT.  Measured on the 10 s
# flexible run: RadauIIA at 2.5e-4 s is 8e-11 rad from 1.25e-4 s on the arm, less accurate than
# the RK4 run at 4e-5 s it would judge (3e-12 from RK4 at 2e-5 s).  Halving the step divides
# the arm error by ~20 (order ~4.3 observed), so at 6.25e-5 s the reference is ~2e-13 rad from
# the exact motion and its printed check (against 1.25e-4 s) is ~4e-12 rad
REF_DT = 6.25e-5
# s, RadauIIA steps benchmarked: the 1e-3 and 2e-3 first, then the smaller steps at
# which RadauIIA may match MuJoCo's accuracy on the arm (its error there comes from the start)
RADAU_DTS = (1e-3, 2e-3, 5e-4, 2.5e-4)
LARGE_DT, LARGE_CHECK_DT = 1e-3, 5e-4   # s, (c)
# s: the arm error is also given after this time, past the start's transient (the on-manifold
# start excites the stiff RFEM modes; RadauIIA's largest arm error falls in the first 0.01 s)
LATE_T = 1.0
MUJOCO_RIGID_DT = 1e-4      # s
# MuJoCo's RK4 with the auxiliary mechanism needs the flexible RK4 step / 8 at n_rfe = 5
MUJOCO_FLEX_DIVISOR = 8
RIGID_RK4_DT = 1e-4         # s, RK4 step of the rigid runs (as in earlier benchmarks)
EPS = np.finfo(float).eps


@dataclass(frozen=True)
class Sizes:
    """What one benchmark run measures (--quick: tiny sizes for the smoke test)."""

    n_values: tuple         # n_rfe of table (a)
    slope_range: tuple      # (n_lo, n_hi) of the log-log slope
    flex_n: int             # n_rfe of the flexible run (b) and the sweep (d)
    t_end: float            # s, runs of (b)
    large_n: int            # n_rfe of (c)
    large_t_end: float      # s
    sweep_amplitudes: tuple  # m, programme amplitudes of (d)
    sweep_t_end: float      # s
    rounds: int             # interleaved timing rounds of (a)
    min_time: float         # s, least duration of one timing in (a)


FULL = Sizes((0, 1, 2, 5, 10, 20, 50), (5, 50), 5, 10.0, 20, 10.0, (0.35, 0.40, 0.45, 0.50),
             1.0, 7, 0.1)
QUICK = Sizes((0, 1, 5), (1, 5), 5, 0.2, 5, 0.2, (0.45, 0.50), 0.2, 3, 0.02)


def _load():
    """1-minute load average of the machine (nan where the OS has none)."""
    try:
        return os.getloadavg()[0]
    except (AttributeError, OSError):
        return float("nan")


# ------------------------------------------------------------------ (a) one evaluation
def sympy_constraints(params=CraneParameters()):
    """The crane's Phi_1 (ellipse) and Phi_2 (height programme) of
    gpme_examples.crane.crane_constraints written as SymPy expressions in x, y, z (m) of
    frame E and t (s), with the numbers of ``params``."""
    p = params
    return [SympyPointConstraint(f"(x/{p.ellipse_a!r})**2 + (y/{p.ellipse_b!r})**2 - 1",
                                 frame="E", name="Phi_1"),
            SympyPointConstraint(f"z - ({p.z0!r} + {p.amplitude!r}*cos(2*pi*t/{p.period!r}))",
                                 frame="E", name="Phi_2")]


def sympy_system(system, params=CraneParameters()):
    """``system`` (the crane) with its constraints replaced by :func:`sympy_constraints`
    (same model, dependent coordinates and Baumgarte parameters)."""
    return ProgrammedMotion(system.model, sympy_constraints(params),
                            dependent=system.dependent, baumgarte=(system.alpha, system.beta))


def _compiled_accelerator(system):
    compiled, reason = for_system(system)
    if compiled is None:
        raise RuntimeError(f"the benchmark needs the compiled path, and {system.model.name} "
                           f"does not compile: {reason}")
    return compiled.accelerator(system.ic, system.dc)


def interleaved_us(functions, rounds, min_time):
    """{name: microseconds per call} of argument-less callables: the best over ``rounds``
    rounds, each timing every function once in turn (so all meet the same machine load),
    each timing lasting at least about ``min_time`` s."""
    numbers = {}
    for name, fn in functions.items():
        fn()
        once = min(timeit.repeat(fn, number=1, repeat=3))
        numbers[name] = max(1, int(min_time / max(once, 1e-7)))
    best = dict.fromkeys(functions, np.inf)
    for _ in range(rounds):
        for name, fn in functions.items():
            best[name] = min(best[name], timeit.timeit(fn, number=numbers[name]) / numbers[name])
    return {name: 1e6 * v for name, v in best.items()}


def evaluation_costs(n_values, rounds, min_time, params=CraneParameters()):
    """Tables (a): (costs, agreement), one row per n_rfe.

    costs: microseconds per q_ddot evaluation of each engine and the ratios;
    agreement: max |q_ddot difference| (SI: m/s^2 and rad/s^2 mixed, as q_ddot) between
    gpme compiled / Python / SymPy and Pinocchio, with max |q_ddot| and the round-off scale
    eps cond(M) max |q_ddot| (cond of Pinocchio's CRBA mass matrix)."""
    costs, agreement = [], []
    for n in n_values:
        system = crane_system(n, params)
        sym = sympy_system(system, params)
        q, qd = system.consistent_state(0.0, *initial_state(system.model, params))
        t = EVAL_TIME
        accelerate = _compiled_accelerator(system)
        accelerate_sym = _compiled_accelerator(sym)
        pc, pc_sym = PinocchioConstrained(system), PinocchioConstrained(sym)
        mj_forward, _ = mujoco_forward_setup(system, q, qd)
        qdd_pin = pc.accelerations(t, q, qd)
        qdd_pin_sym = pc_sym.accelerations(t, q, qd)
        qdd_compiled = accelerate(t, q, qd).copy()
        qdd_python = system.solve(t, q, qd).q_ddot
        qdd_sym_compiled = accelerate_sym(t, q, qd).copy()
        qdd_sym_python = sym.solve(t, q, qd).q_ddot
        scale = float(np.abs(qdd_pin).max())
        cond = float(np.linalg.cond(pc.mass_matrix(q)))

        def diff(a, b):
            return float(np.abs(a - b).max())
        agreement.append({
            "n_rfe": n, "max|qdd|": scale, "cond(M)": cond,
            "eps cond(M) max|qdd|": EPS * cond * scale,
            "compiled-pinocchio": diff(qdd_compiled, qdd_pin),
            "python-pinocchio": diff(qdd_python, qdd_pin),
            "sympy compiled-sympy pinocchio": diff(qdd_sym_compiled, qdd_pin_sym),
            "sympy-builtin compiled": diff(qdd_sym_compiled, qdd_compiled),
            "sympy-builtin python": diff(qdd_sym_python, qdd_python)})
        load = _load()
        us = interleaved_us({
            "gpme_compiled_us": lambda: accelerate(t, q, qd),
            "gpme_python_us": lambda: system.solve(t, q, qd),
            "pinocchio_us": lambda: pc.accelerations(t, q, qd),
            "mujoco_us": mj_forward,
            "sympy_compiled_us": lambda: accelerate_sym(t, q, qd),
            "sympy_python_us": lambda: sym.solve(t, q, qd),
            "sympy_pinocchio_us": lambda: pc_sym.accelerations(t, q, qd)}, rounds, min_time)
        row = {"n_rfe": n, "n_coordinates": system.model.n_coordinates, **us}
        row["compiled/pinocchio"] = us["gpme_compiled_us"] / us["pinocchio_us"]
        row["compiled/mujoco"] = us["gpme_compiled_us"] / us["mujoco_us"]
        row["sympy compiled/sympy pinocchio"] = us["sympy_compiled_us"] / us["sympy_pinocchio_us"]
        row["sympy compiled/mujoco"] = us["sympy_compiled_us"] / us["mujoco_us"]
        row["python/compiled"] = us["gpme_python_us"] / us["gpme_compiled_us"]
        row["load_1min"] = load
        costs.append(row)
        print(f"  n_rfe {n:3d} ({row['n_coordinates']:3d} coordinates): gpme compiled "
              f"{us['gpme_compiled_us']:7.1f} us (SymPy {us['sympy_compiled_us']:7.1f}), "
              f"Python {us['gpme_python_us']:7.1f} us, pinocchio {us['pinocchio_us']:7.1f} us, "
              f"mujoco {us['mujoco_us']:7.1f} us (load {load:.2f})", flush=True)
    return pd.DataFrame(costs), pd.DataFrame(agreement)


def loglog_slope(df, n_lo, n_hi, column="gpme_compiled_us"):
    """Slope of log(cost) against log(number of coordinates) between two n_rfe values."""
    lo, hi = df[df.n_rfe == n_lo].iloc[0], df[df.n_rfe == n_hi].iloc[0]
    return float(np.log(hi[column] / lo[column]) / np.log(hi.n_coordinates / lo.n_coordinates))


# ------------------------------------------------------------------ (b), (c) runs
def arm_coordinates(model):
    """Names of the arm's elastic (RFEM) coordinates ("_arm_" in the name; none if rigid)."""
    return [nm for nm in model.coordinate_names if "_arm_" in nm]


def max_error(run, ref, names, after=None):
    """max over ``names`` and over ref's time grid (from ``after`` s on, if given) of
    |run - ref| (interpolated onto the grid; both recorded every OUTPUT_DT); nan when names
    is empty or no grid time is after ``after``."""
    grid, t = ref.t.to_numpy(), run.t.to_numpy()
    keep = grid > (-np.inf if after is None else after)
    if not names or not keep.any():
        return float("nan")
    return float(max(np.abs(np.interp(grid[keep], t, run[nm].to_numpy())
                            - ref[nm].to_numpy()[keep]).max() for nm in names))


class RunTable:
    """Rows of tables (b) and (c): wall time of one run and its errors against the case's
    reference (psi2, the arm's elastic coordinates, every coordinate) and its largest
    difference from the case's Python RK4 run (the "before"; every coordinate).  ``role``
    names what a row is (reference, reference check, python rk4, compiled rk4, radau <dt>,
    scipy, pinocchio, mujoco)."""

    def __init__(self):
        self.rows = []
        self.python_rk4 = {}        # case -> the Python RK4 run of that case

    def add(self, case, role, engine, method, run, ref, model, compiled=None):
        names = list(model.coordinate_names)
        arm = arm_coordinates(model)
        before = self.python_rk4.get(case)
        row = {"case": case, "role": role, "engine": engine, "method": method,
               "wall_s": run.attrs["wall_time_s"],
               "psi2_error_rad": np.nan if ref is None else max_error(run, ref, ["psi2"]),
               "arm_error_rad": np.nan if ref is None else max_error(run, ref, arm),
               f"arm_error_t>{LATE_T:g}s_rad": np.nan if ref is None else max_error(
                   run, ref, arm, after=LATE_T),
               "q_error": np.nan if ref is None else max_error(run, ref, names),
               "q_vs_python_rk4": np.nan if before is None else max_error(run, before, names),
               "compiled": compiled, "load_1min": _load()}
        self.rows.append(row)
        print(f"  {case}: {engine} {method}: {row['wall_s']:.3g} s, psi2 error "
              f"{row['psi2_error_rad']:.1e} rad, arm error {row['arm_error_rad']:.1e} rad, "
              f"q error {row['q_error']:.1e} (load {row['load_1min']:.2f})", flush=True)
        return row

    def frame(self):
        return pd.DataFrame(self.rows)


def _gpme(table, case, role, system, q0, qd0, t_end, ref, method, dt, compiled=True):
    """A gpme run with simulate, added to ``table``; returns (run, row)."""
    run = simulate(system, t_end, q0, qd0, dt=dt, method=method, output_dt=OUTPUT_DT,
                   compiled=compiled)
    path = "compiled" if run.attrs["compiled"] else "Python"
    label = f"{method} dt={run.attrs['dt']:g} ({path})"
    return run, table.add(case, role, "gpme", label, run, ref, system.model,
                          run.attrs["compiled"])


def warm_up(system, q0, qd0, rk4_dt):
    """Load (or compile) the kernels of both compiled loops and the Python path, so no run
    below pays it: 0.01 s of each."""
    for method, dt, compiled in (("RK4", rk4_dt, True), ("RK4", rk4_dt, False),
                                 ("RadauIIA", RADAU_DTS[0], True)):
        simulate(system, OUTPUT_DT, q0, qd0, dt=dt, method=method, output_dt=OUTPUT_DT,
                 compiled=compiled)


def run_case(table, case, n, t_end, rk4_dt, mujoco_dt, adaptive):
    """All runs of one case of (b); returns {role: row}."""
    system = crane_system(n)
    q0, qd0 = system.consistent_state(0.0, *initial_state(system.model))
    warm_up(system, q0, qd0, rk4_dt)
    rows = {}
    ref, rows["reference"] = _gpme(table, case, "reference", system, q0, qd0, t_end, None,
                                   "RadauIIA", REF_DT)
    rows["reference check"] = _gpme(table, case, "reference check", system, q0, qd0, t_end,
                                    ref, "RadauIIA", 2 * REF_DT)[1]
    table.python_rk4[case], rows["python rk4"] = _gpme(
        table, case, "python rk4", system, q0, qd0, t_end, ref, "RK4", rk4_dt, compiled=False)
    rows["compiled rk4"] = _gpme(table, case, "compiled rk4", system, q0, qd0, t_end, ref,
                                 "RK4", rk4_dt)[1]
    for dt in RADAU_DTS:
        role = f"radau {dt:g}"
        rows[role] = _gpme(table, case, role, system, q0, qd0, t_end, ref, "RadauIIA", dt)[1]
    for method in adaptive:
        # the loosest rtol at least as accurate (psi2) as the Python RK4 run
        for rtol in RTOLS:
            try:
                run = simulate(system, t_end, q0, qd0, method=method, rtol=rtol,
                               atol=rtol * 1e-2, output_dt=OUTPUT_DT)
            except GpmeError as exc:
                print(f"    {method} rtol {rtol:g}: {exc}")
                continue
            if max_error(run, ref, ["psi2"]) <= rows["python rk4"]["psi2_error_rad"] \
                    or rtol == RTOLS[-1]:
                table.add(case, "scipy", "gpme", f"{method} rtol={rtol:g} (SciPy)", run, ref,
                          system.model, False)
                break
    run = pinocchio_run(system, t_end, q0, qd0, rk4_dt, OUTPUT_DT)
    rows["pinocchio"] = table.add(case, "pinocchio", "pinocchio",
                                  f"RK4 dt={rk4_dt:g} (Python loop)", run, ref, system.model)
    try:
        run = mujoco_run(system, t_end, q0, qd0, mujoco_dt, OUTPUT_DT)
        rows["mujoco"] = table.add(case, "mujoco", "mujoco", f"RK4 dt={mujoco_dt:g}", run,
                                   ref, system.model)
    except GpmeError as exc:
        print(f"  {case}: mujoco at dt {mujoco_dt:g}: {exc}")
    return rows


def large_run(table, n, t_end):
    """(c): RadauIIA at LARGE_DT on n_rfe = n against RadauIIA at LARGE_CHECK_DT; returns
    the row of the LARGE_DT run."""
    case = f"(c) flexible n_rfe={n}"
    system = crane_system(n)
    q0, qd0 = system.consistent_state(0.0, *initial_state(system.model))
    ref = _gpme(table, case, "reference", system, q0, qd0, t_end, None, "RadauIIA",
                LARGE_CHECK_DT)[0]
    return _gpme(table, case, f"radau {LARGE_DT:g}", system, q0, qd0, t_end, ref, "RadauIIA",
                 LARGE_DT)[1]


# ------------------------------------------------------------------ (d) sweep throughput
def _one_core():
    """Pin this process to one CPU; returns the previous CPU set (None: not supported)."""
    try:
        before = os.sched_getaffinity(0)
        os.sched_setaffinity(0, {min(before)})
        return before
    except (AttributeError, OSError):
        return None


def sweep_throughput(n, t_end, amplitudes, rk4_dt):
    """(d): one row per programme amplitude: wall and CPU seconds of the whole point
    (system, consistent start, run, output table) before (Python RK4 at rk4_dt) and after
    (RadauIIA at RADAU_DTS[0]), and how far the two runs differ (psi2, arm; rad)."""
    rows = []
    cpus = _one_core()
    try:
        warm = crane_system(n)
        warm_up(warm, *warm.consistent_state(0.0, *initial_state(warm.model)), rk4_dt)
        for amplitude in amplitudes:
            params = CraneParameters().with_changes(amplitude=amplitude)
            row = {"amplitude_m": amplitude, "load_1min": _load()}
            runs = {}
            for label, method, dt, compiled in (("before", "RK4", rk4_dt, False),
                                                ("after", "RadauIIA", RADAU_DTS[0], True)):
                wall, cpu = time.perf_counter(), time.process_time()
                system = crane_system(n, params)
                q0, qd0 = system.consistent_state(0.0, *initial_state(system.model, params))
                runs[label] = simulate(system, t_end, q0, qd0, dt=dt, method=method,
                                       output_dt=OUTPUT_DT, compiled=compiled)
                row[f"{label}_wall_s"] = time.perf_counter() - wall
                row[f"{label}_cpu_s"] = time.process_time() - cpu
            row["psi2_after-before_rad"] = max_error(runs["after"], runs["before"], ["psi2"])
            row["arm_after-before_rad"] = max_error(runs["after"], runs["before"],
                                                    arm_coordinates(system.model))
            row["q_after-before"] = max_error(runs["after"], runs["before"],
                                              list(system.model.coordinate_names))
            rows.append(row)
            print(f"  amplitude {amplitude:g} m: before {row['before_wall_s']:.2f} s, after "
                  f"{row['after_wall_s']:.2f} s, |after - before| psi2 "
                  f"{row['psi2_after-before_rad']:.1e} rad, arm "
                  f"{row['arm_after-before_rad']:.1e} rad (load {row['load_1min']:.2f})",
                  flush=True)
    finally:
        if cpus is not None:
            os.sched_setaffinity(0, cpus)
    df = pd.DataFrame(rows)
    df.attrs["pinned"] = cpus is not None
    return df


def points_per_core_minute(sweep, label, clock="cpu"):
    """Points of the sweep per minute of one core (from CPU or wall seconds)."""
    return 60.0 * len(sweep) / sweep[f"{label}_{clock}_s"].sum()


# ------------------------------------------------------------------ output
def plot(evals):
    from matplotlib.figure import Figure
    fig = Figure(figsize=(6.5, 4.2))
    ax = fig.subplots()
    for col, label, style in (("gpme_compiled_us", "gpme compiled", "o-"),
                              ("sympy_compiled_us", "gpme compiled, SymPy constraints", "o--"),
                              ("gpme_python_us", "gpme Python path", "s-"),
                              ("pinocchio_us", "Pinocchio from Python", "^-"),
                              ("mujoco_us", "MuJoCo mj_forward", "v-")):
        ax.loglog(evals.n_coordinates, evals[col], style, label=label)
    x = evals.n_coordinates.to_numpy(float)
    ax.loglog(x, evals.gpme_compiled_us.iloc[0] * (x / x[0]) ** 2, "k:", lw=0.8,
              label="slope 2")
    ax.set_xlabel("number of coordinates")
    ax.set_ylabel("one constrained q_ddot evaluation [us]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _versions():
    import mujoco
    import numba
    import pinocchio
    import scipy
    return (f"numpy {np.__version__}, scipy {scipy.__version__}, numba {numba.__version__}, "
            f"pinocchio {pinocchio.__version__}, mujoco {mujoco.__version__}")


def _print_table(title, df):
    print(title)
    with pd.option_context("display.width", 250, "display.max_columns", 40,
                           "display.float_format", "{:.4g}".format):
        print(df.to_string(index=False), flush=True)


def _ratio_line(label, num, den, target=None):
    ratio = num["wall_s"] / den["wall_s"]
    goal = f" (target <= {target})" if target else ""
    return (f"  {label}: {num['wall_s']:.3g} s / {den['wall_s']:.3g} s = {ratio:.3g}{goal}; "
            f"psi2 error {num['psi2_error_rad']:.1e} vs {den['psi2_error_rad']:.1e} rad, arm "
            f"error {num['arm_error_rad']:.1e} vs {den['arm_error_rad']:.1e} rad, q error "
            f"{num['q_error']:.1e} vs {den['q_error']:.1e}")


def _matched(rows, other):
    """(dt, row) of the largest RadauIIA step whose psi2 and arm errors are no larger than
    ``other``'s (an error that is nan on both sides, the rigid arm's, counts as matched);
    None if no step is."""
    def at_most(a, b):
        return (np.isnan(a) and np.isnan(b)) or a <= b
    for dt in sorted(RADAU_DTS, reverse=True):
        row = rows[f"radau {dt:g}"]
        if all(at_most(row[k], other[k]) for k in ("psi2_error_rad", "arm_error_rad")):
            return dt, row
    return None


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="smoke test: n_rfe up to 5, 0.2 s runs")
    parser.add_argument("--out", default="reports/benchmarks")
    args = parser.parse_args(argv)
    out = Path(args.out)
    sizes = QUICK if args.quick else FULL
    start = time.perf_counter()
    print(f"machine: {platform.node()}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, Python {platform.python_version()}; {_versions()}")
    print(f"load average at start: {_load():.2f}")

    print("(a) one evaluation of the constrained accelerations (BLAS/LAPACK on one thread, "
          "as in gpme's compiled runs: gpme_core.compiled.single_threaded_blas)")
    with single_threaded_blas():
        evals, agreement = evaluation_costs(sizes.n_values, sizes.rounds, sizes.min_time)
    slopes = {col: loglog_slope(evals, *sizes.slope_range, col)
              for col in ("gpme_compiled_us", "sympy_compiled_us", "gpme_python_us",
                          "pinocchio_us", "mujoco_us")}

    flex_n = sizes.flex_n
    flex_model = crane_system(flex_n).model
    # 90 % of the RK4 stability limit of the linearised modes, rounded down
    flex_dt = float(f"{suggest_rk4_step(flex_model, initial_state(flex_model)[0], 0.9):.1e}")
    print(f"(b) {sizes.t_end:g} s programmed runs (RK4 step of the flexible crane: "
          f"{flex_dt:g} s)")
    table = RunTable()
    rigid = run_case(table, "rigid", 0, sizes.t_end, RIGID_RK4_DT, MUJOCO_RIGID_DT,
                     ("DOP853", "Radau"))
    flex_case = f"flexible n_rfe={flex_n}"
    flex = run_case(table, flex_case, flex_n, sizes.t_end, flex_dt,
                    flex_dt / MUJOCO_FLEX_DIVISOR, ())
    print(f"(c) n_rfe = {sizes.large_n}, {sizes.large_t_end:g} s, RadauIIA dt = {LARGE_DT:g} s")
    large = large_run(table, sizes.large_n, sizes.large_t_end)
    runs = table.frame()

    print(f"(d) sweep throughput: {sizes.sweep_t_end:g} s of n_rfe = {flex_n}, amplitudes "
          f"{list(sizes.sweep_amplitudes)} m")
    sweep = sweep_throughput(flex_n, sizes.sweep_t_end, sizes.sweep_amplitudes, flex_dt)

    atomic_write_csv(evals, out / "evaluation_costs.csv")
    atomic_write_csv(agreement, out / "evaluation_agreement.csv")
    atomic_write_csv(runs, out / "run_costs.csv")
    atomic_write_csv(sweep, out / "sweep_throughput.csv")
    atomic_save_figure(plot(evals), out / "evaluation_costs.png")

    print()
    _print_table("(a) microseconds per q_ddot evaluation (best of interleaved rounds)",
                 evals)
    _print_table("(a) agreement of q_ddot (max |difference|, SI) and the round-off scale",
                 agreement)
    _print_table("(b), (c) runs: wall time of the integration loop, error against the "
                 "reference on the 0.01 s grid", runs.drop(columns=["role", "compiled"]))
    _print_table("(d) sweep points, whole point (system, start, run, output table)", sweep)

    print("\nFigures")
    lo, hi = sizes.slope_range
    print(f"  log-log slope of the cost against coordinates, n_rfe {lo} to {hi}: "
          + ", ".join(f"{col[:-3]} {s:.2f}" for col, s in slopes.items()))
    at = evals[evals.n_rfe == flex_n].iloc[0]
    print(f"  n_rfe {flex_n}: compiled/pinocchio = {at['compiled/pinocchio']:.2f}, "
          f"compiled/mujoco = {at['compiled/mujoco']:.2f}; SymPy constraints: compiled/"
          f"pinocchio = {at['sympy compiled/sympy pinocchio']:.2f}, compiled/mujoco = "
          f"{at['sympy compiled/mujoco']:.2f}; Python path/compiled = "
          f"{at['python/compiled']:.1f}")
    worst = agreement.drop(columns=["n_rfe", "max|qdd|", "cond(M)",
                                    "eps cond(M) max|qdd|"]).max(axis=1) / agreement["max|qdd|"]
    print(f"  largest q_ddot disagreement relative to max|q_ddot|: {worst.max():.1e} "
          f"(eps cond(M) up to {(EPS * agreement['cond(M)']).max():.1e})")
    for case, rows in (("rigid", rigid), (flex_case, flex)):
        check = rows["reference check"]
        print(f"  {case}, {sizes.t_end:g} s; reference RadauIIA dt={REF_DT:g}, its error "
              f"estimate (vs dt={2 * REF_DT:g}): psi2 {check['psi2_error_rad']:.1e} rad, arm "
              f"{check['arm_error_rad']:.1e} rad, q {check['q_error']:.1e}")
        for dt in RADAU_DTS:
            radau = rows[f"radau {dt:g}"]
            print(_ratio_line(f"RadauIIA dt={dt:g} / Python RK4", radau, rows["python rk4"],
                              "1/10" if case == flex_case else None))
            if "mujoco" in rows:
                print(_ratio_line(f"RadauIIA dt={dt:g} / MuJoCo", radau, rows["mujoco"],
                                  "1/20" if case == flex_case else None))
        if "mujoco" in rows:
            matched = _matched(rows, rows["mujoco"])
            print("  largest RadauIIA step at least as accurate as MuJoCo (psi2 and arm): "
                  + ("none" if matched is None else _ratio_line(
                      f"dt={matched[0]:g}, wall / MuJoCo wall", matched[1], rows["mujoco"])[2:]))
        print(_ratio_line("compiled RK4 / Python RK4", rows["compiled rk4"],
                          rows["python rk4"]))
        print(_ratio_line("Python RK4 / Pinocchio RK4", rows["python rk4"], rows["pinocchio"]))
    print(f"  n_rfe {sizes.large_n}, {sizes.large_t_end:g} s, RadauIIA dt={LARGE_DT:g}: "
          f"{large['wall_s']:.1f} s (target < 60 s), psi2 {large['psi2_error_rad']:.1e} rad, "
          f"arm {large['arm_error_rad']:.1e} rad (after {LATE_T:g} s: "
          f"{large[f'arm_error_t>{LATE_T:g}s_rad']:.1e}), q {large['q_error']:.1e} against "
          f"dt={LARGE_CHECK_DT:g}")
    before, after = (points_per_core_minute(sweep, k) for k in ("before", "after"))
    before_w, after_w = (points_per_core_minute(sweep, k, "wall") for k in ("before", "after"))
    print(f"  sweep ({sizes.sweep_t_end:g} s of n_rfe = {flex_n}, "
          f"{'pinned to one core' if sweep.attrs['pinned'] else 'not pinned'}): "
          f"{before:.3g} -> {after:.3g} points per core-minute of CPU time "
          f"(x {after / before:.3g}), {before_w:.3g} -> {after_w:.3g} by wall time; "
          f"|after - before| up to psi2 {sweep['psi2_after-before_rad'].max():.1e} rad, arm "
          f"{sweep['arm_after-before_rad'].max():.1e} rad, q "
          f"{sweep['q_after-before'].max():.1e}")
    print(f"load average at end: {_load():.2f}; benchmark took "
          f"{time.perf_counter() - start:.0f} s")
    print(f"wrote {out}/evaluation_costs.csv, evaluation_agreement.csv, run_costs.csv, "
          "sweep_throughput.csv, evaluation_costs.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

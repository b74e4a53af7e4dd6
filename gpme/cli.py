"""`gpme` command line: simulate a model, crosscheck it against Pinocchio or MuJoCo, verify
everything, sweep parameters.  Every command takes ``--model FILE`` (a TOML model file,
docs/models.md); without it the paper's crane is used.  Run `gpme --help`.

Exit status: 0 success, 1 a check failed, 2 a usage or input error (message on stderr),
74 an output could not be written (disk full, read-only file system, a folder removed;
one line naming the file and the space left), 130 Ctrl-C, 143 SIGTERM, 129 SIGHUP
(gpme.signals: at every moment, compilation included).
"""
# Imports inside functions: a command's own modules are imported by the function that runs
# it (crosscheck's checks and engines, the run service and its writers,
# progress bars, `gpme verify`, `gpme sweep`), so that the parser and the other commands do
# not load them (pandas, Pinocchio, MuJoCo, Drake, Exudyn, Dask, matplotlib).  Not in the
# docstring above, which is `gpme --help`'s text.
import argparse
import os
import signal
import sys
import time
from functools import partial
from importlib import import_module
from pathlib import Path

import numpy as np

from gpme import console_log, signals
from gpme.signals import Terminated  # noqa: F401  (re-exported: gpme.cli.Terminated)
from gpme_core.errors import GpmeError, OutputWriteError
from gpme_core.methods import FIXED_STEP_METHODS, METHODS
from gpme_core.rfem import MAX_SEGMENTS
from gpme_examples import paper
from gpme_io.budget import MAX_CSV_BYTES, MAX_STEP_HALVINGS, MAX_WALL_S, run_budget, wall_limit
from gpme_io.modelfile import load_model_files
from gpme_io.out_lock import exclusive_output, output_dir_problem
from gpme_io.scenario import crane_scenario
from gpme_study.arguments import add_arguments as add_sweep_arguments

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2
EXIT_WRITE = 74         # EX_IOERR: an output could not be written (gpme_core.errors)


def _error(msg):
    print(f"error: {msg}", file=sys.stderr)
    return EXIT_USAGE


# failed checks named in the closing summary line of `gpme simulate` (the others counted)
SUMMARY_FAILURES = 3


def simulate_rows(scenario, df):
    """The checks of one run (crosscheck.run_checks.run_rows), with its rows of constraints
    "not checked" because the run ends inside the Baumgarte transient as information: their
    value is a NaN placeholder under an infinite tolerance, which run_rows means as
    information but crosscheck.compare fails (a NaN fails whatever its tolerance)."""
    from crosscheck.run_checks import run_rows
    return [{**r, "status": "info", "passed": True}
            if r["status"] == "fail" and np.isinf(r["tol_abs"])
            and str(r["reason"]).startswith("not checked") else r
            for r in run_rows(scenario, df)]


def _print_checks(rows):
    """One line per check of a run (crosscheck.run_checks.run_rows): the worst value, where
    it sits, and ok / FAIL with the tolerance, or information."""
    from crosscheck.run_checks import WARNING
    for row in rows:
        if row["status"] == "info" and not np.isfinite(row["gpme_value"]):
            print(f"  {row['quantity']}: {row['reason']} (information)")
        elif row["status"] == "info":
            flag = "WARNING, " + row["reason"] if row["reason"].startswith(WARNING) \
                else "information"
            print(f"  {row['quantity']}: {row['gpme_value']:.3g} at {row['entry']} ({flag})")
        else:
            print(f"  {row['quantity']}: {row['abs_error']:.2e} at {row['entry']} "
                  f"({'ok' if row['status'] == 'pass' else 'FAIL'}, tolerance "
                  f"{row['tol_abs'] + row['tol_rel'] * row['scale']:.1e})")


def _run_checked(label, run, checks, estimate, accurate, force, start):
    """(history, check rows) of one model: with ``accurate`` (RK4 without --dt) the run at
    the step crosscheck.accurate_step chooses, else ``run(None)`` as given; its checks printed."""
    from crosscheck.accurate_step import run_accurately
    if accurate:
        choice = run_accurately(run, checks, estimate=estimate, force=force, start=start,
                                report=lambda line: print(f"  {line}", flush=True))
        df, rows = choice.df, choice.rows
        print(f"  {choice.note}")
    else:
        df = run(None)
        rows = checks(df)
    _print_checks(rows)
    return df, [{**r, "label": label} for r in rows]


def checks_summary(rows):
    """The closing line of `gpme simulate`: the counts of passed, failed and information
    checks, and the failed ones (at most SUMMARY_FAILURES, the worst first, each with its
    worst value, where, and its tolerance)."""
    from crosscheck.accurate_step import gated_errors
    failed = [r for r in rows if r["status"] == "fail"]
    counts = (f"{sum(r['status'] == 'pass' for r in rows)} pass, {len(failed)} fail, "
              f"{sum(r['status'] == 'info' for r in rows)} information")
    if not failed:
        return f"checks: {counts}"
    errors = sorted(((e, r["label"]) for r in failed for e in gated_errors([r])),
                    key=lambda pair: -pair[0].ratio)
    named = "; ".join(f"{label}: {e.describe()}" for e, label in errors[:SUMMARY_FAILURES])
    more = (f"; and {len(errors) - SUMMARY_FAILURES} more" if len(errors) > SUMMARY_FAILURES
            else "")
    return f"FAIL: checks: {counts}: {named}{more}"


def _paper_scenarios(args):
    """The paper's crane runs `gpme simulate` makes without --model: the cases of --case
    (the flexible arm with --n-rfe segments, default the paper's), started on the
    constraints with --on-manifold and in the arm's gravity sag with --static-arm
    (gpme_io.scenario.crane_scenario)."""
    n_rfe = paper.DEFAULT_N_RFE if args.n_rfe is None else args.n_rfe
    cases = list(paper.CASES) if args.case == "both" else [args.case]
    return [crane_scenario(0 if case == "rigid" else n_rfe, on_constraints=args.on_manifold,
                           static_arm=args.static_arm) for case in cases]


def _simulate_scenarios(args, scenarios):
    """Run each scenario (its step chosen by crosscheck.accurate_step unless --dt or another
    method is given), print its checks and write its history and figures, and the figures a
    built-in example adds (the paper's, gpme_io.example_outputs); returns ({file: path},
    check rows)."""
    from gpme_io.example_outputs import write_example_outputs
    from gpme_io.runs import estimate_scenario, simulate_scenario, write_run_outputs
    paths, rows, runs = {}, [], []
    for scenario in scenarios:
        t_end = args.t_end if args.t_end is not None else scenario.t_run(args.quick)
        print(f"simulating {scenario.name}: {scenario.model.n_coordinates} coordinates, "
              f"{scenario.system.n_constraints} constraints, t_end = {t_end:g} s ...", flush=True)

        def run(dt, scenario=scenario, t_end=t_end):
            df = simulate_scenario(scenario, t_end=t_end, dt=args.dt if dt is None else dt,
                                   method=args.method, progress=not args.no_progress,
                                   before_run=run_budget(scenario.name, args.force),
                                   max_wall_s=wall_limit(args.force))
            print(f"  wall time {df.attrs['wall_time_s']:.1f} s", flush=True)
            return df

        def estimate(dt, scenario=scenario, t_end=t_end):
            return estimate_scenario(scenario, t_end=t_end, dt=dt, method="RK4")

        method = args.method or scenario.integrator
        df, model_rows = _run_checked(
            scenario.name, run, partial(simulate_rows, scenario), estimate,
            accurate=method == "RK4" and args.dt is None, force=args.force,
            start=paper.step_name(scenario) or "the model's step")
        rows += model_rows
        runs.append((scenario, df))
        paths.update(write_run_outputs(scenario, df, args.out))
    paths.update(write_example_outputs(runs, args.out))
    return paths, rows


def simulate_problems(args) -> list:
    """Every problem of `gpme simulate`'s options, found from the values alone (no model is
    built): one message lists them all."""
    problems = [p for p in (output_dir_problem(args.out),) if p]
    finite = float("inf")
    dt_ok = args.dt is None or 0 < args.dt < finite
    t_ok = args.t_end is None or 0 < args.t_end < finite
    if not dt_ok:
        problems.append(f"--dt must be a positive, finite step in s, got {args.dt!r}")
    if not t_ok:
        problems.append(f"--t-end must be a positive, finite duration in s, got {args.t_end!r}")
    if dt_ok and t_ok and args.dt is not None and args.t_end is not None \
            and args.dt > args.t_end:
        problems.append(f"--dt {args.dt!r} s is longer than --t-end {args.t_end!r} s; give "
                        "a step no longer than the run")
    if args.n_rfe is not None and not 0 <= args.n_rfe <= MAX_SEGMENTS:
        problems.append(f"--n-rfe must be 0 (rigid arm) or a number of RFEM segments up to "
                        f"{MAX_SEGMENTS} (gpme_core.rfem.MAX_SEGMENTS), got {args.n_rfe}")
    if args.case == "rigid" and (args.static_arm or args.n_rfe is not None):
        problems.append("--static-arm and --n-rfe set the flexible arm; --case rigid has none "
                        "(use --case flexible or both)")
    if args.model and (args.case != "both" or args.static_arm or args.on_manifold or
                       args.n_rfe is not None):
        problems.append("--case, --n-rfe, --on-manifold and --static-arm choose the built-in "
                        "crane runs; with --model the model file sets them")
    return problems


def _simulate(args):
    problems = simulate_problems(args)
    if problems:
        return _error("; ".join(problems) if len(problems) == 1
                      else f"{len(problems)} problems:\n  " + "\n  ".join(problems))
    if args.dt is not None and args.method not in (None,) + FIXED_STEP_METHODS:
        print(f"note: --dt {args.dt:g} s is the largest step of --method {args.method} "
              "(its steps follow its error control)", flush=True)
    try:
        with exclusive_output(args.out):
            scenarios = load_model_files(args.model) if args.model else _paper_scenarios(args)
            paths, rows = _simulate_scenarios(args, scenarios)
    except OutputWriteError:
        raise                        # exit 74, gpme.cli.main
    except GpmeError as exc:
        return _error(exc)
    for p in paths.values():
        print(f"wrote {p}")
    print(checks_summary(rows), flush=True)
    return EXIT_FAILED if any(r["status"] == "fail" for r in rows) else EXIT_OK


def _crosscheck(args):
    if args.out is not None and output_dir_problem(args.out):
        return _error(output_dir_problem(args.out))
    from crosscheck.engines import missing_message
    from crosscheck.verify import default_scenarios, estimate_runs
    if missing_message(args.engine):
        return _error(missing_message(args.engine))
    try:
        scenarios = load_model_files(args.model) if args.model else default_scenarios(
            args.engine, args.quick)
        if args.engine == "mujoco":
            from crosscheck.mujoco.names import scenario_name_problems   # MJCF names
            scenario_name_problems(scenarios)
        estimate_runs(scenarios, args.quick, args.force)
    except OutputWriteError:
        raise                        # exit 74, gpme.cli.main
    except GpmeError as exc:
        return _error(exc)
    check = import_module(f"crosscheck.{args.engine}.check")
    out = Path(args.out) if args.out else Path("reports") / time.strftime(f"{args.engine}-%Y%m%d-%H%M%S")
    try:
        with exclusive_output(out):
            df = check.run(out, scenarios, quick=args.quick, progress=not args.no_progress)
    except OutputWriteError:
        raise                        # exit 74, gpme.cli.main
    except GpmeError as exc:
        return _error(exc)
    from crosscheck.reports.rows import normalise, other_rows, write_rows
    for engine, rows in other_rows(df, args.engine).groupby("engine"):
        write_rows(normalise(rows), out, engine)      # e.g. gpme's observed order: gpme's
    failed = df[df["status"] == "fail"] if "status" in df else df[~df["passed"].astype(bool)]
    print(f"{len(df)} comparisons, {len(failed)} failed; report in {out}")
    if len(failed):
        print(failed[["model", "quantity", "case", "entry", "abs_error", "rel_error"]]
              .head(20).to_string(index=False))
    return EXIT_FAILED if len(failed) else EXIT_OK


def _verify(args):
    from gpme import verify_command
    problems = [p for p in (output_dir_problem(args.out),) if p]
    if args.keep is not None and args.keep < 1:
        problems.append(f"--keep must be at least 1 (the run just made), got {args.keep}")
    if args.workers < 1:
        problems.append(f"--workers must be at least 1 (1: the steps one after another in "
                        f"this process), got {args.workers}")
    return verify_command.main(args, problems)   # listed with the flags' and files' problems


def _sweep(args):
    from gpme_study import command
    return command.main(args)


def _model_option(parser, many=True):
    parser.add_argument("--model", action="append", default=[], metavar="FILE",
                        help="TOML model file (docs/models.md)" +
                             ("; repeat for several" if many else "") +
                             " (default: the paper's crane)")


def build_parser():
    parser = argparse.ArgumentParser(prog="gpme", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="run a model (default: the paper's crane) and write "
                                          "CSV histories and figures; its checks printed, exit "
                                          "status 1 when one fails",
                         description="Run each model (default: the paper's crane), write its "
                                     "history and figures, and judge the run by its own checks "
                                     "(constraints after the Baumgarte transient, energy "
                                     "balance).  Exit status: 0 every check passes or is "
                                     "information, 1 a check failed (one closing line names "
                                     "them), 2 bad input.")
    _model_option(sim)
    sim.add_argument("--case", choices=("rigid", "flexible", "both"), default="both",
                     help="built-in crane only")
    sim.add_argument("--n-rfe", type=int, default=None,
                     help="built-in crane only: RFEM segments of the flexible arm (default 3)")
    sim.add_argument("--t-end", type=float, default=None,
                     help="s (default: the model file's t_end; the crane: 10)")
    sim.add_argument("--quick", action="store_true",
                     help="the model file's quick_t_end (the crane: 2 s)")
    sim.add_argument("--dt", type=float, default=None,
                     help="RK4 step in s, used as given (refused above the stability limit); "
                          "default: the model file's (else half the stability limit; the "
                          "crane: the paper's) halved until the run's own checks pass, at "
                          f"most {MAX_STEP_HALVINGS} times (docs/runs.md); RadauIIA's fixed "
                          "step (default 1 ms); "
                          "with an adaptive --method its largest step")
    sim.add_argument("--method", choices=METHODS,
                     default=None,
                     help="RK4 (explicit, fixed step), RadauIIA (implicit order 5, fixed "
                          "step, default 1 ms: for flexible models whose stiff RFEM modes "
                          "hold RK4 to tiny steps), or SciPy's adaptive RK45, DOP853, Radau")
    sim.add_argument("--on-manifold", action="store_true",
                     help="built-in crane only: start on the constraints")
    sim.add_argument("--static-arm", action="store_true",
                     help="built-in crane only: start the flexible arm in its gravity sag")
    sim.add_argument("--out", default="reports/simulate", help="output directory")
    sim.add_argument("--force", action="store_true",
                     help=f"run even when the estimate (printed before each run) is above "
                          f"{MAX_WALL_S / 3600:g} h or {MAX_CSV_BYTES / 1e9:g} GB of history")
    sim.add_argument("--no-progress", action="store_true")
    sim.set_defaults(func=_simulate)
    cc = sub.add_parser("crosscheck", help="compare gpme with one engine: Pinocchio, MuJoCo, "
                                           "Drake or Exudyn (the last two optional extras)")
    cc.add_argument("engine", choices=("pinocchio", "mujoco", "drake", "exudyn", "continuum"))
    _model_option(cc)
    cc.add_argument("--quick", action="store_true", help="CI-sized run")
    cc.add_argument("--out", default=None, help="report directory (default reports/<engine>-<time>)")
    cc.add_argument("--force", action="store_true",
                    help=f"run even when a gpme run is estimated above {MAX_WALL_S / 3600:g} h "
                         f"or {MAX_CSV_BYTES / 1e9:g} GB of history")
    cc.add_argument("--no-progress", action="store_true")
    cc.set_defaults(func=_crosscheck)
    ver = sub.add_parser("verify", help="the whole verification with HTML/CSV reports")
    _model_option(ver)
    ver.add_argument("--quick", action="store_true", help="CI-sized run")
    ver.add_argument("--only", choices=("gpme", "paper", "pinocchio", "mujoco", "drake",
                                        "exudyn", "continuum"), default=None,
                     help="one step only ('paper' is the gpme step of the default crane)")
    ver.add_argument("--out", default="reports", help="reports root directory")
    ver.add_argument("--keep", type=int, default=None, metavar="N",
                     help="after the run, keep only the N newest runs in --out (default: "
                          "all); partial directories of dead runs are always removed")
    ver.add_argument("--force", action="store_true",
                     help=f"run even when a gpme run is estimated above "
                          f"{MAX_WALL_S / 3600:g} h or {MAX_CSV_BYTES / 1e9:g} GB of history")
    ver.add_argument("--junit-xml", default=None, metavar="PATH",
                     help="also write the checks as JUnit XML (one testcase per check; "
                          "failures, information checks as skipped, crashed steps as "
                          "errors) for CI test reports (docs/ci.md)")
    ver.add_argument("--summary-md", default=None, metavar="PATH",
                     help="also write a short markdown summary (verdict, counts, failed "
                          "checks, changes since the previous run) for a CI job summary")
    ver.add_argument("--compare-to", default=None, metavar="DIR",
                     help="report directory (or its summary.json) to list changes against "
                          "(default: the run --out/latest points at before this run)")
    ver.add_argument("--workers", type=int, default=os.cpu_count() or 1, metavar="N",
                     help="run the steps at once on a local Dask cluster of N worker "
                          "processes (default: one per core); 1 runs them one after another "
                          "in this process (crosscheck.step_pool)")
    ver.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="run the steps on an existing Dask scheduler instead, e.g. "
                          "tcp://10.0.0.5:8786 (its workers must import the same gpme)")
    ver.add_argument("--no-progress", action="store_true")
    ver.set_defaults(func=_verify)
    sw = sub.add_parser("sweep", help="parameter sweep on a Dask cluster: table, heat maps, "
                                      "safe region (docs/sweep.md)")
    add_sweep_arguments(sw)
    sw.set_defaults(func=_sweep)
    return parser


def console_main():
    """Entry point of the `gpme` script and `python -m gpme.cli`: main, then exit with its
    status, late signals ignored."""
    sys.exit(main(ignore_late_signals=True))


def main(argv=None, ignore_late_signals=False):
    """Run one command; returns its exit status (docs/ci.md): 0 passed, 1 a check failed,
    2 bad input, 130 Ctrl-C, 128 + the signal number for SIGTERM (143) and SIGHUP (129)."""
    args = build_parser().parse_args(argv)
    console_log.configure()          # what the library modules log is shown (INFO, stdout)
    signals.install()
    try:
        code = args.func(args)
        signals.raise_if_pending()      # a signal swallowed somewhere is still an interruption
        if ignore_late_signals:
            signals.ignore_late_signals()
        return code
    except Terminated as exc:
        print(f"terminated ({signal.Signals(exc.signum).name}); finished files kept, "
              "partial output removed", file=sys.stderr)
        return signals.exit_status(exc)
    except KeyboardInterrupt as exc:
        print("interrupted; finished files kept, partial output removed", file=sys.stderr)
        return signals.exit_status(exc)
    except OutputWriteError as exc:  # disk full, read-only, a folder removed: one line
        print(f"error: {exc} (nothing half-written is left in place of a file; a verify "
              "report is not published and 'latest' is unchanged)", file=sys.stderr)
        return EXIT_WRITE
    except BrokenPipeError:          # output piped into a reader that stopped (| head)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except Exception as exc:
        if not signals.pending():
            raise
        # an error after a signal is the signal's doing (e.g. numba's compiler left
        # without its object code): the command ends as interrupted
        first = signals.pending()[0]
        print(f"terminated ({signal.Signals(first).name}, then {type(exc).__name__}); "
              "finished files kept, partial output removed", file=sys.stderr)
        return signals.exit_status(signals.interruption(first))
    finally:
        signals.cancel_delivery()


if __name__ == "__main__":
    console_main()

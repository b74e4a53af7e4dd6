"""`gpme sweep`: its options (gpme_study.arguments) translated into a sweep spec (the
command line overrides what a --config file says), then the run, the table and the
plots.  Without --model (and without ``model`` in the --config file) the built-in crane is
swept; with it, the given model file (parameters are paths into it, gpme_study.model_paths).

Loaded by `gpme sweep` only (the parser takes the options from gpme_study.arguments).
"""
import json
import os
import re
import sys
from pathlib import Path

from gpme_core.echo import shown
from gpme_io.atomic import atomic_write_text
from gpme_io.out_lock import (OutputBusyError, busy_problem, exclusive_output,
                              output_dir_problem)

from .cost import estimate
from .plots import write_plots
from .runner import connect, pending_points, run_sweep
from .spec_points import SweepSpecError, read_spec_file
from .sweep_kinds import sweep_kind
from .sweep_spec import spec_from_dict

RUN_FLAGS = {"t_end": "t_end", "n_rfe": "n_rfe", "transient": "transient",
             "output_dt": "output_dt", "dt": "dt", "min_frequency": "min_frequency_hz",
             "phi_tolerance": "phi_tolerance"}
# the keys of the sweep description other options set: {attribute: key}
OTHER_FLAGS = {"plot_x": "plot.x", "plot_y": "plot.y"}
# most local worker processes per core (more only trade memory for nothing)
MAX_WORKERS_PER_CORE = 4


def _pairs(items, flag, problems):
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            problems.append(f"{flag} {shown(item)}: expected NAME=VALUE")
            continue
        out[name.strip()] = value.strip()
    return out


def spec_dict(args, problems):
    """The raw sweep dict of ``args``: the --config file's, overridden by the options;
    problems with the options themselves are appended to ``problems``.  Returns None
    (with the problem appended) when the --config file cannot be read."""
    try:
        data = read_spec_file(args.config) if args.config else {}
    except SweepSpecError as exc:
        problems += exc.problems
        data, args_only = {}, True
    else:
        args_only = False
    model = getattr(args, "model", None)
    if model:
        data["model"] = str(Path(model).resolve())
    elif isinstance(data.get("model"), str):     # relative to the sweep file
        data["model"] = str((Path(args.config).parent / data["model"]).resolve())
    if args.mode:
        data["mode"] = args.mode
    elif args.point and "mode" not in data:
        data["mode"] = "list"
    if args.param:
        data["parameters"] = {**(data.get("parameters") or {}),
                              **_pairs(args.param, "--param", problems)}
    if args.point:
        data["points"] = [_pairs(p, "--point", problems) for p in args.point]
    if args.samples is not None:
        data["samples"] = args.samples
    if args.seed is not None:
        data["seed"] = args.seed
    run = dict(data.get("run") or {})
    for attr, key in RUN_FLAGS.items():
        if getattr(args, attr) is not None:
            run[key] = getattr(args, attr)
    if getattr(args, "on_constraints", None):
        run["on_constraints"] = True
    if run:
        data["run"] = run
    if args.limit:
        data["limits"] = {**(data.get("limits") or {}), **_pairs(args.limit, "--limit", problems)}
    plot = dict(data.get("plot") or {})
    if args.plot_x:
        plot["x"] = args.plot_x
    if args.plot_y:
        plot["y"] = args.plot_y
    if plot:
        data["plot"] = plot
    cores = os.cpu_count() or 1
    if args.workers is not None and args.workers < 1:
        problems.append(f"--workers must be >= 1, got {args.workers}")
    elif args.workers is not None and args.workers > MAX_WORKERS_PER_CORE * cores:
        problems.append(f"--workers {args.workers}: at most {MAX_WORKERS_PER_CORE} x the "
                        f"{cores} cores of this machine ({MAX_WORKERS_PER_CORE * cores}); "
                        "a larger cluster is given with --scheduler")
    if args.workers is not None and args.scheduler:
        problems.append("--workers sizes the local cluster; it cannot be used with --scheduler")
    if getattr(args, "in_process", False) and (args.scheduler or args.workers is not None):
        problems.append("--in-process runs without Dask; it cannot be used with --scheduler "
                        "or --workers")
    return None if args_only else data


def out_dir_problem(out):
    """Why ``out`` cannot be the sweep's output directory (None when it can), found
    without creating anything (gpme_io.out_lock.output_dir_problem, and its points/ and plots/
    must be directories if present)."""
    problem = output_dir_problem(out, example="reports/sweep")
    if problem:
        return problem
    for sub in ("points", "plots"):
        if (Path(out) / sub).exists() and not (Path(out) / sub).is_dir():
            return f"--out {str(out)!r}: {str(Path(out) / sub)!r} exists and is not a directory"
    return None


def _name_flags(problems, args):
    """The problems with the option that set a key named next to it: 'run.t_end' ->
    'run.t_end (--t-end)'."""
    keys = {f"run.{key}": attr for attr, key in RUN_FLAGS.items()}
    keys.update({key: attr for attr, key in OTHER_FLAGS.items()})
    given = {key: "--" + attr.replace("_", "-") for key, attr in keys.items()
             if getattr(args, attr, None) is not None}
    out = []
    for p in problems:
        for key, flag in given.items():
            # 'run.dt (0.01 s)' -> 'run.dt (--dt, 0.01 s)'; 'run.dt must' -> 'run.dt (--dt) must'
            p = re.sub(rf"(?<![\w.]){re.escape(key)}(?![\w.])( \()?",
                       lambda m, k=key, f=flag: f"{k} ({f}, " if m.group(1) else f"{k} ({f})",
                       p, count=1)
        out.append(p)
    return out


def main(args):
    """Run `gpme sweep`; exit status 0, 1 if a point failed unexpectedly (status 'error'),
    2 for an invalid sweep description, an unusable --out or --scheduler, or a sweep
    whose estimate is above the limits of gpme_study.cost (without --force)."""
    problems = []
    out_problem = out_dir_problem(args.out)
    if out_problem:
        problems.append(out_problem)
    else:
        problems += [p for p in (busy_problem(args.out),) if p]   # before the estimate
    spec, data = None, None
    data = spec_dict(args, problems)
    if data is not None:          # the --config file was read: the whole description
        try:
            spec = spec_from_dict(data)
        except SweepSpecError as exc:
            problems += _name_flags(exc.problems, args)
    client = None
    if args.scheduler and not getattr(args, "in_process", False) and args.workers is None:
        client, problem = connect(args.scheduler)
        if problem:
            problems.append(problem)
    if problems:
        if client is not None:
            client.close()
        print(f"error: {SweepSpecError(problems)}", file=sys.stderr)
        return 2
    try:
        return _run(args, spec, data, client)
    finally:
        if client is not None:
            client.close()


def _run(args, spec, data, client):
    out = Path(args.out)
    in_process = getattr(args, "in_process", False)
    report = (lambda line: None) if args.quiet else (lambda line: print(line, flush=True))
    _, pending = pending_points(spec, out, args.retry_errors)
    if in_process:
        workers = 1
    elif client is not None:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
    else:
        workers = args.workers or os.cpu_count() or 1
    cost = estimate(spec, list(pending.values()), workers,
                    dask=bool(pending) and not in_process, report=report)
    report(cost.summary())
    over = cost.problems()
    if over and not args.force:
        print(f"error: {SweepSpecError(over)}", file=sys.stderr)
        return 2
    for line in over:
        report(f"--force given, running although {line}")
    try:
        with exclusive_output(out):       # one sweep writing to one --out at a time
            return _sweep_and_report(args, spec, data, client, out, report, in_process)
    except OutputBusyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


def _sweep_and_report(args, spec, data, client, out, report, in_process):
    atomic_write_text(out / "sweep_spec.json", json.dumps(data, indent=1, default=str))
    table = run_sweep(spec, out, scheduler=args.scheduler, n_workers=args.workers,
                      retry_errors=args.retry_errors, report=report, in_process=in_process,
                      client=client, terminal=sys.stdout.isatty())
    paths = write_plots(table, out, spec.plot_x, spec.plot_y, spec.limits,
                        **sweep_kind(spec).plot_options(spec))
    counts = table["status"].value_counts().to_dict()
    print(f"{len(table)} points: {counts}; computed {table.attrs['computed']} in "
          f"{table.attrs['wall_time_s']:.1f} s; table {out / 'results.csv'} (+ .parquet)")
    for p in paths.values():
        print(f"wrote {p}")
    return 1 if counts.get("error", 0) else 0

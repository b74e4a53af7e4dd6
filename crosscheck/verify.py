"""`gpme verify [--model FILE ...]`: each model's own run and every crosscheck in one command.

Steps: gpme (each scenario's run and its checks; without --model the paper's two crane
runs, gpme_io.scenario.crane_scenario, run the same way, plus the paper's figures),
pinocchio (term by term and exactly realised runs), mujoco (terms, free and programmed
runs), drake (terms of a MultibodyPlant from the URDF, free runs with Drake's integrator)
and exudyn (programmed runs with the task as exact index-3 constraints); the last two are
optional extras (crosscheck.engines): when one is not installed its step is one
information row saying what to install.  Writes
reports/<run-id>/ (index.html, summary.json, summary.csv, models.json, checks/ with every
step's comparison rows and tolerances.csv.gz (crosscheck.reports.rows), pinocchio.html,
mujoco.html and their plots, plots/, runs/ with the run histories and figures, paper/ with
the paper's figures of the default crane runs; reports/README.md) and points reports/latest
at it.  The run is built in a hidden reports/.<run-id>.*.partial directory (removed if the run is
interrupted) and renamed into place only when complete, under a name no other run has
taken (two runs started in the same second get <run-id> and <run-id>-2), and `latest` is
replaced atomically, so an interrupted run leaves the previous report whole and `latest`
unchanged.  Exit status 1 when any check fails (or a step crashes), 0 otherwise.

Each run is compared with the previous one (the report `latest` pointed at when the run
started, or ``--compare-to DIR``): checks whose error/tolerance grew more than 10x, status
changes, new and vanished checks, changed versions (crosscheck.reports.run_diff); the diff
is in summary.json ("diff"), at the top of index.html and printed at the end.  For CI,
``--junit-xml PATH`` and ``--summary-md PATH`` write the JUnit XML and a markdown job
summary of the run (crosscheck.reports.junit, crosscheck.reports.summary_md; docs/ci.md).
"""
import json
import logging
import shutil
import time
from pathlib import Path

import pandas as pd

from gpme_io import dask_cluster
from gpme_io.atomic import atomic_write_text
from gpme_io.budget import run_budget
from gpme_io.runs import estimate_scenario

from . import run_store, step_pool
from .compare import CRASH_QUANTITY
from .reports import run_diff, strict_json
from .reports.index_page import write_index
from .reports.junit import write_junit_xml
from .reports.rows import check_name, normalise, write_rows
from .reports.summary_md import write_summary_md
from .reports.tables import summarise, write_csv
from .run_checks import run_warnings
from .verify_meta import environment
from .verify_steps import STEPS, default_scenarios

STEP_ALIASES = {"paper": "gpme"}
# what verify is doing, one line per step and run (shown by the `gpme` command's logging
# setup, gpme/console_log.py; silent when called as a library)
log = logging.getLogger("gpme.verify")


def _merge_prerequisites(staging, tables, prerequisites):
    """Add the rows other steps made about another engine's own runs (gpme's observed order
    in the Pinocchio, MuJoCo, Drake and Exudyn steps) to that engine's table, once per
    (model, quantity, case), and rewrite its rows in the report."""
    extra = [df for df in prerequisites if len(df)]
    if not extra:
        return
    merged = pd.concat(extra, ignore_index=True)
    for engine, rows in merged.groupby("engine", sort=False):
        base = tables.get(engine)
        table = rows if base is None or not len(base) else pd.concat([base, rows],
                                                                      ignore_index=True)
        table = table.drop_duplicates(subset=["engine", "model", "quantity", "case"],
                                      keep="first", ignore_index=True)
        tables[engine] = table
        write_rows(normalise(table), staging, engine)


def _report_crash(staging, step, crash):
    """One line on the console; the traceback of an unexpected exception (not a gpme input
    or run error, whose message says it all) into <run>/<step>_crash.txt (``crash``:
    crosscheck.verify_steps.Crash)."""
    if crash.input_error:
        log.info(f"[{step}] stopped: {crash.message}")
        return
    path = staging / f"{step}_crash.txt"
    atomic_write_text(path, crash.traceback)
    log.info(f"[{step}] crashed: {crash.kind}: {crash.message} (traceback in "
             f"{path.name} of the report; please report it as a gpme bug)")


def _models_record(scenarios):
    """What each scenario is made of, for models.json and the index page."""
    out = []
    for s in scenarios:
        out.append({"name": s.name, "source": str(s.source) if s.source else "built in",
                    "urdf": str(s.urdf) if s.urdf else None,
                    "chain": list(s.chain) if s.chain else None,
                    "frozen": dict(s.frozen), "coordinates": len(s.model.coordinate_names),
                    "flexible_links": [f"{f.name} ({f.n_segments} segments)"
                                       for f in s.model.flexible_links if f.n_segments],
                    "constraints": list(s.system.constraint_names),
                    "dependent": list(s.system.dependent or ()),
                    "notes": list(s.notes)})
    return out


def _model_names(scenarios, quick, only=None):
    """{"coordinates": set, "constraints": set}: the names of every model the run compared
    (the index's matrix groups quantities that differ only in one of them)."""
    if scenarios is None:
        scenarios = [s for step in STEPS if not only or step == only
                     for s in default_scenarios(step, quick)]
    return {"coordinates": {c for s in scenarios for c in s.model.coordinate_names},
            "constraints": {c for s in scenarios for c in s.system.constraint_names}}


def run_verify(root, quick=False, only=None, progress=True, run_id=None, scenarios=None,
               keep=None, max_wall_s=None, compare_to=None, workers=1, scheduler=None):
    """Run the verification; returns (run_dir, summary DataFrame, all rows DataFrame).

    scenarios: gpme_io.scenario.Scenario list (``--model`` files); None runs the paper's
    crane (its two runs with the paper's figures, and the default crane cases per engine).
    keep     : after publishing, keep only this many newest runs in root (None: all).
    max_wall_s: s, each gpme run stopped after this long (None: no limit).
    compare_to: report directory (or its summary.json) to diff against; None: the run
    root/latest points at when this run starts.
    workers  : 1: the steps one after another in this process; more: at once on a local
               Dask cluster of that many worker processes (crosscheck.step_pool)
    scheduler: address of a running Dask scheduler to run the steps on instead (its
               workers must import the same gpme)
    Staging directories of dead runs in root are removed first.
    """
    root = Path(root)
    only = STEP_ALIASES.get(only, only)
    run_id = run_id or time.strftime("%Y%m%d-%H%M%S") + ("-quick" if quick else "")
    root.mkdir(parents=True, exist_ok=True)
    previous = run_store.previous_report(root, compare_to)
    for name in run_store.remove_dead_partials(root):
        log.info(f"removed {root / name}: the partial directory of a run that died")
    staging = run_store.claim_run_dir(root, run_id)
    try:
        result = _run_steps(root, staging, run_id, quick, only, progress, scenarios,
                            max_wall_s, previous, workers, scheduler)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    for name in run_store.prune_runs(root, keep):
        log.info(f"removed {root / name} (--keep {keep})")
    return result


def _run_steps(root, staging, run_id, quick, only, progress, scenarios, max_wall_s=None,
               previous=(None, "", None), workers=1, scheduler=None):
    start = time.perf_counter()
    tables, timings, prerequisites, part_times = {}, {}, [], {}
    record = _models_record(scenarios if scenarios is not None else
                            default_scenarios("pinocchio", quick))
    atomic_write_text(staging / "models.json", json.dumps(record, indent=1))
    steps = [step for step in STEPS if not only or step == only]

    def done(outcome):
        step = outcome.step
        tables[step], timings[step] = outcome.table, outcome.seconds
        if len(outcome.prerequisites):
            prerequisites.append(outcome.prerequisites)
        if outcome.crash is not None:
            _report_crash(staging, step, outcome.crash)
        failed = int(failed_checks(tables[step]).sum())
        log.info(f"[{step}] {len(tables[step])} comparisons, {failed} failed, "
                 f"{timings[step]:.1f} s")

    if scheduler or (workers > 1 and len(steps) > 1):
        previous_run = (previous[0] or {}).get("run") or {}
        with dask_cluster.client_for(scheduler, workers) as client:
            n_workers, shared = step_pool.run_on_cluster(
                client, steps, staging, scenarios, quick, max_wall_s, done,
                previous_run.get("step_times_s"), previous_run.get("part_times_s"),
                part_times)
            execution = (f"{len(steps)} steps in parallel on {n_workers} Dask workers "
                         f"({scheduler or 'local cluster'})")
    else:
        shared = step_pool.run_in_process(steps, staging, scenarios, quick, progress,
                                          max_wall_s, done)
        execution = "steps one after another in one process"
    execution += (f"; gpme runs the engines compare against: {shared['computed']} computed, "
                  f"{shared['shared']} reused from another step")
    log.info(f"[verify] {execution}")
    shutil.rmtree(staging / step_pool.SHARED_RUNS_DIR, ignore_errors=True)
    tables = {step: tables[step] for step in steps}          # the report's order, not the finish order
    timings = {step: timings[step] for step in steps}
    _merge_prerequisites(staging, tables, prerequisites)
    # engines without sections (Pinocchio) compare terms; keep gated and ungated cases of
    # one quantity apart (MuJoCo's programmed runs vs its ungated off-manifold start)
    rows = normalise(pd.concat(tables.values(), ignore_index=True))
    summary = summary_of(rows)
    warnings = run_warnings(rows.to_dict("records")) if "reason" in rows.columns else []
    for warning in warnings:
        log.warning(warning)
    meta = environment(quick=quick, only=only, run_id=run_id,
                       wall_time_s=time.perf_counter() - start, step_times_s=timings,
                       part_times_s=part_times,
                       execution=execution)
    write_csv(summary, staging / "summary.csv")
    document = {
        "run": meta,
        "passed": not bool(failed_checks(summary).any()),
        "models": record,
        "warnings": warnings,
        "checks": [_check_record(r) for r in summary.to_dict("records")]}
    previous_doc, source, note = previous
    document["diff"] = run_diff.diff_summaries(previous_doc, document, source=source, note=note)
    atomic_write_text(staging / "summary.json", strict_json.dumps(document))
    write_index(staging, summary, rows, meta, record, diff=document["diff"],
                names=_model_names(scenarios, quick, only))
    final = run_store.publish_run(root, staging, run_id)
    return final, summary, rows


def summary_of(rows):
    """One row per check (engine, section, model, quantity) of the normalised comparison
    rows: crosscheck.reports.tables.summarise plus ``check`` (its name) and
    ``error_over_tolerance`` / ``tolerance`` of its worst row (the measure of the diff)."""
    keys = ["engine", "section", "model", "quantity"]
    summary = summarise(rows, keys=keys)
    summary.insert(0, "check", [check_name(r.engine, r.section, r.model, r.quantity)
                                for r in summary.itertuples()])
    return summary.merge(run_diff.check_ratios(rows, keys=keys), on=keys, how="left",
                         validate="one_to_one")


def _check_record(r):
    """summary.json's entry of one check (a summary row as a dict)."""
    return {"name": r["check"], "engine": r["engine"], "section": r["section"],
            "model": r["model"], "quantity": r["quantity"], "n_compared": int(r["n_compared"]),
            "n_fail": int(r["n_fail"]),
            "worst_abs_error": _num(r["worst_abs_error"]),
            "value": _num(r["value"]) if check_status(r) == "info" else None,
            "worst_rel_error": _num(r["worst_rel_error"]),
            "worst_case": _text(r["worst_case"]), "worst_entry": _text(r["worst_entry"]),
            "tol_abs": _num(r["tol_abs"]), "tol_rel": _num(r["tol_rel"]),
            "tolerance": _num(r["tolerance"]),
            "error_over_tolerance": _num(r["error_over_tolerance"]),
            "status": check_status(r), "reason": r["reason"],
            "crashed": r["quantity"] == CRASH_QUANTITY and r["model"] == "-"}


def _text(v):
    return None if v is None or (isinstance(v, float) and v != v) else str(v)


def failed_checks(df):
    """Boolean Series: rows (or checks) that failed."""
    if "status" in df.columns and df["status"].notna().all():
        return df["status"] == "fail"
    return ~df["passed"].astype(bool)


def check_status(record):
    status = record.get("status")
    if isinstance(status, str):
        return status
    return "pass" if record["passed"] else "fail"


def _num(v):
    v = float(v)
    return None if v != v else v  # NaN -> null in JSON


def estimate_runs(scenarios, quick, force):
    """Print the estimated cost of the gpme runs of a verification before any work, and
    refuse (gpme_io.budget.BudgetError) one above the limits unless ``force``; an input problem
    found on the way (an unstable step in a model file, say) is raised here too."""
    log.info("estimated cost of the gpme runs (the engine steps take about as long again):")
    for scenario in scenarios if scenarios is not None else default_scenarios("gpme", quick):
        log.info(f"  {scenario.name}, {scenario.t_run(quick):g} s:")
        run_budget(scenario.name, force)(estimate_scenario(scenario, quick=quick))


def write_ci_outputs(run_dir, document, junit_xml=None, summary_md=None):
    """Write the JUnit XML and the markdown summary of the run in ``run_dir`` (``document``:
    its summary.json); returns the paths written."""
    written = []
    if junit_xml is not None:
        written.append(write_junit_xml(junit_xml, document, report_dir=str(run_dir)))
    if summary_md is not None:
        written.append(write_summary_md(summary_md, document,
                                        index_path=str(Path(run_dir) / "index.html")))
    return written

"""`gpme verify`: the paper's two simulations and every crosscheck in one command.

Writes reports/<run-id>/ (index.html, paper.csv, pinocchio.csv/.html, mujoco.csv/.html,
summary.json, summary.csv, paper/ with the run histories and figures) and points
reports/latest at it.  The run is built in reports/.<run-id>.partial and renamed into
place only when complete, and `latest` is replaced atomically, so an interrupted run
leaves the previous report whole and `latest` unchanged.  Exit status 1 when any check
fails (or a step crashes), 0 otherwise.
"""
import json
import os
import shutil
import time
import traceback
from pathlib import Path

import pandas as pd

from .reports.index_page import write_index
from .reports.tables import atomic_write_text, summarise, write_csv
from .verify_meta import environment

STEPS = ("paper", "pinocchio", "mujoco")
QUICK_T_END = 2.0      # s of programmed motion in --quick
FULL_T_END = 10.0


def _say(msg):
    print(msg, flush=True)


def _paper_step(run_dir, quick, progress):
    from gpme_examples import paper
    from .paper_checks import paper_rows
    t_end = QUICK_T_END if quick else FULL_T_END
    runs = {}
    for case in ("rigid", "flexible"):
        _say(f"  paper: {case} crane, {t_end:g} s of programmed motion (RK4, dt = "
             f"{paper.DEFAULT_DT[case]:g} s)")
        runs[case] = paper.run_case(case, t_end=t_end, progress=progress)
        _say(f"    wall time {runs[case].attrs['wall_time_s']:.1f} s")
    paper.write_outputs(runs, run_dir / "paper")
    df = pd.DataFrame(paper_rows(runs))
    df["section"] = "paper"
    write_csv(df, run_dir / "paper.csv")
    return df, runs


def _engine_step(name, run_dir, quick, progress):
    module = __import__(f"crosscheck.{name}.check", fromlist=["run"])
    return module.run(run_dir, quick=quick, progress=progress)


def _crash_row(step, exc):
    return pd.DataFrame([{
        "engine": step if step != "paper" else "gpme", "model": "-", "quantity": "step crashed",
        "case": "-", "entry": type(exc).__name__, "gpme_value": float("nan"),
        "engine_value": float("nan"), "abs_error": float("inf"), "rel_error": float("nan"),
        "scale": float("nan"), "tol_abs": 0.0, "tol_rel": 0.0, "passed": False,
        "reason": f"{exc}"[:500]}])


def run_verify(root, quick=False, only=None, progress=True, run_id=None):
    """Run the verification; returns (run_dir, summary DataFrame, all rows DataFrame)."""
    root = Path(root)
    run_id = run_id or time.strftime("%Y%m%d-%H%M%S") + ("-quick" if quick else "")
    staging = root / f".{run_id}.partial"
    if staging.exists():
        shutil.rmtree(staging)
    staging.mkdir(parents=True)
    start = time.perf_counter()
    tables, runs, timings = {}, None, {}
    for step in STEPS:
        if only and step != only:
            continue
        _say(f"[{step}] ...")
        t0 = time.perf_counter()
        try:
            if step == "paper":
                tables[step], runs = _paper_step(staging, quick, progress)
            else:
                tables[step] = _engine_step(step, staging, quick, progress)
        except Exception as exc:  # a crashed step is a failed check, reported in full
            traceback.print_exc()
            tables[step] = _crash_row(step, exc)
        timings[step] = time.perf_counter() - t0
        failed = int((~tables[step]["passed"].astype(bool)).sum())
        _say(f"[{step}] {len(tables[step])} comparisons, {failed} failed, "
             f"{timings[step]:.1f} s")
    rows = pd.concat(tables.values(), ignore_index=True)
    if "section" not in rows.columns:
        rows["section"] = None
    # engines without sections (Pinocchio) compare terms; keep gated and ungated cases of
    # one quantity apart (MuJoCo's programmed runs vs its ungated off-manifold start)
    rows["section"] = rows["section"].fillna("terms")
    summary = summarise(rows, keys=("engine", "section", "model", "quantity"))
    summary.insert(0, "check", [f"{r.engine}/{r.section}/{r.model}/{r.quantity}"
                                for r in summary.itertuples()])
    meta = environment(quick=quick, only=only, run_id=run_id,
                       wall_time_s=time.perf_counter() - start, step_times_s=timings)
    write_csv(summary, staging / "summary.csv")
    atomic_write_text(staging / "summary.json", json.dumps({
        "run": meta,
        "passed": bool(summary["passed"].all()),
        "checks": [{"name": r["check"], "engine": r["engine"], "model": r["model"],
                    "quantity": r["quantity"], "n_compared": int(r["n_compared"]),
                    "worst_abs_error": _num(r["worst_abs_error"]),
                    "worst_rel_error": _num(r["worst_rel_error"]),
                    "tol_abs": _num(r["tol_abs"]), "tol_rel": _num(r["tol_rel"]),
                    "status": "pass" if r["passed"] else "fail", "reason": r["reason"]}
                   for r in summary.to_dict("records")]}, indent=1))
    write_index(staging, summary, rows, runs, meta)
    final = root / run_id
    if final.exists():
        shutil.rmtree(final)
    os.rename(staging, final)
    _point_latest(root, run_id)
    return final, summary, rows


def _num(v):
    v = float(v)
    return None if v != v else v  # NaN -> null in JSON


def _point_latest(root, run_id):
    tmp = root / f".latest.{os.getpid()}.tmp"
    if tmp.is_symlink() or tmp.exists():
        tmp.unlink()
    os.symlink(run_id, tmp)
    os.replace(tmp, root / "latest")


def main(args):
    run_dir, summary, _ = run_verify(args.out, quick=args.quick, only=args.only,
                                     progress=not args.no_progress)
    cols = ["engine", "section", "model", "quantity", "n_compared", "worst_abs_error",
            "worst_rel_error", "passed"]
    with pd.option_context("display.width", 200, "display.max_rows", 500):
        print(summary[cols].to_string(index=False))
    n_fail = int((~summary["passed"]).sum())
    print(f"{len(summary)} checks, {n_fail} failed; report: {run_dir / 'index.html'}")
    return 1 if n_fail else 0

"""index.html of a `gpme verify` run (templates/index.html.j2).

First screen: the verdict (counts, each engine with its version, the failing checks, what
changed since the previous run), the matrix of quantities x models coloured by error /
tolerance (crosscheck.reports.matrix) and the key plots.  Below: every check, folded by
engine and model and filterable by status and text, each linked to its rows (CSV slice) and
plot; the reasons for the tolerances once, as a side table; the runs' figures and
histories; the models; the files; the run's versions and machine.

Images are linked, not embedded: each plot is stored once, as a PNG of the report.
"""
from pathlib import Path

import pandas as pd
from markupsafe import Markup

from gpme_io.atomic import atomic_write_text
from gpme_io.example_outputs import PAPER_FIGURES
from gpme_io.file_names import file_stem

from ..compare import CRASH_QUANTITY, FAIL, INFO, PASS
from .check_plots import write_spread_plots
from .html import render, table as html_table_data
from .matrix import legend, matrix_blocks
from .rows import CHECKS_DIR, TOLERANCES_FILE, check_id, slice_path
from .run_diff import diff_lines, headline
from .tables import checks_worst_first

ENGINE_TITLES = {"gpme": "gpme alone: each model's run", "pinocchio": "Pinocchio (term by term)",
                 "mujoco": "MuJoCo (terms and full runs)",
                 "drake": "Drake (terms of a MultibodyPlant from the URDF, free runs)",
                 "exudyn": "Exudyn (programmed runs with exact index-3 constraints)",
                 "continuum": "Model validity (RFEM links against geometrically exact beams)"}
ENGINE_VERSION_KEYS = {"gpme": "gpme", "pinocchio": "pinocchio (pin)", "mujoco": "mujoco",
                       "drake": "drake", "exudyn": "exudyn", "continuum": "exudyn"}
NOT_INSTALLED = "not installed"       # crosscheck.verify_meta's version of a missing package
MAX_FAILING_LISTED = 8
MAX_KEY_PLOTS = 3
FILE_NOTES = {
    "summary.json": "one entry per check, the run's versions, warnings and the diff",
    "summary.csv": "one row per check",
    "models.json": "what each model is made of",
    TOLERANCES_FILE: "tol_id, tol_abs, tol_rel and reason of the comparison rows (gzip CSV)",
    CHECKS_DIR: ("the comparison rows, one gzip CSV per check (checks/index.csv lists them; "
                 "all of them as one table: python -m crosscheck.reports.rows <this "
                 "directory> [engine])"),
    "plots": "spread of each check group's error / tolerance",
    "pinocchio.html": "the Pinocchio crosscheck's own page",
    "mujoco.html": "the MuJoCo crosscheck's own page",
    "drake.html": "the Drake crosscheck's own page",
    "exudyn.html": "the Exudyn crosscheck's own page",
    "urdf": "the URDFs written for Pinocchio (drake/: those Drake read)",
    "paper": "the paper's figures of the crane's runs (their histories are in runs/)",
    "runs": "each model's run: histories and figures",
}


def _fmt(v, digits=3):
    if v is None or v != v:
        return "-"
    return f"{v:.{digits}g}" if 1e-3 <= abs(v) < 1e5 or v == 0 else f"{v:.{digits - 1}e}"


def diff_section(diff):
    """The "against the run before this one" section (HTML) of summary.json's ``diff``
    (crosscheck.reports.run_diff): one headline, then the lists, each capped, and the
    definition of the measure folded."""
    if not diff:
        return Markup("")
    if diff.get("previous") is None:
        return Markup(render("diff.html.j2", line=diff.get("note") or
                             "no previous run to compare with", items=[], definition=None))
    items = [line.strip() for line in diff_lines(diff, limit=10)[1:]]
    return Markup(render("diff.html.j2", line=headline(diff), items=items,
                         definition=diff.get("definition", "")))


def _failure(r):
    """What went wrong in a failed check (a summary row as a dict), in one line."""
    if r["quantity"] == CRASH_QUANTITY:
        return f"the step crashed: {r['reason']}"
    return (f"error {_fmt(r['worst_abs_error'])} > tolerance {_fmt(r['tolerance'])} "
            f"(x{_fmt(r['error_over_tolerance'])}), at {r['worst_case']} {r['worst_entry']}")


def _status_counts(summary):
    return {st: int((summary["status"] == st).sum()) for st in (FAIL, PASS, INFO)}


def _verdict(summary, rows, meta, diff):
    counts = _status_counts(summary)
    ok = counts[FAIL] == 0
    failing = summary[summary["status"] == FAIL]
    listed = [{"id": check_id(r["check"]), "name": r["check"], "detail": _failure(r)}
              for r in failing.head(MAX_FAILING_LISTED).to_dict("records")]
    engines = []
    for engine, g in summary.groupby("engine", sort=False):
        version = meta.get("versions", {}).get(ENGINE_VERSION_KEYS.get(engine, engine), "")
        n_fail = int((g["status"] == FAIL).sum())
        text = (f"{engine}: not installed (optional extra: pip install 'gpme[{engine}]'), "
                "not compared" if version == NOT_INSTALLED else
                f"{engine} {version}".strip() + f": {len(g)} checks, "
                + (f"{n_fail} FAILED" if n_fail else "none failed"))
        engines.append({"engine": engine, "n_fail": n_fail, "text": text})
    if diff and diff.get("previous") is not None:
        # named with its date, not "the previous run": the page is read long after, when
        # other runs have come since
        prev = diff["previous"]
        when = f" of {prev['date_utc']}" if prev.get("date_utc") else ""
        changes = headline(diff).split(": ", 1)[-1]
        changes = f"{changes} (against run {prev.get('run_id') or prev.get('source')}{when})"
    else:
        changes = (diff or {}).get("note") or "no previous run to compare with"
    mode = "quick (CI-sized)" if meta.get("quick") else "full"
    return {"ok": ok,
            "headline": (f"all {counts[PASS]} gated checks pass" if ok else
                         f"{counts[FAIL]} of {counts[FAIL] + counts[PASS]} gated checks FAILED"),
            "counts": (f"{len(summary)} checks: {counts[PASS]} pass, {counts[FAIL]} fail, "
                       f"{counts[INFO]} information only (no tolerance, never counted as a "
                       f"pass); {len(rows)} comparisons."),
            "engines": engines, "failing": listed,
            "more_failing": max(0, len(failing) - MAX_FAILING_LISTED),
            "changes": changes,
            "run": (f"{mode} run {meta.get('run_id', '')}, {meta.get('date_utc', '')}, commit "
                    f"{str(meta.get('git_commit', ''))[:12]}, {meta.get('wall_time_s', 0):.0f} s "
                    "wall.")}


def _engine_plot(run_dir, engine, section, model, spreads):
    """Relative path of the plot a check links to: the engine's own plot of that run if
    there is one, else the spread plot of its group."""
    candidates = [f"{engine}_{section}_{file_stem(model)}.png"]
    if engine == "gpme":
        candidates.append(f"runs/{file_stem(model)}_constraints.png")
    for c in candidates:
        if (run_dir / c).is_file():
            return c
    spread = spreads.get((engine, section, model))
    return str(spread) if spread else None


def _reasons(summary):
    """{reason text: id} numbered in order of first appearance, and the side table."""
    ids, table = {}, []
    for reason, g in summary.groupby("reason", sort=False):
        ids[reason] = len(ids) + 1
        table.append({"id": ids[reason], "text": reason, "n": len(g)})
    return ids, table


def _engines(run_dir, summary, spreads, reason_ids):
    out = []
    for engine, eg in summary.groupby("engine", sort=False):
        models = []
        for model, mg in eg.groupby("model", sort=False):
            checks = []
            for r in checks_worst_first(mg).to_dict("records"):
                rows_file = slice_path(r["check"])
                checks.append({
                    "id": check_id(r["check"]), "status": r["status"],
                    "section": r["section"], "quantity": r["quantity"],
                    "n_compared": int(r["n_compared"]),
                    # an information check reports its value (its "error" is 0 by
                    # construction: a smallest singular value of 0.247 is not an error 0)
                    "abs_error": (f"value {_fmt(r['value'])}" if r["status"] == INFO
                                  else _fmt(r["worst_abs_error"])),
                    "rel_error": "-" if r["status"] == INFO else _fmt(r["worst_rel_error"]),
                    "ratio": "info" if r["status"] == INFO else _fmt(r["error_over_tolerance"]),
                    "tolerance": _fmt(r["tolerance"]),
                    "reason": r["reason"], "reason_id": reason_ids[r["reason"]],
                    "rows_href": str(rows_file) if (run_dir / rows_file).is_file() else None,
                    "plot_href": _engine_plot(run_dir, engine, r["section"], model, spreads)})
            counts = _status_counts(mg)
            models.append({"model": model, "checks": checks, "open": counts[FAIL] > 0,
                           "summary": _count_text(counts)})
        links = [{"href": f, "text": f} for f in (f"{engine}.html",) if (run_dir / f).is_file()]
        if (run_dir / CHECKS_DIR / engine).is_dir():
            links.append({"href": f"{CHECKS_DIR}/{engine}/", "text": f"{CHECKS_DIR}/{engine}/ "
                          "(rows, one file per check)"})
        out.append({"engine": engine, "title": ENGINE_TITLES.get(engine, engine),
                    "summary": _count_text(_status_counts(eg)), "links": links,
                    "models": models})
    return out


def _count_text(counts):
    return (f"({counts[PASS]} pass, {counts[FAIL]} fail, {counts[INFO]} info)"
            if counts[FAIL] else f"({counts[PASS]} pass, {counts[INFO]} info)")


def _runs_section(run_dir):
    """The run histories and figures (runs/), after the paper's figures when the run had the
    paper's crane (paper/, gpme_io.example_outputs)."""
    paper, runs = run_dir / "paper", run_dir / "runs"
    if not runs.is_dir():
        return None
    figures = [{"src": f"paper/{name}", "caption": caption}
               for name, caption, _ in PAPER_FIGURES if (paper / name).is_file()]
    figures += [{"src": f"runs/{p.name}", "caption": p.stem.replace("_", " ")}
                for p in sorted(runs.glob("*.png"))]
    text = "Histories and figures of the gpme runs (columns: reports/README.md)."
    if paper.is_dir():
        text += (" The paper's crane (docs/crane.md): rigid arm and RFEM-flexible arm, "
                 "flexible support, drive torque ramp, programmed ellipse and height; the "
                 "paper's figures first.")
    return {"title": "Each model's own run", "text": text,
            "files": [{"href": f"runs/{p.name}",
                       "note": "the motion in 3D (opens offline; elastic deflection magnified "
                               "as its page says)" if p.name.endswith("_motion.html") else ""}
                      for p in sorted(runs.iterdir()) if p.suffix != ".png"],
            "figures": figures}


def _key_plots(run_dir, summary, spreads, runs):
    """The worst gated check's plot, then the run figures, at most MAX_KEY_PLOTS."""
    plots = []
    gated = summary[summary["status"] != INFO]
    if len(gated):
        worst = checks_worst_first(gated).iloc[0]
        href = _engine_plot(run_dir, worst["engine"], worst["section"], worst["model"], spreads)
        if href:
            word = "failing" if worst["status"] == FAIL else "closest to its tolerance"
            plots.append({"src": href, "caption": f"The check {word}: {worst['check']} "
                          f"(error / tolerance {_fmt(worst['error_over_tolerance'])})"})
    if runs:
        plots += [p for p in runs["figures"] if p["src"] not in {q["src"] for q in plots}]
    return plots[:MAX_KEY_PLOTS]


def _models(record):
    out = []
    for m in record:
        items = [("source", m["source"]), ("URDF", m["urdf"] or "-"),
                 ("chain (root, tip)", _chain_text(m["chain"])),
                 ("coordinates", m["coordinates"]),
                 ("frozen joints", ", ".join(f"{k} = {v:g}" for k, v in m["frozen"].items())
                  or "none"),
                 ("flexible links", ", ".join(m["flexible_links"]) or "none"),
                 ("constraints", ", ".join(m["constraints"]) or "none"),
                 ("dependent coordinates", ", ".join(m["dependent"]) or "-")]
        out.append({"name": m["name"], "facts": items, "notes": list(m["notes"])})
    return out


def _meta_items(meta):
    items = [("date", meta["date_utc"]), ("git commit", meta["git_commit"]),
             ("mode", "quick (CI-sized)" if meta.get("quick") else "full"),
             ("wall time", f"{meta['wall_time_s']:.1f} s")]
    if meta.get("execution"):
        items.append(("steps ran", meta["execution"]))
    items += [(f"{k} time", f"{v:.1f} s") for k, v in meta.get("step_times_s", {}).items()]
    items += list(meta["versions"].items())
    m = meta["machine"]
    items.append(("machine", f"{m['node']}, {m['platform']}, {m['processor']}, {m['cpus']} CPUs"))
    return items


def _files(run_dir):
    out = []
    for p in sorted(run_dir.iterdir()):
        if p.name.startswith(".") or p.name == "index.html":
            continue
        note = FILE_NOTES.get(p.name) or ("traceback of a crashed step" if p.name.endswith(
            "_crash.txt") else "plot" if p.suffix == ".png" else
            "the motion in 3D, another engine's run as a ghost (opens offline)"
            if p.name.endswith("_motion.html") else "")
        out.append({"href": p.name + ("/" if p.is_dir() else ""), "note": note})
    return out


def _benchmarks(bench_dir):
    """The latest `python -m benchmarks.bench` results beside the runs, if there are any."""
    png, evals, runs = (bench_dir / "evaluation_costs.png", bench_dir / "evaluation_costs.csv",
                        bench_dir / "run_costs.csv")
    if not (png.exists() and evals.exists() and runs.exists()):
        return None
    return {"tables": [html_table_data(pd.read_csv(evals), status_column="-"),
                       html_table_data(pd.read_csv(runs), status_column="-",
                                       left_columns=("case", "engine", "method"))],
            "figure": "../benchmarks/evaluation_costs.png"}


def write_index(run_dir, summary, rows, meta, models=(), diff=None, names=None):
    """Write run_dir/index.html (and the spread plots under run_dir/plots/) atomically.

    summary: verify's one row per check (check, engine, section, model, quantity, status,
    error_over_tolerance, tolerance, worst_*, reason); rows: all comparison rows; meta:
    verify_meta.environment(); models: models.json's
    record; diff: summary.json's diff against the previous run; names: {"coordinates":
    names, "constraints": names} of the models, to group the matrix rows."""
    run_dir = Path(run_dir)
    names = names or {}
    spreads = write_spread_plots(run_dir, rows)
    reason_ids, reasons = _reasons(summary)
    runs_section = _runs_section(run_dir)
    page = render("index.html.j2", title="gpme verification report",
                  verdict=_verdict(summary, rows, meta, diff),
                  blocks=matrix_blocks(summary, names.get("coordinates", ()),
                                       names.get("constraints", ()),
                                       titles=ENGINE_TITLES),
                  legend=legend(),
                  key_plots=_key_plots(run_dir, summary, spreads, runs_section),
                  diff_html=diff_section(diff) if diff else Markup(""),
                  n_checks=len(summary), status_counts=_status_counts(summary),
                  engines=_engines(run_dir, summary, spreads, reason_ids),
                  reasons=reasons, runs=runs_section, models=_models(models),
                  files=_files(run_dir), meta_items=_meta_items(meta),
                  benchmarks=_benchmarks(run_dir.parent / "benchmarks"))
    atomic_write_text(run_dir / "index.html", page)


def _chain_text(chain) -> str:
    """'root -> tip' of a chain read from a URDF, 'whole tree below root' of a tree (tip
    None), '-' for a model built in code."""
    if not chain:
        return "-"
    if len(chain) < 2 or chain[1] is None:
        return f"whole tree below {chain[0]}"
    return " -> ".join(chain)

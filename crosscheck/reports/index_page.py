"""index.html of a `gpme verify` run: summary first, then the paper figures, then one
section per engine with its worst cases and plots.  Self-contained (images as data URIs)."""
import base64
import html
from pathlib import Path

from .tables import atomic_write_text, html_page, html_table, worst_first

PAPER_FIGURES = (("fig2_joint_coordinates.png", "Joint coordinates against time, rigid and "
                  "flexible crane (paper Fig. 2)"),
                 ("fig3_end_effector.png", "End-effector path over the target ellipse and "
                  "z_E(t) over z_a(t) (paper Fig. 3)"),
                 ("constraint_violation.png", "|Phi_1| and |Phi_2| against time (log scale)"))
ENGINE_TITLES = {"gpme": "gpme alone: each model's run", "pinocchio": "Pinocchio (term by term)",
                 "mujoco": "MuJoCo (terms and full runs)"}
WORST_ROWS = 15
ROW_COLUMNS = ["section", "model", "quantity", "case", "entry", "gpme_value", "engine_value",
               "abs_error", "rel_error", "tol_abs", "tol_rel", "status", "reason"]


def _img(path, alt):
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    return (f"<figure><img src='data:image/png;base64,{data}' alt='{html.escape(alt)}'>"
            f"<figcaption>{html.escape(alt)}</figcaption></figure>")


def _meta_table(meta):
    items = [("date", meta["date_utc"]), ("git commit", meta["git_commit"]),
             ("mode", "quick (CI-sized)" if meta.get("quick") else "full"),
             ("wall time", f"{meta['wall_time_s']:.1f} s")]
    items += [(k, v) for k, v in meta["versions"].items()]
    m = meta["machine"]
    items.append(("machine", f"{m['node']}, {m['platform']}, {m['processor']}, {m['cpus']} CPUs"))
    cells = "".join(f"<tr><th class='l'>{html.escape(k)}</th><td class='l'>{html.escape(str(v))}"
                    f"</td></tr>" for k, v in items)
    return f"<table class='meta'>{cells}</table>"


def _overview(summary, rows):
    """One line per engine: checks, failures, comparisons, the check closest to its
    tolerance (largest error / (tol_abs + tol_rel * scale) over gated comparisons)."""
    import numpy as np
    import pandas as pd
    out = []
    ranked = worst_first(rows)
    for engine, g in summary.groupby("engine", sort=False):
        r = ranked[(ranked["engine"] == engine) & np.isfinite(ranked["error_over_tolerance"])]
        worst = r.iloc[0] if len(r) else None
        status = g["status"] if "status" in g else g["passed"].map({True: "pass", False: "fail"})
        out.append({"engine": engine, "checks": len(g), "failed": int((status == "fail").sum()),
                    "information only": int((status == "info").sum()),
                    "comparisons": int((rows["engine"] == engine).sum()),
                    "closest to tolerance": "-" if worst is None else
                    f"{worst['section']} / {worst['model']} / {worst['quantity']}",
                    "error / tolerance": np.nan if worst is None else worst["error_over_tolerance"],
                    "passed": not (status == "fail").any()})
    return html_table(pd.DataFrame(out), left_columns=("engine", "closest to tolerance"))


def _summary_table(summary):
    cols = [c for c in ("status", "passed") if c in summary][:1] + ["engine", "section", "model", "quantity", "n_compared", "worst_abs_error",
            "worst_rel_error", "tol_abs", "tol_rel"]
    df = summary[cols].copy()
    table = html_table(df, left_columns=("engine", "section", "model", "quantity"))
    # link each check to its engine section
    for engine in summary["engine"].unique():
        table = table.replace(f"<td class='l'>{html.escape(engine)}</td>",
                              f"<td class='l'><a href='#engine-{engine}'>{html.escape(engine)}</a></td>")
    return table.replace("<table>", "<table id='summary'>", 1)


def _benchmark_section(bench_dir):
    """The latest `python -m benchmarks.bench` results beside the runs, if there are any."""
    png, evals, runs = (bench_dir / "evaluation_costs.png", bench_dir / "evaluation_costs.csv",
                        bench_dir / "run_costs.csv")
    if not (png.exists() and evals.exists() and runs.exists()):
        return []
    import pandas as pd
    return ["<h2 id='benchmarks'>Benchmarks (latest python -m benchmarks.bench)</h2>",
            "<p>Measured separately from this run; see docs/benchmarks.md for the method. "
            f"Files: <a href='../benchmarks/'>../benchmarks/</a>.</p>",
            html_table(pd.read_csv(evals), status_column="-"),
            html_table(pd.read_csv(runs), status_column="-", left_columns=("case", "engine", "method")),
            _img(png, "cost of one constrained q_ddot evaluation against the number of coordinates")]


def _models_section(record):
    """What each compared model is made of: source, chain, frozen joints, flexible links,
    constraints and what the reader left out of M, h, g."""
    parts = ["<h2 id='models'>Models</h2>"]
    for m in record:
        items = [("source", m["source"]), ("URDF", m["urdf"] or "-"),
                 ("chain (root, tip)", " -> ".join(m["chain"]) if m["chain"] else "-"),
                 ("coordinates", m["coordinates"]),
                 ("frozen joints", ", ".join(f"{k} = {v:g}" for k, v in m["frozen"].items())
                  or "none"),
                 ("flexible links", ", ".join(m["flexible_links"]) or "none"),
                 ("constraints", ", ".join(m["constraints"]) or "none"),
                 ("dependent coordinates", ", ".join(m["dependent"]) or "-")]
        cells = "".join(f"<tr><th class='l'>{html.escape(k)}</th><td class='l'>"
                        f"{html.escape(str(v))}</td></tr>" for k, v in items)
        notes = "".join(f"<li>{html.escape(n)}</li>" for n in m["notes"])
        parts.append(f"<h3>{html.escape(m['name'])}</h3><table class='meta'>{cells}</table>"
                     + (f"<p>Accepted from the model description but left out of M, h, g, or "
                        f"replaced:</p><ul>{notes}</ul>" if notes else ""))
    return parts


def diff_section(diff):
    """The "since the previous run" section (HTML) of summary.json's ``diff``
    (crosscheck.reports.run_diff): one headline, then the lists, each capped, and the
    definition of the measure folded."""
    from .run_diff import diff_lines, headline
    if not diff:
        return ""
    if diff.get("previous") is None:
        line = diff.get("note") or "no previous run to compare with"
        return (f"<section id='diff'><h2>Since the previous run</h2><p>{html.escape(line)}"
                "</p></section>")
    items = [line.strip() for line in diff_lines(diff, limit=10)[1:]]
    body = "".join(f"<li>{html.escape(i)}</li>" for i in items)
    return (f"<section id='diff'><h2>Since the previous run</h2><p>{html.escape(headline(diff))}"
            f"</p>{f'<ul>{body}</ul>' if body else ''}<details><summary>How changes are "
            f"measured</summary><p>{html.escape(diff.get('definition', ''))}.</p></details>"
            "</section>")


def write_index(run_dir, summary, rows, runs, meta, models=(), diff=None):
    """Write run_dir/index.html atomically; ``models`` is verify's models.json record,
    ``diff`` summary.json's diff against the previous run (shown below the verdict)."""
    run_dir = Path(run_dir)
    failed = summary["status"] == "fail" if "status" in summary else ~summary["passed"]
    ok = not bool(failed.any())
    n_fail = int(failed.sum())
    n_info = int((summary["status"] == "info").sum()) if "status" in summary else 0
    parts = [f"<h1>gpme verification report</h1>",
             f"<p class='banner {'ok' if ok else 'bad'}'><strong>"
             f"{'NO CHECK FAILED' if ok else f'{n_fail} CHECK(S) FAILED'}</strong> — "
             f"{len(summary)} checks ({n_info} information only, not gated), "
             f"{len(rows)} comparisons.</p>",
             diff_section(diff),
             _meta_table(meta),
             "<h2 id='overview'>At a glance</h2>",
             _overview(summary, rows),
             "<h2 id='summary-h'>Summary: one row per check</h2>",
             "<p>A check passes when, for every compared state or run, the largest absolute "
             "difference is at most tol_abs + tol_rel × max|engine value|. rel_error is that "
             "difference over max|engine value|. Column definitions: reports/README.md.</p>",
             _summary_table(summary)]
    parts += _models_section(models)
    run_figs = sorted((run_dir / "runs").glob("*.png")) if (run_dir / "runs").exists() else []
    if run_figs:
        parts.append("<h2 id='runs'>Runs</h2><p>Histories: runs/&lt;model&gt;.csv.</p>")
        parts += [_img(p, p.stem.replace("_", " ")) for p in run_figs]
    paper_dir = run_dir / "paper"
    if paper_dir.exists():
        parts.append("<h2 id='paper'>The paper's simulations</h2>")
        parts.append("<p>Crane of docs/crane.md: rigid arm and RFEM-flexible arm, flexible "
                     "support, drive torque ramp, programmed ellipse and height; the run "
                     "histories are paper/rigid.csv and paper/flexible.csv.</p>")
        for name, caption in PAPER_FIGURES:
            if (paper_dir / name).exists():
                parts.append(_img(paper_dir / name, caption))
    for engine in rows["engine"].unique():
        sub = rows[rows["engine"] == engine]
        parts.append(f"<h2 id='engine-{engine}'>{html.escape(ENGINE_TITLES.get(engine, engine))}</h2>")
        links = [f"<a href='{f}'>{f}</a>" for f in (f"{engine}.html", f"{engine}.csv",
                                                      "gpme.csv" if engine == "gpme" else "")
                 if f and (run_dir / f).exists()]
        if links:
            parts.append(f"<p>Full results: {', '.join(links)}.</p>")
        parts.append(f"<h3>Worst cases (failures first, then by error over tolerance)</h3>")
        cols = [c for c in ROW_COLUMNS if c in sub.columns]
        parts.append(html_table(worst_first(sub)[cols], max_rows=WORST_ROWS,
                                left_columns=("section", "model", "quantity", "case", "entry",
                                              "reason")))
        for png in sorted(run_dir.glob(f"{engine}_*.png")):
            parts.append(_img(png, png.stem.replace("_", " ")))
    parts += _benchmark_section(run_dir.parent / "benchmarks")
    extra_css = ("<style>.banner{padding:.5rem;border-radius:4px}.ok{background:#dfd}"
                 ".bad{background:#fdd}table.meta{margin:.5rem 0}figure{margin:1rem 0}"
                 "figcaption{font-size:.85rem;color:#555}</style>")
    atomic_write_text(run_dir / "index.html",
                      html_page("gpme verification report", extra_css + "".join(parts)))

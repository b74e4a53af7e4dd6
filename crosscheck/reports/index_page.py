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
ENGINE_TITLES = {"gpme": "gpme alone: the paper's runs", "pinocchio": "Pinocchio (term by term)",
                 "mujoco": "MuJoCo (terms and full runs)"}
WORST_ROWS = 15
ROW_COLUMNS = ["section", "model", "quantity", "case", "entry", "gpme_value", "engine_value",
               "abs_error", "rel_error", "tol_abs", "tol_rel", "passed", "reason"]


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
        out.append({"engine": engine, "checks": len(g), "failed": int((~g["passed"]).sum()),
                    "comparisons": int((rows["engine"] == engine).sum()),
                    "closest to tolerance": "-" if worst is None else
                    f"{worst['section']} / {worst['model']} / {worst['quantity']}",
                    "error / tolerance": np.nan if worst is None else worst["error_over_tolerance"],
                    "passed": not (~g["passed"]).any()})
    return html_table(pd.DataFrame(out), left_columns=("engine", "closest to tolerance"))


def _summary_table(summary):
    cols = ["passed", "engine", "section", "model", "quantity", "n_compared", "worst_abs_error",
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


def write_index(run_dir, summary, rows, runs, meta):
    """Write run_dir/index.html atomically."""
    run_dir = Path(run_dir)
    ok = bool(summary["passed"].all())
    n_fail = int((~summary["passed"]).sum())
    parts = [f"<h1>gpme verification report</h1>",
             f"<p class='banner {'ok' if ok else 'bad'}'><strong>"
             f"{'ALL CHECKS PASSED' if ok else f'{n_fail} CHECK(S) FAILED'}</strong> — "
             f"{len(summary)} checks, {len(rows)} comparisons.</p>",
             _meta_table(meta),
             "<h2 id='overview'>At a glance</h2>",
             _overview(summary, rows),
             "<h2 id='summary-h'>Summary: one row per check</h2>",
             "<p>A check passes when, for every compared state or run, the largest absolute "
             "difference is at most tol_abs + tol_rel × max|engine value|. rel_error is that "
             "difference over max|engine value|. Column definitions: reports/README.md.</p>",
             _summary_table(summary)]
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
                                                      "paper.csv" if engine == "gpme" else "")
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

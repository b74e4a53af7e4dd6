"""CSV and self-contained HTML page (with plots) of the MuJoCo crosscheck."""
import html

import numpy as np
from matplotlib.figure import Figure

from ..compare import FAIL, INFO, row_status
from ..reports.tables import (atomic_write_bytes, atomic_write_text, figure_data_uri,
                              html_page, html_table, summarise, worst_first)
from ..reports.rows import write_rows

TINY = 1e-18   # floor for log plots of differences
MAX_PLOTTED = 5


def _coords(model, g, mj):
    """Up to MAX_PLOTTED coordinates: the non-RFEM ones first (model order), then the RFEM
    coordinate with the largest difference."""
    flexible = {model.coordinate_names[k] for f in model.flexible_links for k in f.joint_indices}
    cols = [c for c in model.coordinate_names if c not in flexible][:MAX_PLOTTED - 1]
    flex = [c for c in model.coordinate_names if c in flexible]
    if flex:
        cols.append(max(flex, key=lambda c: float(np.abs(g[c] - mj[c]).max())))
    return cols


def _trajectory_figure(title, model, g, mj):
    cols = _coords(model, g, mj)
    fig = Figure(figsize=(3.2 * len(cols), 5.0))
    axes = fig.subplots(2, len(cols), squeeze=False)
    for k, c in enumerate(cols):
        ax = axes[0, k]
        ax.plot(g["t"], g[c], label="gpme", lw=1.6)
        ax.plot(mj["t"], mj[c], "--", label="MuJoCo", lw=1.2)
        ax.set_title(c)
        ax.set_xlabel("t [s]")
        ax = axes[1, k]
        ax.semilogy(g["t"], np.maximum(np.abs(g[c] - mj[c]), TINY), color="C3", lw=1)
        ax.set_title(f"|gpme - MuJoCo| {c}")
        ax.set_xlabel("t [s]")
    axes[0, 0].legend()
    fig.suptitle(title)
    fig.tight_layout()
    uri = figure_data_uri(fig)
    return uri


def _off_manifold_figure(model, g, variants, dependent, constraint_names):
    cols = list(dependent) + list(constraint_names)
    fig = Figure(figsize=(3.5 * len(cols), 3.6))
    axes = fig.subplots(1, len(cols), squeeze=False)[0]
    for k, c in enumerate(cols):
        ax = axes[k]
        if c in constraint_names:
            ax.semilogy(g["t"], np.maximum(np.abs(g[c]), TINY), label="gpme (Baumgarte)", lw=1.6)
            for label, mj in variants.items():
                ax.semilogy(mj["t"], np.maximum(np.abs(mj[c]), TINY), "--", label=f"MuJoCo {label}")
            ax.set_title(f"|{c}|")
        else:
            ax.plot(g["t"], g[c], label="gpme (Baumgarte)", lw=1.6)
            for label, mj in variants.items():
                ax.plot(mj["t"], mj[c], "--", label=f"MuJoCo {label}", lw=1.1)
            ax.set_title(c)
        ax.set_xlabel("t [s]")
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{model.name}: off-manifold start")
    fig.tight_layout()
    return figure_data_uri(fig)


def _img(uri, alt="plot"):
    return f"<p><img src='{uri}' alt='{html.escape(alt)}'></p>"


def _save_png(uri, path):
    """Also keep a plot as a PNG beside the page (the verify index embeds these)."""
    import base64
    atomic_write_bytes(path, base64.b64decode(uri.split(",", 1)[1]))


SECTION_TEXT = {
    "free": "Free motion, drive on, both engines RK4 at the same dt; bottom: |gpme - MuJoCo|.",
    "exact": "Programmed motion realised exactly in MuJoCo (multipliers in mjcb_control at "
             "every RK4 stage); bottom: |gpme - MuJoCo|, gated by gpme's own RK4 error.",
    "mechanism": "Programmed motion through MuJoCo's soft-equality mechanism at the smallest "
                 "timeconst run, against gpme at dt/4.",
}


def write_report(out_dir, df, convergence, plots, quick, scenario_names):
    """Write out_dir/mujoco.csv and out_dir/mujoco.html atomically.

    df: the tidy table; convergence: one row per (scenario, mechanism setting); plots:
    {(section, model name): (model, gpme DataFrame, MuJoCo DataFrame or {label: DataFrame})};
    quick: CI run or full; scenario_names: the scenarios run."""
    write_rows(df, out_dir, "mujoco")
    st = row_status(df)
    n_fail, n_info = int((st == FAIL).sum()), int((st == INFO).sum())
    ok = n_fail == 0
    parts = [f"<h1>gpme against MuJoCo {html.escape(_mujoco_version())}</h1>",
             f"<p>{'quick (CI) run' if quick else 'full run'} of "
             f"{html.escape(', '.join(scenario_names))}. Overall: <b>{'PASS' if ok else 'FAIL'}</b> "
             f"({n_fail} failing, {n_info} information rows, of {len(df)}). Method and gates: "
             "docs/crosscheck-mujoco.md; mechanism: docs/mjcf.md.</p>",
             "<h2>Summary</h2>",
             html_table(summarise(df, keys=("section", "model", "quantity")),
                        left_columns=("section", "model", "quantity", "worst_case", "reason"))]
    if len(convergence):
        parts.append("<h2>Soft-equality mechanism: difference to gpme (at dt/4) as timeconst "
                     "and dt shrink</h2>")
        parts.append(html_table(convergence, status_column="-", left_columns=("model",)))
    for (section, name), (model, g, mj) in plots.items():
        if section == "off-manifold":
            parts.append(f"<h2>Off-manifold start: {html.escape(name)} (information)</h2>")
            parts.append("<p>gpme pulls the state onto the constraints with Baumgarte; MuJoCo "
                         "with its own soft-constraint reference acceleration. With timeconst = "
                         "dt it snaps onto them within a few milliseconds; with timeconst = "
                         "1/alpha its reference acceleration equals Baumgarte's, but it lacks "
                         "the Jdot q_dot term, so its violation does not settle to zero.</p>")
            dependent = list(g.attrs.get("dependent", []))
            cons = [c for c in g.columns if c.startswith("Phi") and not c.endswith("_dot")]
            off = _off_manifold_figure(model, g, mj, dependent, cons)
            parts.append(_img(off, f"off-manifold start {name}"))
            _save_png(off, out_dir / f"mujoco_off-manifold_{name}.png")
            continue
        title = f"{section}: {name}"
        parts.append(f"<h2>{html.escape(title)}</h2><p>{html.escape(SECTION_TEXT.get(section, ''))}</p>")
        traj = _trajectory_figure(title, model, g, mj)
        parts.append(_img(traj, f"{title}: both trajectories and their difference"))
        _save_png(traj, out_dir / f"mujoco_{section}_{name}.png")
    parts.append("<h2>All rows, worst first</h2>")
    parts.append(html_table(worst_first(df), left_columns=("section", "case", "model",
                                                           "coordinate", "metric", "quantity",
                                                           "entry", "reason")))
    atomic_write_text(out_dir / "mujoco.html", html_page("gpme vs MuJoCo", "".join(parts)))


def _mujoco_version():
    import mujoco
    return mujoco.__version__

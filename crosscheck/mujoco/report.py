"""Rows, plots (PNG files beside the page, each stored once) and the HTML page of the
MuJoCo crosscheck (crosscheck/reports/templates/engine.html.j2)."""
import mujoco
import numpy as np
from matplotlib.figure import Figure

from gpme_io.atomic import atomic_save_figure
from gpme_io.file_names import file_stem

from ..compare import FAIL, INFO, row_status
from ..reports.html import cite_reasons, engine_page, reason_refs, section, table
from ..reports.rows import own_rows, write_rows
from gpme_io.atomic import atomic_write_text

from ..reports.tables import summarise, worst_first

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
    return fig


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
    return fig


SECTION_TEXT = {
    "free": "Free motion, drive on, both engines RK4 at the same dt; bottom: |gpme - MuJoCo|.",
    "exact": "Programmed motion realised exactly in MuJoCo (multipliers in mjcb_control at "
             "every RK4 stage); bottom: |gpme - MuJoCo|, gated by gpme's own RK4 error.",
    "mechanism": "Programmed motion through MuJoCo's soft-equality mechanism at the smallest "
                 "timeconst run, against gpme at dt/4.",
}


OFF_MANIFOLD_TEXT = (
    "gpme pulls the state onto the constraints with Baumgarte; MuJoCo with its own "
    "soft-constraint reference acceleration. With timeconst = dt it snaps onto them within a "
    "few milliseconds; with timeconst = 1/alpha its reference acceleration equals "
    "Baumgarte's, but it lacks the Jdot q_dot term, so its violation does not settle to zero.")
WORST_ROWS = 40
ROW_COLUMNS = ("section", "case", "model", "coordinate", "metric", "quantity", "entry")


def plot_name(section, model_name):
    """File name of the plot of one run section of one model (beside mujoco.html)."""
    return f"mujoco_{section}_{file_stem(model_name)}.png"


def write_report(out_dir, df, convergence, plots, quick, scenario_names):
    """Write the rows (crosscheck.reports.rows), one PNG per plotted run and
    out_dir/mujoco.html, each atomically.

    df: the tidy table; convergence: one row per (scenario, mechanism setting); plots:
    {(section, model name): (model, gpme DataFrame, MuJoCo DataFrame or {label: DataFrame})};
    quick: CI run or full; scenario_names: the scenarios run."""
    write_rows(own_rows(df, "mujoco"), out_dir, "mujoco")
    st = row_status(df)
    n_fail, n_info = int((st == FAIL).sum()), int((st == INFO).sum())
    ok = n_fail == 0
    intro = [f"{'quick (CI) run' if quick else 'full run'} of {', '.join(scenario_names)}. "
             f"Overall: {'PASS' if ok else 'FAIL'} ({n_fail} failing, {n_info} information "
             f"rows, of {len(df)}). Method and gates: docs/crosscheck-mujoco.md; mechanism: "
             "docs/mjcf.md."]
    summary = summarise(df, keys=("section", "model", "quantity"))
    worst = worst_first(df).head(WORST_ROWS)
    reasons, reason_table = reason_refs(summary, worst)
    sections = [section("Summary", table=table(cite_reasons(summary, reasons),
                                               left_columns=("section", "model", "quantity",
                                                             "worst_case")))]
    if len(convergence):
        sections.append(section("Soft-equality mechanism: difference to gpme (at dt/4) as "
                                "timeconst and dt shrink",
                                table=table(convergence, status_column="-",
                                            left_columns=("model",))))
    for (kind, name), (model, g, mj) in plots.items():
        path = plot_name(kind, name)
        if kind == "off-manifold":
            dependent = list(g.attrs.get("dependent", []))
            cons = [c for c in g.columns if c.startswith("Phi") and not c.endswith("_dot")]
            atomic_save_figure(_off_manifold_figure(model, g, mj, dependent, cons),
                               out_dir / path)
            sections.append(section(f"Off-manifold start: {name} (information)",
                                    [OFF_MANIFOLD_TEXT],
                                    figures=[(path, f"off-manifold start {name}")]))
            continue
        title = f"{kind}: {name}"
        atomic_save_figure(_trajectory_figure(title, model, g, mj), out_dir / path)
        sections.append(section(title, [SECTION_TEXT.get(kind, "")], figures=[
            (path, f"{title}: both trajectories and their difference")]))
    sections.append(section(
        f"Worst {min(WORST_ROWS, len(df))} of {len(df)} rows", [
            "Every row of every check: the checks/mujoco/ files of this report (one gzip CSV "
            "per check), or all at once with python -m crosscheck.reports.rows <report dir> "
            "mujoco."],
        table=table(cite_reasons(worst, reasons),
                    left_columns=[c for c in ROW_COLUMNS if c in df.columns])))
    sections.append(section("Why each tolerance is what it is (the reason column's ids)",
                            table=reason_table))
    atomic_write_text(out_dir / "mujoco.html", engine_page(
        "gpme vs MuJoCo", f"gpme against MuJoCo {_mujoco_version()}", ok, intro, sections))


def _mujoco_version():
    return mujoco.__version__

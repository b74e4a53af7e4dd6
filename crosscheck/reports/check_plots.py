"""The spread plot of each (engine, section, model): every gated comparison row as a dot at
its error / tolerance (log scale), one line per quantity, the pass limit at 1.  It shows
where inside its tolerance a check sits and whether one state or run stands out; the
index links every check to its group's plot.  Information rows (no tolerance) are left out.
"""
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from gpme_io.atomic import atomic_save_figure

from .rows import check_id
from .run_diff import row_ratios

PLOTS_DIR = "plots"
FLOOR = 1e-12          # error / tolerance below this is drawn at it (exact agreement)
ROW_HEIGHT_IN = 0.22   # figure inches per quantity


def spread_path(engine, section, model):
    """Path (relative to the run directory) of the spread plot of one group."""
    name = f"{engine}/{section}/{model}"
    return Path(PLOTS_DIR) / f"{check_id(name)}.png"


def write_spread_plots(run_dir, rows):
    """Write one spread plot per (engine, section, model) with gated rows; returns
    {(engine, section, model): relative path}."""
    run_dir = Path(run_dir)
    rows = rows.assign(_ratio=row_ratios(rows))
    out = {}
    for (engine, section, model), g in rows.groupby(["engine", "section", "model"], sort=False):
        g = g[g["_ratio"].notna()]      # information rows have no ratio
        if g.empty:
            continue
        quantities = list(dict.fromkeys(g["quantity"]))
        fig = Figure(figsize=(7.0, 1.1 + ROW_HEIGHT_IN * len(quantities)))
        ax = fig.subplots()
        position = {q: k for k, q in enumerate(quantities)}
        y = g["quantity"].map(position).to_numpy(float)
        # a non-finite error fails with ratio inf: drawn at the right edge
        x = np.clip(g["_ratio"].to_numpy(float), FLOOR, 1e6)
        failed = (g["status"] == "fail").to_numpy()
        ax.scatter(x[~failed], y[~failed], s=9, color="C0", alpha=0.6, label="pass")
        if failed.any():
            ax.scatter(x[failed], y[failed], s=14, color="C3", label="fail")
        ax.axvline(1.0, color="C3", lw=1)
        ax.set_xscale("log")
        ax.set_xlim(FLOOR / 2, max(10.0, float(x.max()) * 2))
        ax.set_yticks(range(len(quantities)), quantities, fontsize=7)
        ax.invert_yaxis()
        ax.set_xlabel("error / tolerance of each compared state or run (pass below 1)")
        ax.set_title(f"{engine} / {section} / {model}", fontsize=9)
        ax.grid(True, axis="x", alpha=0.3)
        # no tight_layout: the PNG is cut to its drawn extent (gpme_io.png.figure_png,
        # bbox_inches="tight"), long labels included, and the axes keep the figure's
        # width; tight_layout's extra draw was a quarter of each plot's cost
        path = spread_path(engine, section, model)
        atomic_save_figure(fig, run_dir / path, dpi=80)
        out[(engine, section, model)] = path
    return out

"""CSV and self-contained HTML page (with plots) of the MuJoCo crosscheck."""
import html

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..reports.tables import (atomic_write_bytes, atomic_write_text, figure_data_uri,
                              html_page, html_table, summarise, worst_first, write_csv)

MAIN = ("z1", "psi2", "psi3", "z4")
TINY = 1e-18   # floor for log plots of differences


def _coords(model, g, mj):
    flex = [c for c in model.coordinate_names if c not in MAIN]
    cols = list(MAIN)
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


def _off_manifold_figure(model, g, variants):
    fig = Figure(figsize=(14, 3.6))
    axes = fig.subplots(1, 4)
    for k, c in enumerate(("psi3", "z4")):
        axes[k].plot(g["t"], g[c], label="gpme (Baumgarte 20, 20)", lw=1.6)
        for label, mj in variants.items():
            axes[k].plot(mj["t"], mj[c], "--", label=f"MuJoCo {label}", lw=1.1)
        axes[k].set_title(c)
        axes[k].set_xlabel("t [s]")
    for k, c in enumerate(("Phi_1", "Phi_2")):
        ax = axes[2 + k]
        ax.semilogy(g["t"], np.maximum(np.abs(g[c]), TINY), label="gpme", lw=1.6)
        for label, mj in variants.items():
            ax.semilogy(mj["t"], np.maximum(np.abs(mj[c]), TINY), "--", label=f"MuJoCo {label}")
        ax.set_title(f"|{c}|")
        ax.set_xlabel("t [s]")
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{model.name}: off-manifold start")
    fig.tight_layout()
    uri = figure_data_uri(fig)
    return uri


def _energy_figure(title, g, mj):
    fig = Figure(figsize=(9, 3.2))
    axes = fig.subplots(1, 2)
    for k, c in enumerate(("E_kin", "E_pot")):
        axes[k].plot(g["t"], g[c], label="gpme")
        axes[k].plot(mj["t"], mj[c], "--", label="MuJoCo")
        axes[k].set_title(f"{c} [J]")
        axes[k].set_xlabel("t [s]")
    axes[0].legend()
    fig.suptitle(title)
    fig.tight_layout()
    uri = figure_data_uri(fig)
    return uri


def _img(uri, alt="plot"):
    return f"<p><img src='{uri}' alt='{html.escape(alt)}'></p>"


def _save_png(uri, path):
    """Also keep a plot as a PNG beside the page (the verify index embeds these)."""
    import base64
    atomic_write_bytes(path, base64.b64decode(uri.split(",", 1)[1]))


def write_report(out_dir, df, convergence, runs, plan):
    """Write out_dir/mujoco.csv and out_dir/mujoco.html atomically."""
    write_csv(df, out_dir / "mujoco.csv")
    ok = bool(df["passed"].all())
    parts = [f"<h1>gpme against MuJoCo {html.escape(_mujoco_version())}</h1>",
             f"<p>{'quick (CI) run' if plan.quick else 'full run'}: {plan.t_end:g} s of motion per "
             f"case. Overall: <b>{'PASS' if ok else 'FAIL'}</b> "
             f"({int((~df['passed']).sum())} failing of {len(df)} rows). Method, mechanism and "
             "tolerances: docs/crosscheck-mujoco.md and docs/mjcf.md.</p>",
             "<h2>Summary</h2>",
             html_table(summarise(df, keys=("section", "model", "quantity")),
                        left_columns=("section", "model", "quantity", "worst_case", "reason"))]
    parts.append("<h2>Convergence: rigid crane, programmed motion, MuJoCo timeconst and dt</h2>")
    parts.append("<p>gpme at dt = 1e-4 s is the reference; the last row (when present) bounds "
                 "gpme's own RK4 error.</p>")
    parts.append(html_table(convergence, status_column="-"))
    for (section, n), (model, g, mj) in runs.items():
        if section == "off-manifold":
            parts.append(f"<h2>Off-manifold start: {model.name} (not gated)</h2>")
            parts.append("<p>gpme pulls the state onto the constraints with Baumgarte's "
                         "alpha = beta = 20 1/s; MuJoCo with its own soft-constraint reference "
                         "acceleration. With timeconst = dt it snaps onto them within a few "
                         "milliseconds (a violent, impact-like start); with timeconst = 1/alpha "
                         "its reference acceleration equals Baumgarte's, but it lacks the Jdot "
                         "q_dot term, so its violation does not settle to zero.</p>")
            off = _off_manifold_figure(model, g, mj)
            parts.append(_img(off, f"off-manifold start {model.name}"))
            _save_png(off, out_dir / f"mujoco_off-manifold_{model.name}.png")
            continue
        title = f"{section}: {model.name}"
        parts.append(f"<h2>{html.escape(title)}</h2>")
        traj = _trajectory_figure(title, model, g, mj)
        parts.append(_img(traj, f"{title}: both trajectories and their difference"))
        _save_png(traj, out_dir / f"mujoco_{section}_{model.name}.png")
        parts.append(_img(_energy_figure(title, g, mj), f"{title}: energies"))
    parts.append("<h2>All rows, worst first</h2>")
    parts.append(html_table(worst_first(df), left_columns=("section", "case", "model",
                                                           "coordinate", "metric", "quantity",
                                                           "entry", "reason")))
    atomic_write_text(out_dir / "mujoco.html", html_page("gpme vs MuJoCo", "".join(parts)))


def _mujoco_version():
    import mujoco
    return mujoco.__version__

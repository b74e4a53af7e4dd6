"""Figures of any scenario's run (the crane's paper figures are gpme_io.paper_figures).

Each function takes a run DataFrame of gpme_core.integrate.simulate and the Scenario and
returns a matplotlib Figure built with the object API (no pyplot state, no backend
switched); the caller saves it.
"""
import numpy as np
from matplotlib.figure import Figure

TINY = 1e-18   # floor of log plots


def coordinates(scenario, df):
    """Joint coordinates against time (rad or m); a second panel with the RFEM coordinates
    when the model has flexible links."""
    flex = set(scenario.flexible_coordinates)
    joints = [c for c in scenario.model.coordinate_names if c not in flex]
    panels = [("joint coordinates [rad, m]", joints)]
    if flex:
        panels.append(("RFEM coordinates [rad]", [c for c in scenario.model.coordinate_names
                                                  if c in flex]))
    fig = Figure(figsize=(8, 2.8 * len(panels)))
    axes = np.atleast_1d(fig.subplots(len(panels), 1, sharex=True))
    for ax, (label, cols) in zip(axes, panels):
        for c in cols:
            ax.plot(df["t"], df[c], lw=0.8, label=c)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if len(cols) <= 12:
            ax.legend(fontsize=7, ncol=3, loc="upper right")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{scenario.name}: coordinates")
    fig.tight_layout()
    return fig


def constraint_values(scenario, df):
    """|Phi_k| against time, log scale (units of each constraint's expression)."""
    fig = Figure(figsize=(8, 3.4))
    ax = fig.subplots()
    for name in scenario.system.constraint_names:
        ax.semilogy(df["t"], np.maximum(df[name].abs(), TINY), lw=0.8, label=f"|{name}|")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|Phi|")
    ax.grid(alpha=0.3, which="both")
    if scenario.system.constraint_names:
        ax.legend(fontsize=8)
    fig.suptitle(f"{scenario.name}: programmed constraints")
    fig.tight_layout()
    return fig


def constrained_frames(scenario, df):
    """Path of every constrained frame: x-y plane and z(t), world frame (m)."""
    frames = sorted({getattr(c, "frame", None) for c in scenario.constraints} - {None})
    fig = Figure(figsize=(11, 4.4))
    ax1, ax2 = fig.subplots(1, 2)
    for f in frames:
        if f"x_{f}" not in df:
            continue
        ax1.plot(df[f"x_{f}"], df[f"y_{f}"], lw=0.8, label=f)
        ax1.plot(df[f"x_{f}"].iloc[0], df[f"y_{f}"].iloc[0], "o", ms=4)
        ax2.plot(df["t"], df[f"z_{f}"], lw=0.8, label=f)
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("z [m]")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        if frames:
            ax.legend(fontsize=8)
    fig.suptitle(f"{scenario.name}: constrained frames (world)")
    fig.tight_layout()
    return fig


FIGURES = {"coordinates.png": coordinates, "constraints.png": constraint_values,
           "frames.png": constrained_frames}

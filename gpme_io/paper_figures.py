"""Figures of the paper's crane runs, after the paper's Figs. 2 and 3 (matplotlib).

Each function takes run DataFrames from gpme_core.integrate.simulate keyed by a case
label and returns a matplotlib Figure (object API: no pyplot state, no backend is
switched); gpme_io.example_outputs saves them.  Figures of any scenario's run are
gpme_io.figures.
"""
import numpy as np
from matplotlib.figure import Figure

MAIN_COORDINATES = (("z1", "z$^{(1)}$ [m]"), ("psi2", r"$\psi^{(2)}$ [rad]"),
                    ("psi3", r"$\psi^{(3,0)}$ [rad]"), ("z4", "z$^{(4)}$ [m]"))
STYLES = ("-", "--", ":", "-.")


def _flexible_columns(df):
    return [c for c in df.columns if "_arm_" in c and not c.endswith("_dot")]


def joint_coordinates(runs):
    """Fig. 2: joint coordinates against time, all cases on shared axes; a last panel
    shows the largest-amplitude flexible coordinate of each flexible case."""
    flex = {k: _flexible_columns(df) for k, df in runs.items()}
    n_panels = len(MAIN_COORDINATES) + (1 if any(flex.values()) else 0)
    fig = Figure(figsize=(8, 2.0 * n_panels))
    axes = fig.subplots(n_panels, 1, sharex=True)
    for (col, label), ax in zip(MAIN_COORDINATES, axes):
        for (case, df), ls in zip(runs.items(), STYLES):
            ax.plot(df.t, df[col], ls, lw=1.0, label=case)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    if n_panels > len(MAIN_COORDINATES):
        ax = axes[-1]
        for (case, df), ls in zip(runs.items(), STYLES):
            if flex[case]:
                col = max(flex[case], key=lambda c: df[c].abs().max())
                ax.plot(df.t, df[col], ls, lw=0.8, label=f"{case}: {col}")
        ax.set_ylabel("flexible [rad]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[0].legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle("Joint coordinates (paper Fig. 2)")
    fig.tight_layout()
    return fig


def end_effector(runs, params):
    """Fig. 3: end-effector path in the x-y plane over the target ellipse, and z_E(t)
    over the programme z_a(t) = z0 + A cos(2 pi t / T)."""
    fig = Figure(figsize=(11, 4.6))
    ax1, ax2 = fig.subplots(1, 2)
    s = np.linspace(0, 2 * np.pi, 400)
    ax1.plot(params.ellipse_a * np.cos(s), params.ellipse_b * np.sin(s), "k-", lw=2.5,
             alpha=0.25, label="target ellipse")
    for (case, df), ls in zip(runs.items(), STYLES):
        ax1.plot(df.x_E, df.y_E, ls, lw=0.8, label=case)
        ax1.plot(df.x_E.iloc[0], df.y_E.iloc[0], "o", ms=5)
    ax1.set_aspect("equal")
    ax1.set_xlabel("x$_E^{(0)}$ [m]")
    ax1.set_ylabel("y$_E^{(0)}$ [m]")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    df0 = next(iter(runs.values()))
    za = params.z0 + params.amplitude * np.cos(2 * np.pi * df0.t / params.period)
    ax2.plot(df0.t, za, "k-", lw=2.5, alpha=0.25, label="z$_{E,a}$(t)")
    for (case, df), ls in zip(runs.items(), STYLES):
        ax2.plot(df.t, df.z_E, ls, lw=0.8, label=case)
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("z$_E^{(0)}$ [m]")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle("End-effector against the programmed constraints (paper Fig. 3)")
    fig.tight_layout()
    return fig


def constraint_violation(runs, names=("Phi_1", "Phi_2")):
    """|Phi_k| against time on a log scale for every case."""
    fig = Figure(figsize=(8, 3.6))
    ax = fig.subplots()
    for (case, df), ls in zip(runs.items(), STYLES):
        for name, color in zip(names, ("C0", "C3")):
            ax.semilogy(df.t, np.maximum(df[name].abs(), 1e-18), ls, color=color, lw=0.8,
                        label=f"|{name}| {case}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|Phi|")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    return fig

"""Figures of a sweep table: heat maps of one metric over two swept parameters with the
infeasible points marked, and the safe region for user-given limits.

When the (x, y) points form a full grid the map is a cell plot; otherwise (Latin hypercube,
lists) a scatter plot coloured the same way.  Parameters other than x and y that vary are
reduced per (x, y) cell to the worst case: the largest metric value, and "infeasible" when
any point of the cell failed.

``units`` ({column: unit}) and ``parameters`` (the parameter columns) describe a table that
is not the crane's (a model-file sweep); without them the crane's names are used.
"""
from pathlib import Path

import numpy as np
import pandas as pd

from gpme_io.atomic import atomic_save_figure
from gpme_io import file_names

from .spec import PARAMETERS, unit_of

HEAT_MAP_METRICS = ("vib_peak_m", "dev_peak_m", "flex_peak_rad", "psi3_dev_peak_rad",
                    "drive_psi3_peak_Nm", "drive_z4_peak_N")
# cells above this count are not annotated with their values (the text would overlap)
MAX_ANNOTATED_CELLS = 80
SAFE, UNSAFE, INFEASIBLE = 0, 1, 2
_LABELS = {"amplitude": "amplitude A", "period": "period T", "ellipse_a": "ellipse a",
           "ellipse_b": "ellipse b", "steel_youngs_modulus": "Young's modulus E"}


def _unit(name, units=None):
    if units is not None and name in units:
        return units[name]
    return unit_of(name)


def axis_label(name, units=None):
    unit = _unit(name, units)
    return f"{_LABELS.get(name, name)}" + (f" ({unit})" if unit and unit != "1" else "")


def file_stem(name):
    """A file-name-safe form of a metric name (constraint and joint names come from files)."""
    return file_names.file_stem(name)


def feasible(table):
    """bool Series: the point ran and met its constraints."""
    return (table["status"] == "ok") & table["constraints_met"].fillna(False).astype(bool)


def safe_mask(table, limits):
    """bool Series: feasible and every limited metric <= its limit ({metric: max})."""
    ok = feasible(table)
    for name, bound in limits.items():
        ok &= table[name].le(bound).fillna(False)
    return ok


def cell_table(table, x, y, metric, limits=None):
    """One row per (x, y): the worst-case ``metric`` over the other parameters, whether any
    point of the cell is infeasible, and (if limits) whether every point of it is safe."""
    t = table.assign(_feasible=feasible(table))
    t["_value"] = t[metric].where(t["_feasible"]) if metric else np.nan
    if limits is not None:
        t["_safe"] = safe_mask(table, limits)
    agg = {"_value": "max", "_feasible": "all"}
    if limits is not None:
        agg["_safe"] = "all"
    return t.groupby([x, y], as_index=False).agg(agg)


def _edges(values):
    v = np.asarray(values, dtype=float)
    if len(v) == 1:
        half = 0.5 * (abs(v[0]) or 1.0) * 0.2
        return np.array([v[0] - half, v[0] + half])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


def _as_grid(cells, x, y, column):
    xs, ys = np.sort(cells[x].unique()), np.sort(cells[y].unique())
    if len(cells) != len(xs) * len(ys):
        return None
    grid = cells.pivot(index=y, columns=x, values=column).reindex(index=ys, columns=xs)
    return xs, ys, grid.to_numpy()


def heat_map(table, x, y, metric, limits=None, units=None, parameters=None):
    """Figure: ``metric`` over parameters x, y; infeasible cells grey with a cross, feasible
    cells without a value of this metric (NaN: e.g. a vibration frequency of a rigid point)
    hatched and labelled "no value", never left blank; the contour metric = limit drawn
    when ``limits`` bounds this metric."""
    from matplotlib.figure import Figure    # matplotlib: heavy, loaded when a figure is drawn
    cells = cell_table(table, x, y, metric)
    fig = Figure(figsize=(6.4, 4.8))
    ax = fig.subplots()
    unit = _unit(metric, units)
    label = f"{metric} ({unit})"
    grid = _as_grid(cells, x, y, "_value")
    bad = cells[~cells["_feasible"]]
    no_value = cells[cells["_feasible"] & cells["_value"].isna()]
    if grid is not None:
        xs, ys, z = grid
        finite = np.isfinite(z)
        # one power of ten for the colour bar and the cell labels keeps the labels short
        scale = 10.0 ** np.floor(np.log10(np.nanmax(np.abs(z)))) if finite.any() and \
            np.nanmax(np.abs(z)) > 0 else 1.0
        if scale != 1.0:
            label = f"{metric} ({scale:.0e} {unit})"
        mesh = ax.pcolormesh(_edges(xs), _edges(ys), np.ma.masked_invalid(z / scale),
                             cmap="viridis", shading="flat")
        fig.colorbar(mesh, ax=ax, label=label)
        if len(cells) <= MAX_ANNOTATED_CELLS:
            for i, yv in enumerate(ys):
                for j, xv in enumerate(xs):
                    if finite[i, j]:
                        ax.text(xv, yv, f"{z[i, j] / scale:.2g}", ha="center", va="center",
                                fontsize=7, color="w")
        bound = (limits or {}).get(metric)
        if bound is not None and finite.sum() >= 4 and len(xs) > 1 and len(ys) > 1 \
                and np.nanmin(z) < bound < np.nanmax(z):
            cs = ax.contour(xs, ys, np.ma.masked_invalid(z), [bound], colors="r",
                            linewidths=1.5)
            ax.clabel(cs, fmt=f"limit {bound:g}", fontsize=7)
        _mark_cells(ax, bad, x, y, _edges(xs), _edges(ys), xs, ys, INFEASIBLE_CELL)
        _mark_cells(ax, no_value, x, y, _edges(xs), _edges(ys), xs, ys, NO_VALUE_CELL)
    else:
        good = cells[cells["_feasible"] & cells["_value"].notna()]
        sc = ax.scatter(good[x], good[y], c=good["_value"], cmap="viridis", s=40)
        fig.colorbar(sc, ax=ax, label=label)
        if len(bad):
            ax.scatter(bad[x], bad[y], marker="x", c="k", s=40, label="infeasible")
        if len(no_value):
            ax.scatter(no_value[x], no_value[y], marker="o", facecolors="none",
                       edgecolors="k", s=40, label="no value")
    params = PARAMETERS if parameters is None else parameters
    others = [p for p in table.columns if p in params and p not in (x, y)
              and table[p].nunique() > 1]
    ax.set_xlabel(axis_label(x, units))
    ax.set_ylabel(axis_label(y, units))
    title = f"{metric}" + (f" (max over {', '.join(others)})" if others else "")
    ax.set_title(title, fontsize=10)
    if len(bad) or len(no_value):
        ax.legend(loc="upper right", fontsize=8, framealpha=0.8)
    fig.tight_layout()
    return fig


# how a cell without a colour is drawn: (label, face colour, hatch)
INFEASIBLE_CELL = ("infeasible", "0.75", "xx")
NO_VALUE_CELL = ("no value", "white", "//")


def _mark_cells(ax, cells, x, y, x_edges, y_edges, xs, ys, style):
    """Draw ``cells`` (rows of cell_table) as hatched rectangles of ``style``, the first
    one labelled for the legend."""
    from matplotlib.patches import Rectangle    # matplotlib: heavy, loaded when drawing
    label, face, hatch = style
    for k, (_, row) in enumerate(cells.iterrows()):
        j, i = int(np.searchsorted(xs, row[x])), int(np.searchsorted(ys, row[y]))
        ax.add_patch(Rectangle((x_edges[j], y_edges[i]), x_edges[j + 1] - x_edges[j],
                               y_edges[i + 1] - y_edges[i], facecolor=face, hatch=hatch,
                               edgecolor="0.35", linewidth=0.0,
                               label=label if k == 0 else None))


def safe_region(table, x, y, limits, units=None):
    """Figure: each (x, y) safe (all points feasible and within every limit), over a limit,
    or infeasible; the title lists the limits."""
    # matplotlib: heavy, loaded only when a figure is drawn
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch
    cells = cell_table(table, x, y, None, limits)
    cells["_class"] = np.where(~cells["_feasible"], INFEASIBLE,
                               np.where(cells["_safe"], SAFE, UNSAFE))
    colours = ["#4daf4a", "#ff7f00", "0.75"]
    fig = Figure(figsize=(6.4, 4.8))
    ax = fig.subplots()
    grid = _as_grid(cells, x, y, "_class")
    if grid is not None:
        xs, ys, z = grid
        ax.pcolormesh(_edges(xs), _edges(ys), z, cmap=ListedColormap(colours), vmin=-0.5,
                      vmax=2.5, shading="flat", edgecolors="w", linewidth=0.5)
    else:
        ax.scatter(cells[x], cells[y], c=[colours[c] for c in cells["_class"]], s=50)
    handles = [Patch(color=c, label=lab) for c, lab in
               zip(colours, ("safe", "over a limit", "infeasible"))]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.8)
    ax.set_xlabel(axis_label(x, units))
    ax.set_ylabel(axis_label(y, units))
    text = ", ".join(f"{k} <= {v:g} {_unit(k, units)}" for k, v in limits.items())
    ax.set_title(f"safe region: {text}", fontsize=9)
    fig.tight_layout()
    return fig


def write_plots(table, out_dir, x, y, limits=None, metrics=HEAT_MAP_METRICS, units=None,
                parameters=None):
    """heatmap_<metric>.png for each metric with a finite value and safe_region.png (when
    limits are given) into <out_dir>/plots; returns {name: path}.  Needs two swept axes."""
    if x is None or y is None or table.empty or x not in table or y not in table:
        return {}
    table = pd.DataFrame(table)
    # every point has both axes (a list's points are completed with the defaults,
    # gpme_study.spec_points.fill_defaults); a row without one could not be placed on the map
    placed = pd.to_numeric(table[x], errors="coerce").notna() & \
        pd.to_numeric(table[y], errors="coerce").notna()
    table = table[placed]
    if table.empty:
        return {}
    out = Path(out_dir) / "plots"
    paths = {}
    for metric in metrics:
        if metric in table and pd.to_numeric(table[metric], errors="coerce").notna().any():
            name = f"heatmap_{file_stem(metric)}.png"
            paths[name] = out / name
            atomic_save_figure(heat_map(table, x, y, metric, limits, units, parameters),
                               paths[name])
    if limits:
        paths["safe_region.png"] = out / "safe_region.png"
        atomic_save_figure(safe_region(table, x, y, limits, units), paths["safe_region.png"])
    return paths

"""Convergence of RFEM against the continuum reference, and the reference's own errors.

* :func:`continuum_reference`: the continuum run refined until it stops changing: the mesh
  doubled (elements N, 2N, 4N, ...) and the step halved until the compared quantities
  change by less than REFERENCE_FRACTION of their peak; the last change of each is
  reported as the reference's discretisation and integration error (measured, not
  assumed).
* :func:`rfem_history`: the same quantities from a gpme run (RK4, compiled).
* :func:`convergence_table`: for RFEM at n = 1, 2, 3, 5, 10, 20 the largest difference over
  the run to the continuum reference per quantity (absolute, and relative to the
  reference's peak |value|), with the observed order log(e_a / e_b) / log(n_b / n_a)
  between successive n.

A difference that stops falling with n while far above the reference's own error is a
limit RFEM converges to that is not the continuum's (no axial stretch: RFEM's segments
are rigid; no shear): :func:`convergence_table` marks the order of such a quantity, and the
docs (docs/rfem-continuum.md) say what the limit is and why.
"""
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from gpme_core.integrate import simulate

from .runs import continuum_run, rfem_quantities

# the reference is refined until a quantity changes by less than this fraction of its
# peak |value| over the run between the last two meshes (and steps): RFEM is judged at 1 %
# and 0.1 %, so the reference must be ten times finer than the finer of these
REFERENCE_FRACTION = 1e-4
NS = (1, 2, 3, 5, 10, 20)


def _peak(df, col) -> float:
    return float(np.nanmax(np.abs(df[col].to_numpy())))


def max_difference(a: pd.DataFrame, b: pd.DataFrame, col: str) -> float:
    """max_t |a - b| of column col over the common sample times (both on one grid)."""
    m = a[["t", col]].merge(b[["t", col]], on="t", suffixes=("_a", "_b")).dropna()
    return float(np.abs(m[f"{col}_a"] - m[f"{col}_b"]).max())


@dataclass
class Reference:
    """The refined continuum run: frame (finest mesh and step), elements, dt, and per
    quantity the last mesh change and step change (absolute, same unit as the column)."""

    frame: pd.DataFrame
    elements: int
    dt: float
    mesh_change: dict
    step_change: dict
    history: list


def continuum_reference(model, q0, q_dot0, t_end, output_dt, specs, quantities,
                        elements=8, dt=0.01, max_elements=128, min_dt=1e-4,
                        fraction=REFERENCE_FRACTION, log=print, groups=None,
                        euler_bernoulli=False, targets=None) -> Reference:
    """Refine mesh, then step, until every quantity's change < fraction x its peak (the
    largest peak of its group when ``groups`` {name: [columns]} is given: a deflection
    component that stays near 0 is judged on the scale of the others), or below
    targets[column] when given and larger (the accuracy a check needs of the reference)."""
    history = []

    def run(ne, h):
        df = continuum_run(model, q0, q_dot0, t_end, h, output_dt, specs, elements=ne,
                           euler_bernoulli=euler_bernoulli)
        history.append((ne, h, df.attrs["wall_time_s"]))
        log(f"  continuum: {ne} elements, dt = {h:g} s, {df.attrs['wall_time_s']:.1f} s")
        return df

    def changes(a, b):
        return {c: max_difference(a, b, c) for c in quantities}

    def scale(ref, c):
        for cols in (groups or {}).values():
            if c in cols:
                return max(_peak(ref, g) for g in cols)
        return _peak(ref, c)

    def settled(ch, ref):
        goal = {c: max(fraction * max(scale(ref, c), 1e-300), (targets or {}).get(c, 0.0))
                for c in quantities}
        worst = max(quantities, key=lambda c: ch[c] / goal[c])
        log(f"  continuum: largest change {worst} {ch[worst]:.3g} (goal {goal[worst]:.3g})")
        return ch[worst] <= goal[worst]

    ne, h = elements, dt
    coarse = run(ne, h)
    while True:
        fine = run(2 * ne, h)
        mesh = changes(coarse, fine)
        ne *= 2
        coarse = fine
        if settled(mesh, fine) or 2 * ne > max_elements:
            break
    while True:
        fine = run(ne, h / 2)
        step = changes(coarse, fine)
        h /= 2
        coarse = fine
        if settled(step, fine) or h / 2 < min_dt:
            break
    return Reference(coarse, ne, h, mesh, step, history)


def rfem_history(system, q0, q_dot0, t_end, output_dt, dt=None, method="RK4",
                 flexible_of=None) -> pd.DataFrame:
    """The compared quantities from a gpme run of ``system`` (gpme's own kinematics).
    flexible_of: for a rigid model (n = 0), the flexible model whose columns to give: its
    joint coordinates and multipliers (no tip columns: a rigid link has no deflection)."""
    h = simulate(system, t_end, q0, q_dot0, dt=dt, output_dt=output_dt, method=method)
    names = system.constraint_names
    q_cols = list(system.model.coordinate_names)
    lam_cols = [f"lambda_{c}" for c in names]
    if flexible_of is not None:
        rows = [{"t": r["t"], **{c: r[c] for c in q_cols},
                 **{c: r[c] for c in lam_cols}} for _, r in h.iterrows()]
    else:
        rows = [rfem_quantities(system.model, r["t"], r[q_cols].to_numpy(dtype=float),
                                r[lam_cols].to_numpy(dtype=float), names)
                for _, r in h.iterrows()]
    df = pd.DataFrame(rows)
    df["t"] = np.round(df["t"] / output_dt) * output_dt
    df.attrs.update(dt=h.attrs.get("dt"), method=method)
    return df


def convergence_table(make_system: Callable, reference: Reference, quantities: Sequence[str],
                      t_end, output_dt, ns=NS, log=print) -> pd.DataFrame:
    """Rows (n, quantity, error, relative, order) of RFEM at each n against the reference."""
    ref = reference.frame.copy()
    ref["t"] = np.round(ref["t"] / output_dt) * output_dt
    rows, last = [], {}
    for n in ns:
        system, q0, q_dot0 = make_system(n)
        df = rfem_history(system, q0, q_dot0, t_end, output_dt)
        log(f"  RFEM n = {n}: RK4 dt = {df.attrs['dt']:.3g} s")
        for c in quantities:
            err = max_difference(df, ref, c)
            peak = _peak(ref, c)
            order = np.nan
            if c in last and last[c][1] > 0 and err > 0:
                order = np.log(last[c][1] / err) / np.log(n / last[c][0])
            rows.append(dict(n=n, quantity=c, error=err, relative=err / peak if peak else np.nan,
                             order=order, reference_peak=peak,
                             reference_error=reference.mesh_change[c] + reference.step_change[c]))
            last[c] = (n, err)
    return pd.DataFrame(rows)

"""Generic metrics of one gpme run of any model file (``gpme sweep --model FILE``).

Pure functions of a Scenario and its run history (gpme_core.integrate.simulate); no runs
here (gpme_study.model_point runs).  A metric column is ``<family>.<name>`` for a
per-constraint, per-drive or per-coordinate family, or a plain name:

  phi_max_abs.<constraint>   [Phi]   max |Phi_k| for t >= the Baumgarte transient
  lambda_peak.<constraint>   J/[Phi] max over t of |lambda_k| (N for Phi in m, J = N m for a
                                     dimensionless Phi, N m for Phi in rad)
  tau_peak.<coordinate>      N m, N  max over t of |tau| of the file's drive on it
  reaction_peak.<coordinate> N m, N  max over t of |(A^T lambda)_i|: the generalized force the
                                     task puts on coordinate i; on a dependent coordinate it is
                                     what an ideal drive there would deliver
  q_dot_peak.<coordinate>    rad/s, m/s  max over t of |q_dot_i|
  limit_margin.<coordinate>  rad, m  min over t of min(q_i - lower_i, upper_i - q_i), for the
                                     coordinates with a finite limit (a run reaching a limit
                                     stops as infeasible, so the margin of a finished run is >= 0)
  rfem_peak_rad              rad     max over t and the RFEM coordinates of |q_f|
  sigma_min_A                [A]     smallest singular value of the constraint Jacobian A
                                     (m, n) over the recorded rows (0 = singular pose; mixed
                                     units 1/rad, m/rad, ... as A's entries)
  constraints_met            bool    every phi_max_abs.<k> <= phi_tolerance (False when the run
                                     ends inside the transient: nothing was checked)
  transient_s                s       start of the |Phi| window
  wall_time_s, sim_wall_s    s       wall time of the point (build, run, metrics) / of the run
  dt_s, t_end_s              s       RK4 step (NaN for the adaptive integrators), run length

[Phi] is the unit of the constraint function: m for a ``kind = "coordinate"`` constraint and
for expressions in x, y, z written as lengths, 1 for ``kind = "ellipse"``, rad or m for a
[[programme]] of a revolute or prismatic joint.
"""
from typing import Mapping, Optional

import numpy as np
import pandas as pd

from crosscheck.run_checks import transient_time
from gpme_core.constraints import EllipseConstraint, JointProgramme

FAMILIES = ("phi_max_abs", "lambda_peak", "tau_peak", "reaction_peak", "q_dot_peak",
            "limit_margin")
# which metrics a safe-region limit may bound (an upper bound: "the largest allowed value");
# limit_margin and sigma_min_A are "larger is better" and are left to the table
BOUNDABLE = ("phi_max_abs", "lambda_peak", "tau_peak", "reaction_peak", "q_dot_peak",
             "rfem_peak_rad", "wall_time_s")
# metrics drawn as heat maps by default (others when a limit names them)
HEAT_MAP_FAMILIES = ("phi_max_abs", "lambda_peak", "tau_peak", "limit_margin", "rfem_peak_rad",
                     "sigma_min_A")
_LAMBDA_UNIT = {"m": "N", "1": "J", "rad": "N m", "m or 1": "J/[Phi]"}


def coordinate_unit(model, name: str) -> str:
    """'m' for a prismatic coordinate, 'rad' otherwise (revolute and RFEM coordinates)."""
    return "m" if model.joints[model.index(name)].kind == "prismatic" else "rad"


def constraint_units(scenario) -> dict:
    """{constraint name: unit of Phi} ('m', '1', 'rad'); expressions are taken as lengths
    (their symbols x, y, z are in m)."""
    out = {}
    for con, name in zip(scenario.system.bound, scenario.system.constraint_names):
        c = con.spec
        if isinstance(c, EllipseConstraint):
            out[name] = "1"
        elif isinstance(c, JointProgramme):
            out[name] = coordinate_unit(scenario.model, c.coordinate)
        else:
            out[name] = "m"
    return out


def metric_columns(scenario) -> dict:
    """{column: (unit, definition, can be bounded)} of the metrics of ``scenario``'s runs,
    in table order (see the module docstring)."""
    model = scenario.model
    names = list(model.coordinate_names)
    force = {n: ("N" if coordinate_unit(model, n) == "m" else "N m") for n in names}
    out = {}
    units = constraint_units(scenario)
    for c in scenario.system.constraint_names:
        out[f"phi_max_abs.{c}"] = (units[c], f"max |{c}| after the Baumgarte transient", True)
    for c in scenario.system.constraint_names:
        out[f"lambda_peak.{c}"] = (_LAMBDA_UNIT[units[c]], f"max over t of |lambda of {c}|", True)
    for k in sorted({model.index(d.joint) for d in model.drives}):
        out[f"tau_peak.{names[k]}"] = (force[names[k]], f"max over t of |drive on {names[k]}|",
                                       True)
    if scenario.system.constraint_names:
        for n in names:
            out[f"reaction_peak.{n}"] = (force[n], f"max over t of |(A^T lambda)[{n}]|", True)
    for n in names:
        unit = coordinate_unit(model, n) + "/s"
        out[f"q_dot_peak.{n}"] = (unit, f"max over t of |{n}_dot|", True)
    for k, n in enumerate(names):
        if np.isfinite(model.lower_limits[k]) or np.isfinite(model.upper_limits[k]):
            out[f"limit_margin.{n}"] = (coordinate_unit(model, n), f"min over t of the "
                                        f"distance of {n} to its limits", False)
    if scenario.flexible_coordinates:
        out["rfem_peak_rad"] = ("rad", "max over t and the RFEM coordinates of |q_f|", True)
    if scenario.system.constraint_names:
        out["sigma_min_A"] = ("[A]", "smallest singular value of the constraint Jacobian "
                              "over the run", False)
    out["constraints_met"] = ("bool", "every phi_max_abs <= phi_tolerance", False)
    out["wall_time_s"] = ("s", "wall time of the point: build, run and metrics", True)
    return out


def heat_map_metrics(columns: Mapping, limits: Mapping = ()) -> tuple:
    """The columns drawn as heat maps: those of HEAT_MAP_FAMILIES and any limited one."""
    return tuple(c for c in columns if c.split(".", 1)[0] in HEAT_MAP_FAMILIES or c in limits)


def transient_of(scenario, df: pd.DataFrame, transient: Optional[float] = None) -> float:
    """s, start of the |Phi| window: ``transient`` if given, else the time after which the
    Baumgarte envelope of the run's initial violation is below 1e-11
    (crosscheck.run_checks.transient_time; 0 for a run started on its constraints)."""
    if transient is not None:
        return float(transient)
    names = list(scenario.system.constraint_names)
    if not names:
        return 0.0
    system = scenario.system
    return float(transient_time(system.alpha, system.beta, df[names].iloc[0].to_numpy()))


def run_metrics(scenario, df: pd.DataFrame, transient: Optional[float] = None,
                phi_tolerance: float = 1e-3) -> dict:
    """The metric values (see :func:`metric_columns`; wall times excluded) of the run
    ``df`` of ``scenario``.  The constraint Jacobian A is evaluated at every recorded row,
    once, for both reaction_peak and sigma_min_A."""
    model, system = scenario.model, scenario.system
    names = list(model.coordinate_names)
    q = df[names].to_numpy()
    q_dot = df[[f"{n}_dot" for n in names]].to_numpy()
    out = {}
    cons = list(system.constraint_names)
    t_tr = transient_of(scenario, df, transient)
    late = df[df["t"] >= t_tr - 1e-12]
    out["transient_s"] = t_tr
    for c in cons:
        out[f"phi_max_abs.{c}"] = float(late[c].abs().max()) if len(late) else np.nan
    for c in cons:
        out[f"lambda_peak.{c}"] = float(df[f"lambda_{c}"].abs().max())
    for k in sorted({model.index(d.joint) for d in model.drives}):
        out[f"tau_peak.{names[k]}"] = float(df[f"tau_{names[k]}"].abs().max())
    if cons:
        lam = df[[f"lambda_{c}" for c in cons]].to_numpy()
        reaction = np.empty_like(q)
        sigma = np.empty(len(df))
        for r, t in enumerate(df["t"].to_numpy()):
            _, _, a, _ = system.constraints(float(t), q[r], q_dot[r])
            reaction[r] = a.T @ lam[r]
            sigma[r] = np.linalg.svd(a, compute_uv=False).min()
        for i, n in enumerate(names):
            out[f"reaction_peak.{n}"] = float(np.abs(reaction[:, i]).max())
    for i, n in enumerate(names):
        out[f"q_dot_peak.{n}"] = float(np.abs(q_dot[:, i]).max())
    for i, n in enumerate(names):
        lo, hi = model.lower_limits[i], model.upper_limits[i]
        if np.isfinite(lo) or np.isfinite(hi):
            out[f"limit_margin.{n}"] = float(np.min(np.minimum(q[:, i] - lo, hi - q[:, i])))
    flex = list(scenario.flexible_coordinates)
    if flex:
        out["rfem_peak_rad"] = float(df[flex].abs().max().max())
    if cons:
        out["sigma_min_A"] = float(sigma.min())
    phis = [out[f"phi_max_abs.{c}"] for c in cons]
    out["constraints_met"] = bool(len(late) > 0 and all(p <= phi_tolerance for p in phis))
    return out

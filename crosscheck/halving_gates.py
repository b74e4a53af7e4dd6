"""Gates of whole runs made by two engines with *different* integrators, from step halving.

crosscheck.run_gates gates an engine that integrates gpme's ODE with gpme's own scheme (RK4,
same step, same stage times): both runs then carry the same truncation error and only
gpme's own error needs estimating.  An engine that integrates with its own scheme (Drake's
Runge-Kutta, Exudyn's generalized-alpha on the index-3 DAE) carries a different truncation
error, so each engine's error is measured on its own side, by halving its step:

    runs at h, h/2, h/4 of one engine, global order p:
        x_h/2 - x_h/4 = C (h/2)^p (1 - 2^-p)   =>   e(h/4) = (x_h/2 - x_h/4) / (2^p - 1)

and the observed order p_obs = log2(max|x_h - x_h/2| / max|x_h/2 - x_h/4|) checks the
asymptotic regime run-wide, and the local order at every compared time checks that the
run-wide bound holds there too (crosscheck.convergence: a start transient or a stiff mode
can converge slower at a few samples).  The order row accepts |p_obs - p| <=
ORDER_TOLERANCE (1), so the error estimate uses the lowest accepted order p - 1, which
bounds the estimate from above over everything the order row lets through (RK4: 1/7 of
the last difference instead of 1/15; an order-2 scheme: the last difference itself instead
of a third of it).  Each engine's runs are refined (crosscheck.convergence.refine) until
both hold, within a budget; an engine whose runs did not converge fails its own order row
once, and the column rows are "not judged" (information) rather than failed.

The two finest runs (each engine at its h/4) are compared column by column; the gate is

    e_gpme(h/4) + e_engine(h/4) + round-off floors of both + the engine's solver floor

(solver floor: the error its nonlinear solver's tolerance allows, in the column's unit; 0 for
explicit schemes).  A difference above the gate is more than both integrations can explain.
"""
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from typing import Optional

from .compare import Tolerance, compare, not_judged
from .convergence import FINEST, Convergence, Refinement, convergence
from .run_gates import (EPS, ORDER_TOLERANCE, RESOLVED, RefinedRuns, column_unit,
                        overridden_quantities)

HALVINGS = 3            # runs at h, h/2, h/4
TIME_MATCH_S = 1e-9     # s: output times of two runs are the same sample when this close


@dataclass(frozen=True)
class HalvedRuns:
    """One engine's runs of one system from one start at steps h, h/2, h/4.

    engine      : "gpme", "drake", "exudyn", ...
    scheme      : the integrator in words (report text), e.g. "RK4", "generalized-alpha"
    order       : the scheme's nominal global order p (> 1)
    runs        : 3 DataFrames (at h, h/2, h/4), each with column "t" (s) and the compared
                  columns, recorded at the same output times
    dt          : s, the coarsest step h
    solver_floor: {column: error the engine's nonlinear solver tolerance allows, in the
                  column's unit}; missing columns have 0
    refinement  : crosscheck.convergence.Refinement, how dt was reached (None: not refined)
    judged      : the columns whose convergence decides the order row (None: all compared);
                  e.g. Exudyn's q and q_dot, not its index-3 multipliers
    """

    engine: str
    scheme: str
    order: float
    runs: tuple
    dt: float
    solver_floor: Mapping[str, float] = field(default_factory=dict)
    refinement: Optional[Refinement] = None
    judged: Optional[tuple] = None

    def __post_init__(self):
        if len(self.runs) != HALVINGS:
            raise ValueError(f"{self.engine}: HalvedRuns needs {HALVINGS} runs (h, h/2, h/4), "
                             f"got {len(self.runs)}")
        if not self.order - ORDER_TOLERANCE > 0.0:     # also refuses NaN
            raise ValueError(f"{self.engine}: nominal order {self.order!r} leaves no positive "
                             f"lowest accepted order (order - {ORDER_TOLERANCE:g}); give p > "
                             f"{ORDER_TOLERANCE:g}")
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"{self.engine}: step dt = {self.dt!r} s; give a positive step")
        t0 = self.runs[0]["t"].to_numpy(float)
        for k, run in enumerate(self.runs[1:], start=1):
            t = run["t"].to_numpy(float)
            if len(t) != len(t0) or np.abs(t - t0).max(initial=0.0) > TIME_MATCH_S:
                raise ValueError(f"{self.engine}: the run at h/{2 ** k} is recorded at other "
                                 "output times than the run at h (harness bug)")

    @property
    def finest(self) -> pd.DataFrame:
        """The run at h/4."""
        return self.runs[-1]

    @property
    def finest_dt(self) -> float:
        """s, the finest step h/4."""
        return self.dt / 2 ** (HALVINGS - 1)

    @property
    def n_steps(self) -> int:
        """Steps of the finest run."""
        t_end = float(self.finest["t"].iloc[-1])
        return int(round(t_end / self.finest_dt))

    def differences(self, column: str) -> tuple:
        """(max_t |x_h - x_h/2|, max_t |x_h/2 - x_h/4|) of ``column``, in its unit."""
        x1, x2, x4 = (r[column].to_numpy(float) for r in self.runs)
        return float(np.abs(x1 - x2).max(initial=0.0)), float(np.abs(x2 - x4).max(initial=0.0))

    def error(self, column: str) -> float:
        """Estimated max_t |error| of the finest run's ``column`` at the lowest accepted
        order p - 1: max|x_h/2 - x_h/4| / (2^(p-1) - 1)."""
        return self.differences(column)[1] / (2.0 ** (self.order - ORDER_TOLERANCE) - 1.0)

    def floor(self, column: str, model) -> float:
        """This engine's round-off in ``column`` over its finest run, plus its solver floor
        (column's unit); the terms of crosscheck.run_gates.column_floor for one engine:

        - own:   eps N (|x|max + coupled): each of the N steps rounds the update once,
                 relative to the component and to the rate that updates it (coupled = h
                 max|q_dot| for a coordinate, h max|q_ddot| for a velocity, from the run);
                 a multiplier carries the solve's eps cond(M) |x| (attrs max_cond_M);
        - cross: eps sqrt(N) max|state of that kind|: round-off of the solve that mixes all
                 components, without sign, so a random walk; it decides for a coordinate
                 the motion leaves at ~0 (an RFEM torsion of a planar motion).
        model: the gpme model (coordinate names); None treats every column as a plain one.
        """
        run = self.finest
        x = run[column].to_numpy(float)
        scale = float(np.abs(x).max(initial=0.0))
        n, h = self.n_steps, self.finest_dt
        names = list(model.coordinate_names) if model is not None else []
        velocities = [f"{c}_dot" for c in names]
        coupled, cond, kind = 0.0, 0.0, None
        if column in names:
            coupled = h * _max_abs(run, velocities)
            kind = names
        elif column in velocities:
            coupled = h * _max_rate(run, velocities)
            kind = velocities
        elif column.startswith("lambda_"):
            cond = float(run.attrs.get("max_cond_M", 0.0))
        own = EPS * (n * (scale + coupled) + cond * scale)
        cross = EPS * np.sqrt(n) * _max_abs(run, kind) if kind else 0.0
        return own + cross + float(self.solver_floor.get(column, 0.0))


def _max_abs(run: pd.DataFrame, columns) -> float:
    """Largest |value| over ``columns`` of ``run`` (those it has)."""
    cols = [c for c in columns if c in run.columns]
    return float(np.abs(run[cols].to_numpy(float)).max(initial=0.0)) if cols else 0.0


def _max_rate(run: pd.DataFrame, columns) -> float:
    """Largest |d/dt| over ``columns`` of ``run`` by differences of its samples (the
    recorded accelerations' size for the velocity columns)."""
    cols = [c for c in columns if c in run.columns]
    t = run["t"].to_numpy(float)
    if not cols or len(t) < 2:
        return 0.0
    dt = np.diff(t)[:, None]
    return float(np.abs(np.diff(run[cols].to_numpy(float), axis=0) / dt).max(initial=0.0))


def from_refined(refined: RefinedRuns) -> HalvedRuns:
    """gpme's RK4 runs at h, h/2, h/4 (crosscheck.run_gates.refined_gpme_runs) as HalvedRuns."""
    return HalvedRuns("gpme", "classical RK4", 4.0, tuple(refined.runs), refined.dt,
                      refinement=refined.refinement)


def runs_convergence(runs: HalvedRuns, columns: Sequence[str], model) -> Convergence:
    """crosscheck.convergence.Convergence of one engine's three runs, the finest compared,
    with this engine's floors (:meth:`HalvedRuns.floor`)."""
    if runs.judged is not None:
        columns = [c for c in columns if c in runs.judged]
    floors = {c: runs.floor(c, model) for c in columns}
    return convergence(runs.runs, columns, floors, runs.order, FINEST)


def gate(gpme: HalvedRuns, other: HalvedRuns, column: str, model, override=None) -> Tolerance:
    """Tolerance of one column: both engines' halving error estimates of their finest runs
    plus both floors (or the model file's override, a gpme_io.scenario.ToleranceOverride)."""
    if override is not None:
        return Tolerance(override.abs, override.rel,
                         f"override from the model file: {override.reason}")
    e_g, e_o = gpme.error(column), other.error(column)
    f_g, f_o = gpme.floor(column, model), other.floor(column, model)
    unit = column_unit(model, column) if model is not None else ""
    solver = float(other.solver_floor.get(column, 0.0))
    return Tolerance(
        e_g + e_o + f_g + f_o, 0.0,
        f"two integrators, each one's error measured by halving its own step and taken at "
        f"the lowest order the order rows accept (p - 1): {gpme.engine} {gpme.scheme} (p = "
        f"{gpme.order:g}) at dt = {gpme.finest_dt:.3g} s: {e_g:.2e} {unit}; {other.engine} "
        f"{other.scheme} (p = {other.order:g}) at dt = {other.finest_dt:.3g} s: {e_o:.2e} "
        f"{unit}; + round-off per engine, eps (N (|x|max + h |rate|max) + sqrt(N) "
        f"|state|max) ({f_g + f_o - solver:.2e}) + "
        f"{other.engine}'s solver-tolerance floor ({solver:.2e})")


def order_row(engine: str, scenario_name: str, runs: HalvedRuns, columns: Sequence[str],
              label: str, case: str, model=None) -> dict:
    """Row of one engine's observed order at the compared times (validates its error
    estimate, crosscheck.convergence), counted for the engine whose runs it judges
    (runs.engine; ``engine`` names the comparison in the quantity); information only when
    no column's h/2 - h/4 difference is resolved.  model: the gpme model (the floors'
    coupling terms; see HalvedRuns.floor)."""
    conv = runs_convergence(runs, columns, model)
    p, where = conv.decisive_order()
    owner = runs.engine
    quantity = f"{label}: observed order of {runs.engine} ({runs.scheme})"
    if owner != engine:
        quantity = f"{label} ({engine}): observed order of {runs.engine} ({runs.scheme})"
    steps = runs.refinement.describe(runs.engine) if runs.refinement is not None else ""
    if not conv.resolved:
        tol = Tolerance(np.inf, 0.0, f"information: at dt/2 every column's {runs.engine} "
                        f"step-halving difference is below {RESOLVED:g} round-off and solver "
                        "floors, so no order can be observed (shown: the column closest to "
                        "resolved); the gates are then the floors" + steps)
        return compare(owner, scenario_name, quantity, case,
                       [p if np.isfinite(p) else 0.0], [runs.order], tol, [where])
    verdict = ""
    if not conv.converged:
        verdict = " NOT CONVERGED: " + (
            runs.refinement.remedy(runs.engine, "[run] quick_t_end or t_end")
            if runs.refinement is not None else "its step was not refined")
    tol = Tolerance(ORDER_TOLERANCE, 0.0,
                    f"{runs.scheme} is order {runs.order:g}; {conv.describe()}. The halving "
                    f"estimate is {runs.engine}'s error only when the run-wide order is within "
                    f"{ORDER_TOLERANCE:g} of {runs.order:g} and the local order supports it at "
                    "every compared time (crosscheck.convergence)" + steps + verdict)
    value = p if np.isfinite(p) else -99.0
    return compare(owner, scenario_name, quantity, case, [value], [runs.order], tol, [where])


def run_rows(engine: str, scenario, gpme: HalvedRuns, other: HalvedRuns,
             columns: Sequence[str], label: str, case: str) -> list:
    """Rows (crosscheck.compare dicts) comparing the finest runs of gpme and ``other``
    column by column (quantity "<label> <column>", :func:`gate` or the scenario's override
    of "<engine>/<label> <column>"), then one observed-order row per engine, each counted
    for the engine whose runs it judges.  When either engine's runs did not converge (its
    order row fails) the column rows are "not judged" (information): the failure is
    counted once, in that engine's order row."""
    g, o = gpme.finest, other.finest
    if len(g) != len(o) or np.abs(g["t"].to_numpy(float) - o["t"].to_numpy(float)).max(
            initial=0.0) > TIME_MATCH_S:
        raise ValueError(f"{engine}/{scenario.name}/{label}: output times of {other.engine} "
                         "differ from gpme's (harness bug)")
    missing = [c for c in columns if c not in g.columns or c not in o.columns]
    if missing:
        raise ValueError(f"{engine}/{scenario.name}/{label}: columns {missing} missing from "
                         "a run (harness bug)")
    times = [f"t={t:.4g}" for t in g["t"]]
    rows = []
    for c in columns:
        quantity = f"{label} {c}"
        tol = gate(gpme, other, c, scenario.model, scenario.tolerance(engine, quantity))
        rows.append(compare(engine, scenario.name, quantity, case, g[c].to_numpy(float),
                            o[c].to_numpy(float), tol, times))
    orders = [order_row(engine, scenario.name, r, columns, label, case, scenario.model)
              for r in (gpme, other)]
    failed = [r for r in orders if r["status"] == "fail"]
    if failed:
        because = ("the step-halving error estimate that gates it is not the error: see "
                   + "; ".join(f"the {r['engine']} check '{r['quantity']}' ({r['entry']})"
                               for r in failed))
        overridden = overridden_quantities(scenario, engine)
        rows = [r if r["quantity"] in overridden else not_judged(r, because) for r in rows]
    return rows + orders

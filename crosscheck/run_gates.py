"""Gates of whole runs from the integrator's own error (Richardson), for any scenario.

gpme and an engine that realises the same equations integrate the same ODE with the same
classical RK4 scheme, the same step h and the same stage times.  RK4's global truncation
error e(h) = C h^4 + O(h^5) is a property of the ODE and the scheme, so both runs carry
the same e(h); what separates them is round-off and any difference in the equations.
A difference larger than gpme's own integration error therefore cannot be a
discretisation artefact of either engine: it is a real disagreement.

gpme's error at h is estimated from gpme alone, at the same output times:

    x_h - x_{h/2} = C h^4 (1 - 1/16)   =>   e(h) ~ 16/15 (x_h - x_{h/2})

and a column's gate is max_t |e(h)| plus a round-off floor (:func:`roundoff_floor`).
The estimate holds only in RK4's asymptotic regime, which a third run at h/4 checks:
max|x_h - x_{h/2}| / max|x_{h/2} - x_{h/4}| = 2^p with the observed order p ~ 4
(:func:`observed_order`).  p outside [3, 5] means the runs are not in that regime, the
16/15 estimate is not the error, and the gates of that scenario are meaningless: the
order row then fails.

Columns: every coordinate (rad or m) and velocity (rad/s or m/s), every constraint value
Phi (the constraint's unit) and multiplier lambda_<name> (N, N m, or per unit of Phi).
"""
from dataclasses import dataclass
from typing import Mapping, Optional, Sequence

import numpy as np
import pandas as pd

from gpme_core.integrate import rk4_step_plan, simulate

from .compare import Tolerance, compare

EPS = float(np.finfo(float).eps)
RICHARDSON_RK4 = 16.0 / 15.0       # 2^p / (2^p - 1) for p = 4
ORDER = 4.0
ORDER_TOLERANCE = 1.0              # |p - 4| <= 1, i.e. the ratio within [8, 32]
RESOLVED = 10.0                    # a column enters the order only when its h/2 - h/4
                                   # difference is this many round-off floors


@dataclass(frozen=True)
class RefinedRuns:
    """gpme runs of one system from one start at steps h, h/2, h/4, same output times.

    runs    : (DataFrame at h, at h/2, at h/4) from gpme_core.integrate.simulate
    dt      : s, the step h actually used (rk4_step_plan may shorten the requested one)
    n_steps : number of RK4 steps of the run at h
    t_end   : s;  output_dt : s
    """

    runs: tuple
    dt: float
    n_steps: int
    t_end: float
    output_dt: float

    @property
    def coarse(self) -> pd.DataFrame:
        return self.runs[0]

    @property
    def finest(self) -> pd.DataFrame:
        return self.runs[-1]


# s: longest run the engines are compared over in the full plan.  A run of the reference
# engine costs ~7 gpme runs (h, h/2, h/4 and up to 3 halvings) plus the engine's own loop
# from Python, so the full 10 s of the crane at n = 10 would take hours; 2 s covers the
# drive's start, most of a programme period and ~30 periods of the first bending mode, and the
# comparison is at round-off and truncation level, which a longer run does not change.  The
# scenario's own gpme run (verify's gpme step) still covers its whole t_end.
FULL_RUN_T_END = 2.0
MAX_HALVINGS = 3
# RK4 steps of one compared run above which the engines are not run (an information row
# says so): the reference run costs ~7 gpme runs plus the engine's loop from Python, about
# a minute per 1e5 steps here.  Stiff RFEM models (the crane at n_rfe = 10 needs
# dt = 4e-6 s for RK4's stability) exceed it; an implicit integrator would not.
MAX_RUN_STEPS = 100_000


def over_budget(t_end: float, dt: float):
    """The reason a run of t_end s at step dt is not compared, or None when it is affordable."""
    steps = t_end / dt
    if steps <= MAX_RUN_STEPS:
        return None
    return (f"not compared: {t_end:g} s at the RK4 step {dt:.3g} s that the model's stiffest "
            f"mode needs is {steps:.3g} steps, above the budget of {MAX_RUN_STEPS:,} per run "
            "(the terms are compared at every sampled state)")     # at most 8x the requested step's cost to reach RK4's asymptotic regime


def refined_gpme_runs(system, q0, q_dot0, t_end: float, dt: float,
                      output_dt: float, max_halvings: int = MAX_HALVINGS) -> RefinedRuns:
    """gpme (RK4) at h, h/2 and h/4 from (q0, q_dot0) (n,), recorded every output_dt s.

    h starts at dt; while gpme's own observed order (coordinates and velocities resolved
    above their round-off, see :func:`observed_order`) is more than 1 away from 4, h is
    halved (at most ``max_halvings`` times): a step chosen for stability only (the default
    of a model file: half the RK4 stability limit of the stiffest RFEM mode) can lie outside
    the asymptotic regime, where 16/15 (x_h - x_h/2) is not the error and would not be a
    gate.  The engines are then run at the h this returns (``.dt``)."""
    step, _ = rk4_step_plan(t_end, dt, output_dt)
    runs = [simulate(system, t_end, q0, q_dot0, dt=step / k, output_dt=output_dt)
            for k in (1, 2, 4)]
    names = list(system.model.coordinate_names)
    columns = names + [f"{c}_dot" for c in names]
    for _ in range(max_halvings):
        refined = RefinedRuns(tuple(runs), step, int(round(t_end / step)), t_end, output_dt)
        # the same floors as the engines' rows (column_floor), from gpme's own run
        runs[0].attrs.setdefault("max_abs_q_ddot", float(np.abs(np.diff(
            runs[0][columns[len(names):]].to_numpy(float), axis=0)).max(initial=0.0)
            / max(output_dt, 1e-300)))
        floors = {c: column_floor(refined, runs[0], c, system.model) for c in columns}
        p, _, resolved = observed_order(refined, columns, floors)
        if not resolved or abs(p - 4.0) <= 1.0:
            return refined
        step /= 2.0
        runs = runs[1:] + [simulate(system, t_end, q0, q_dot0, dt=step / 4, output_dt=output_dt)]
    return RefinedRuns(tuple(runs), step, int(round(t_end / step)), t_end, output_dt)


def richardson_error(refined: RefinedRuns, column: str) -> np.ndarray:
    """(samples,) gpme's estimated global RK4 error of ``column`` at step h, over time."""
    h, h2 = (refined.runs[k][column].to_numpy(float) for k in (0, 1))
    return RICHARDSON_RK4 * (h - h2)


def roundoff_floor(scale: float, n_steps: int, cond: float = 0.0, coupled: float = 0.0) -> float:
    """Round-off two engines may differ by after n_steps RK4 steps, in the column's unit.

    Each step rounds every state component's update once: relative eps of the component
    itself (scale = its |x|max) plus the absolute round-off of the rate that updates it,
    which is computed from the whole state (a solve with M mixes every component), hence
    eps times the largest rate entry, h max||x_dot||_inf (``coupled``, in the column's unit;
    it decides for columns far smaller than the rest of the state, e.g. an RFEM torsion).
    Accumulated linearly (the worst case, not the random-walk sqrt(n)): n eps (scale +
    coupled) per engine, x2 for two engines.  A quantity obtained by a linear solve with M
    (the multipliers) also carries the solve's forward error eps cond(M) |x| per
    evaluation, added through ``cond`` (0 for states).  For Phi, scale is the size of the
    terms Phi is formed from (the engines' ``phi_scale``), not |Phi|, which is ~0.
    """
    return 2.0 * EPS * (n_steps * (float(scale) + float(coupled)) + cond * float(scale))


def column_floor(refined: "RefinedRuns", engine_df: pd.DataFrame, column: str, model) -> float:
    """:func:`roundoff_floor` of one run column, from the engine's own run: coordinates
    couple through h max||q_dot||_inf, velocities through h max||q_ddot||_inf (the engine's
    attrs max_abs_q_ddot), multipliers carry cond(M) (attrs max_cond_M)."""
    names = list(model.coordinate_names)
    h = refined.dt
    coupled, cond = 0.0, 0.0
    if column in names:
        coupled = h * float(np.abs(engine_df[[f"{c}_dot" for c in names]].to_numpy()).max())
    elif column.endswith("_dot") and column[:-4] in names:
        coupled = h * float(engine_df.attrs.get("max_abs_q_ddot", 0.0))
    elif column.startswith("lambda_"):
        cond = float(engine_df.attrs.get("max_cond_M", 0.0))
    floor = roundoff_floor(column_scale(engine_df, column), refined.n_steps, cond, coupled)
    # cross-talk: a step's update of one coordinate (velocity) is computed together with all
    # the others (the solve with M mixes them), so it also carries round-off relative to the
    # largest coordinate (velocity) of the state; unlike the column's own round-off above it
    # has no systematic sign, so it accumulates as a random walk (Henrici's statistical model
    # of round-off): 2 eps sqrt(N) max|state|.  It decides for a joint the task holds still,
    # whose value or rate is ~0 in both engines up to round-off.
    kind = names if column in names else [f"{c}_dot" for c in names] \
        if column.endswith("_dot") and column[:-4] in names else None
    if kind is not None:
        state = float(np.abs(engine_df[kind].to_numpy(float)).max())
        floor += 2.0 * EPS * np.sqrt(refined.n_steps) * state
    return floor


def observed_order(refined: RefinedRuns, columns: Sequence[str],
                   floors: Mapping[str, float]):
    """(p, column, resolved) of the least resolved ratio: p = log2(max|x_h - x_h/2| /
    max|x_h/2 - x_h/4|) minimised over the columns whose h/2 - h/4 difference exceeds
    RESOLVED round-off floors (resolved = True); when no column does, the p of the column
    closest to being resolved, with resolved = False (truncation error below round-off)."""
    resolved, closest = (np.nan, None), (np.nan, None, -np.inf)
    for c in columns:
        x1, x2, x4 = (r[c].to_numpy(float) for r in refined.runs)
        d1, d2 = float(np.abs(x1 - x2).max()), float(np.abs(x2 - x4).max())
        p = float(np.log2(d1 / d2)) if d1 > 0 and d2 > 0 else np.nan
        above = d2 / floors[c] if floors[c] > 0 else np.inf
        if above > closest[2] and np.isfinite(p):
            closest = (p, c, above)
        if above > RESOLVED and (np.isnan(resolved[0]) or p < resolved[0]):
            resolved = (p, c)
    if resolved[1] is not None:
        return resolved[0], resolved[1], True
    return closest[0], closest[1], False


def column_unit(model, column: str) -> str:
    """Unit of a run column: rad or m for coordinates, /s for velocities, '' otherwise."""
    base = column[:-4] if column.endswith("_dot") else column
    if base in model.coordinate_names:
        unit = "rad" if model.is_revolute[model.index(base)] else "m"
        return unit + ("/s" if column.endswith("_dot") else "")
    return ""


def column_scale(engine_df: pd.DataFrame, column: str) -> float:
    """|x|max of a column for the round-off floor: a Phi column uses the engine's
    phi_scale (max_t sum_j |A_kj q_j|, the size of the terms Phi is formed from) when the
    engine recorded it, every other column its own largest value."""
    phi_scale = engine_df.attrs.get("phi_scale", {})
    if column in phi_scale:
        return float(phi_scale[column])
    return float(np.abs(engine_df[column].to_numpy(float)).max())


def gate(refined: RefinedRuns, engine_df: pd.DataFrame, column: str, model,
         override=None) -> Tolerance:
    """Tolerance of one run column: gpme's Richardson error at h + round-off floor, or the
    model file's override (a gpme_io.scenario.ToleranceOverride)."""
    if override is not None:
        return Tolerance(override.abs, override.rel,
                         f"override from the model file: {override.reason}")
    est = float(np.abs(richardson_error(refined, column)).max())
    cond = float(engine_df.attrs.get("max_cond_M", 0.0)) if column.startswith("lambda_") else 0.0
    scale = column_scale(engine_df, column)
    floor = column_floor(refined, engine_df, column, model)
    unit = column_unit(model, column)
    cond_txt = f" + eps cond(M) with cond(M) <= {cond:.1e}" if cond else ""
    return Tolerance(est + floor, 0.0,
                     f"same RK4 scheme, step dt = {refined.dt:g} s ({refined.n_steps} steps) and "
                     f"stage times in both engines, so their truncation errors coincide and a "
                     f"difference above gpme's own integration error is a real disagreement: "
                     f"gpme's error at dt by Richardson, 16/15 max|x(dt) - x(dt/2)| = "
                     f"{est:.2e} {unit}, + round-off floor 2 eps (N (|x|max + h |rate|max){cond_txt}) = "
                     f"{floor:.2e} {unit} (|x|max = {scale:.3g})")


def run_rows(engine: str, scenario, refined: RefinedRuns, engine_df: pd.DataFrame,
             columns: Sequence[str], label: str, case: str) -> list:
    """Tidy rows (crosscheck.compare.compare) of one engine's run against gpme's run at h:
    one per column (quantity "<label> <column>", gate :func:`gate` or the scenario's
    override of "<engine>/<label> <column>"), then one row of the observed order."""
    g = refined.coarse
    if len(g) != len(engine_df) or not np.allclose(g["t"], engine_df["t"], rtol=0, atol=1e-9):
        raise ValueError(f"{engine}/{scenario.name}/{label}: output times differ from gpme's "
                         "(harness bug)")
    times = [f"t={t:.4g}" for t in g["t"]]
    rows = []
    floors = {}
    for c in columns:
        quantity = f"{label} {c}"
        tol = gate(refined, engine_df, c, scenario.model, scenario.tolerance(engine, quantity))
        floors[c] = column_floor(refined, engine_df, c, scenario.model)
        rows.append(compare(engine, scenario.name, quantity, case, g[c].to_numpy(float),
                            engine_df[c].to_numpy(float), tol, times))
    rows.append(order_row(engine, scenario, refined, columns, floors, label, case))
    return rows


def order_row(engine, scenario, refined, columns, floors, label, case) -> dict:
    """The row of gpme's observed RK4 order (h/2 vs h/4), which validates the gates."""
    p, col, resolved = observed_order(refined, columns, floors)
    quantity = f"{label}: observed RK4 order of gpme"
    if not resolved:
        tol = Tolerance(np.inf, 0.0, "information: at dt/2 every column's truncation error is "
                        f"below {RESOLVED:g} round-off floors, so no order can be observed (shown: "
                        "the column closest to resolved); the gates are then the round-off floor "
                        "plus Richardson noise")
        return compare(engine, scenario.name, quantity, case, [p if np.isfinite(p) else 0.0],
                       [ORDER], tol, [str(col)])
    tol = Tolerance(ORDER_TOLERANCE, 0.0,
                    f"RK4 is order 4 (ratio 16 per halving); the smallest observed order over the "
                    f"columns resolved above round-off is {p:.2f} ({col}). |p - 4| > 1 means the "
                    "runs are not in RK4's asymptotic regime, 16/15 (x(dt) - x(dt/2)) is not "
                    "gpme's error and the gates of this run are meaningless")
    return compare(engine, scenario.name, quantity, case, [p], [ORDER], tol, [col])

"""Gates of whole runs from the integrator's own error (Richardson), for any scenario.

gpme and an engine that realises the same equations integrate the same ODE with the same
classical RK4 scheme, the same step h and the same stage times.  RK4's global truncation
error e(h) = C h^4 + O(h^5) is a property of the ODE and the scheme, so both runs carry
the same e(h); what separates them is round-off and any difference in the equations.
A difference larger than gpme's own integration error therefore cannot be a
discretisation artefact of either engine: it is a real disagreement.

gpme's error at h is estimated from gpme alone, at the same output times:

    x_h - x_{h/2} = C h^p (1 - 2^-p)   =>   e(h) ~ 2^p / (2^p - 1) (x_h - x_{h/2})

taken at the lowest order the order row accepts, p = 3 (8/7; 16/15 at p = 4), and a
column's gate is max_t |e(h)| plus a round-off floor (:func:`roundoff_floor`).  The
estimate holds only in RK4's asymptotic regime, which a third run at h/4 checks, run-wide
(max|x_h - x_{h/2}| / max|x_{h/2} - x_{h/4}| = 2^p with p within 1 of 4) and at every
output time (crosscheck.convergence: the local order must support the bound where the
error is); :func:`refined_gpme_runs` halves h until both hold, within a budget.  When they
do not, the estimate is not the error and the gates of that scenario mean nothing: gpme's
order row (a gpme check: it judges gpme's runs) fails once, and the engine's rows of that
run are reported as "not judged" (information) instead of failing in every engine.

Columns: every coordinate (rad or m) and velocity (rad/s or m/s), every constraint value
Phi (the constraint's unit) and multiplier lambda_<name> (N, N m, or per unit of Phi).
"""
from dataclasses import dataclass
from typing import Mapping, Optional, Sequence

import numpy as np
import pandas as pd

from gpme_core.integrate import rk4_step_plan, simulate

from . import run_memo
from .compare import Tolerance, compare, not_judged
from .convergence import (COARSEST, ORDER_TOLERANCE, RESOLVED, Convergence,
                          Refinement, RefinementBudget, convergence, refine)

EPS = float(np.finfo(float).eps)
ORDER = 4.0
# 2^(p-1) / (2^(p-1) - 1) at the lowest order the order row accepts (p - 1 = 3): the error
# of the run at h is (x_h - x_h/2) times this when RK4 converges at order 3, which the
# order row lets through; at order 4 it would be 16/15, 7 % less
RICHARDSON_RK4 = 8.0 / 7.0
# s: no further halving of gpme's runs when the next one is projected to take longer
GPME_RUN_WALL_S = 120.0


@dataclass(frozen=True)
class RefinedRuns:
    """gpme runs of one system from one start at steps h, h/2, h/4, same output times.

    runs    : (DataFrame at h, at h/2, at h/4) from gpme_core.integrate.simulate
    dt      : s, the step h actually used (rk4_step_plan may shorten the requested one)
    n_steps : number of RK4 steps of the run at h
    t_end   : s;  output_dt : s
    convergence : crosscheck.convergence.Convergence of the three runs (None: not judged
                  when made, e.g. by a test)
    refinement  : crosscheck.convergence.Refinement, how h was reached (None: not refined)
    """

    runs: tuple
    dt: float
    n_steps: int
    t_end: float
    output_dt: float
    convergence: Optional[Convergence] = None
    refinement: Optional[Refinement] = None

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
                      output_dt: float, max_halvings: int = MAX_HALVINGS,
                      compared: str = COARSEST, log=None) -> RefinedRuns:
    """gpme (RK4) at h, h/2 and h/4 from (q0, q_dot0) (n,), recorded every output_dt s.

    h starts at dt and is halved (at most ``max_halvings`` times, crosscheck.convergence.
    refine) until gpme's three runs are in RK4's asymptotic regime: the run-wide observed
    order over the coordinates and velocities resolved above their round-off within 1 of
    4, and the error bound of the compared run (``compared``: COARSEST for run_gates, whose
    engines run at h; FINEST for halving_gates, which compares the h/4 runs) supported by
    the local order at every output time (crosscheck.convergence).  A step chosen for
    stability only (the default of a model file: half the RK4 stability limit of the
    stiffest RFEM mode) can lie outside that regime, where the halving estimate is not the
    error and would not be a gate.  The engines are then run at the h this returns
    (``.dt``); ``.convergence`` and ``.refinement`` say whether it converged and how."""
    step, _ = rk4_step_plan(t_end, dt, output_dt)
    names = list(system.model.coordinate_names)
    columns = names + [f"{c}_dot" for c in names]

    def run_at(h):
        # the same run another step of the verification may ask for (crosscheck.run_memo)
        key = run_memo.run_key("refined_gpme_run", system, np.asarray(q0, float),
                               np.asarray(q_dot0, float), float(t_end), float(h),
                               float(output_dt))
        return run_memo.memoised(key, lambda: simulate(system, t_end, q0, q_dot0, dt=h,
                                                       output_dt=output_dt))

    def floors_of(runs):
        refined = RefinedRuns(tuple(runs), float(runs[0].attrs.get("dt", step)),
                              int(round(t_end / float(runs[0].attrs.get("dt", step)))),
                              t_end, output_dt)
        # the same floors as the engines' rows (column_floor), from gpme's own run
        runs[0].attrs.setdefault("max_abs_q_ddot", float(np.abs(np.diff(
            runs[0][columns[len(names):]].to_numpy(float), axis=0)).max(initial=0.0)
            / max(output_dt, 1e-300)))
        return {c: column_floor(refined, runs[0], c, system.model) for c in columns}

    budget = RefinementBudget(max_halvings, GPME_RUN_WALL_S)
    runs, h, conv, record = refine(run_at, step, columns, floors_of, ORDER, compared,
                                   budget, log)
    return RefinedRuns(tuple(runs), h, int(round(t_end / h)), t_end, output_dt, conv, record)


def richardson_error(refined: RefinedRuns, column: str) -> np.ndarray:
    """(samples,) gpme's estimated global RK4 error of ``column`` at step h, over time, at
    the lowest order the order row accepts (:data:`RICHARDSON_RK4`)."""
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


# roundings of one evaluation of Phi relative to the size of its terms: the frame's position
# ends a chain of 4x4 products (each rounds once relative to the running |p|, and the chains
# of the engines compared differ), and phi's expression adds a few more; 32 covers chains of
# ~25 bodies
PHI_EVAL_ROUNDINGS = 32


def phi_term_scale(a, q) -> "np.ndarray":
    """(m,) size of the terms a constraint value Phi is formed from at one state, in Phi's
    unit: sum_j |A_kj| (|q_j| + 1), A (m, n) its Jacobian, q (n,) rad or m.  |A_kj| x 1 rad
    is the change of Phi per radian of joint j, |grad phi| times the lever arm of the frame
    about that joint, so the sum is |grad phi| times the chain's reach: the size of the
    products whose round-off Phi carries even where q_j ~ 0 (sum_j |A_kj q_j| alone
    vanishes at a zero posture while the terms, e.g. z of a tool 0.3 m up, do not)."""
    return np.abs(np.asarray(a, float)) @ (np.abs(np.asarray(q, float)) + 1.0)


def baumgarte_memory_steps(h: float, baumgarte) -> float:
    """Steps over which a rounding of the state's normal component to the constraints is
    still carried in Phi: 1 / (r h), r the slowest decay rate of Phi_ddot + 2 alpha Phi_dot +
    beta^2 Phi = 0 (alpha - sqrt(alpha^2 - beta^2) for alpha >= beta, else alpha); inf
    without Baumgarte (baumgarte None or a rate <= 0)."""
    if baumgarte is None:
        return np.inf
    alpha, beta = (float(v) for v in baumgarte)
    rate = alpha - np.sqrt(alpha * alpha - beta * beta) if alpha >= beta else alpha
    return 1.0 / (rate * h) if rate > 0 and h > 0 else np.inf


def phi_floor(scale: float, n_steps: int, h: float, baumgarte=None) -> float:
    """Round-off two engines' Phi may differ by (Phi's unit): each engine's evaluation,
    PHI_EVAL_ROUNDINGS eps scale, plus the roundings of the state's normal component that
    Baumgarte has not yet pulled back, eps scale per step over min(N, 1 / (r h)) steps
    (:func:`baumgarte_memory_steps`; linear, the worst case).  Unlike the coordinates'
    floor it does not grow with the run's step count: Phi is held, not integrated."""
    carried = min(float(n_steps), baumgarte_memory_steps(h, baumgarte))
    return 2.0 * EPS * float(scale) * (PHI_EVAL_ROUNDINGS + carried)


def column_floor(refined: "RefinedRuns", engine_df: pd.DataFrame, column: str, model,
                 baumgarte=None) -> float:
    """:func:`roundoff_floor` of one run column, from the engine's own run: coordinates
    couple through h max||q_dot||_inf, velocities through h max||q_ddot||_inf (the engine's
    attrs max_abs_q_ddot), multipliers carry cond(M) (attrs max_cond_M); a constraint value
    Phi (in the engine's attrs phi_scale) has :func:`phi_floor` with the scenario's
    Baumgarte rates ``baumgarte`` = (alpha, beta) 1/s."""
    names = list(model.coordinate_names)
    h = refined.dt
    if column in engine_df.attrs.get("phi_scale", {}):
        return phi_floor(column_scale(engine_df, column), refined.n_steps, h, baumgarte)
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
    closest to being resolved, with resolved = False (truncation error below round-off).
    The run-wide part of crosscheck.convergence.convergence."""
    conv = convergence(refined.runs, columns, floors, ORDER, COARSEST)
    return conv.order, conv.column, conv.resolved


def column_unit(model, column: str) -> str:
    """Unit of a run column: rad or m for coordinates, /s for velocities, '' otherwise."""
    base = column[:-4] if column.endswith("_dot") else column
    if base in model.coordinate_names:
        unit = "rad" if model.is_revolute[model.index(base)] else "m"
        return unit + ("/s" if column.endswith("_dot") else "")
    return ""


def column_scale(engine_df: pd.DataFrame, column: str) -> float:
    """|x|max of a column for the round-off floor: a Phi column uses the engine's
    phi_scale (max_t of :func:`phi_term_scale`, the size of the terms Phi is formed from) when the
    engine recorded it, every other column its own largest value."""
    phi_scale = engine_df.attrs.get("phi_scale", {})
    if column in phi_scale:
        return float(phi_scale[column])
    return float(np.abs(engine_df[column].to_numpy(float)).max())


def gate(refined: RefinedRuns, engine_df: pd.DataFrame, column: str, model,
         override=None, baumgarte=None) -> Tolerance:
    """Tolerance of one run column: gpme's Richardson error at h + round-off floor, or the
    model file's override (a gpme_io.scenario.ToleranceOverride)."""
    if override is not None:
        return Tolerance(override.abs, override.rel,
                         f"override from the model file: {override.reason}")
    est = float(np.abs(richardson_error(refined, column)).max())
    cond = float(engine_df.attrs.get("max_cond_M", 0.0)) if column.startswith("lambda_") else 0.0
    scale = column_scale(engine_df, column)
    floor = column_floor(refined, engine_df, column, model, baumgarte)
    unit = column_unit(model, column)
    cond_txt = f" + eps cond(M) with cond(M) <= {cond:.1e}" if cond else ""
    return Tolerance(est + floor, 0.0,
                     f"same RK4 scheme, step dt = {refined.dt:g} s ({refined.n_steps} steps) and "
                     f"stage times in both engines, so their truncation errors coincide and a "
                     f"difference above gpme's own integration error is a real disagreement: "
                     f"gpme's error at dt by Richardson at the lowest accepted order 3, "
                     f"8/7 max|x(dt) - x(dt/2)| = "
                     f"{est:.2e} {unit}, + round-off floor 2 eps (N (|x|max + h |rate|max){cond_txt}) = "
                     f"{floor:.2e} {unit} (|x|max = {scale:.3g})")


def run_rows(engine: str, scenario, refined: RefinedRuns, engine_df: pd.DataFrame,
             columns: Sequence[str], label: str, case: str) -> list:
    """Tidy rows (crosscheck.compare.compare) of one engine's run against gpme's run at h:
    one per column (quantity "<label> <column>", gate :func:`gate` or the scenario's
    override of "<engine>/<label> <column>"), then gpme's order row (engine "gpme": it
    judges gpme's own runs).  When gpme's runs did not converge (the order row fails) the
    column rows are "not judged" (information, crosscheck.compare.not_judged)."""
    g = refined.coarse
    if len(g) != len(engine_df) or not np.allclose(g["t"], engine_df["t"], rtol=0, atol=1e-9):
        raise ValueError(f"{engine}/{scenario.name}/{label}: output times differ from gpme's "
                         "(harness bug)")
    times = [f"t={t:.4g}" for t in g["t"]]
    rows = []
    floors = {}
    for c in columns:
        quantity = f"{label} {c}"
        baumgarte = (scenario.system.alpha, scenario.system.beta) \
            if hasattr(scenario, "system") else None
        tol = gate(refined, engine_df, c, scenario.model, scenario.tolerance(engine, quantity),
                   baumgarte)
        floors[c] = column_floor(refined, engine_df, c, scenario.model, baumgarte)
        rows.append(compare(engine, scenario.name, quantity, case, g[c].to_numpy(float),
                            engine_df[c].to_numpy(float), tol, times))
    order = order_row(engine, scenario, refined, columns, floors, label, case)
    if order["status"] == "fail":
        because = (f"gpme's own RK4 runs of this case are not in their asymptotic regime, so "
                   f"the gate (gpme's Richardson error) is not its error: see the gpme check "
                   f"'{order['quantity']}' ({order['entry']})")
        overridden = overridden_quantities(scenario, engine)
        rows = [r if r["quantity"] in overridden else not_judged(r, because) for r in rows]
    rows.append(order)
    return rows


def overridden_quantities(scenario, engine) -> set:
    """Quantities of ``engine`` whose tolerance the model file sets (judged whatever the
    runs' convergence: the file takes responsibility, with its reason)."""
    prefix = f"{engine}/"
    return {k[len(prefix):] for k in getattr(scenario, "tolerances", {}) if k.startswith(prefix)}


def order_row(engine, scenario, refined, columns, floors, label, case) -> dict:
    """gpme's row (engine "gpme", whichever engine's comparison made the runs) of its
    observed RK4 order at the compared times (h, h/2, h/4; crosscheck.convergence), which
    validates the gates; ``engine`` names the comparison in the quantity."""
    conv = refined.convergence
    if conv is None:
        conv = convergence(refined.runs, columns, floors, ORDER, COARSEST)
    p, where = conv.decisive_order()
    quantity = f"{label} ({engine}): observed RK4 order of gpme"
    steps = refined.refinement.describe("gpme") if refined.refinement is not None else ""
    if not conv.resolved:
        tol = Tolerance(np.inf, 0.0, "information: at dt/2 every column's truncation error is "
                        f"below {RESOLVED:g} round-off floors, so no order can be observed (shown: "
                        "the column closest to resolved); the gates are then the round-off floor "
                        "plus Richardson noise" + steps)
        return compare("gpme", scenario.name, quantity, case, [p if np.isfinite(p) else 0.0],
                       [ORDER], tol, [where])
    verdict = "" if conv.converged else (
        " NOT CONVERGED: " + (refined.refinement.remedy("gpme", "[run] quick_t_end or t_end")
                              if refined.refinement is not None else "no refinement made"))
    tol = Tolerance(ORDER_TOLERANCE, 0.0,
                    f"RK4 is order 4 (ratio 16 per halving); {conv.describe()}. The gate "
                    "8/7 (x(dt) - x(dt/2)) is gpme's error only when the run-wide order is "
                    "within 1 of 4 and the local order supports it at every output time "
                    "(crosscheck.convergence); otherwise the gates of this run are "
                    "meaningless" + steps + verdict)
    value = p if np.isfinite(p) else -99.0
    return compare("gpme", scenario.name, quantity, case, [value], [ORDER], tol, [where])

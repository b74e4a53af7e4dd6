"""The default RK4 step of `gpme simulate`: accurate enough for the run's own checks, not
only stable.

The scenario's step (the model file's ``[run] dt``, else half the RK4 stability limit at the
start, at most ``output_dt``: gpme_io/runs.py resolved_step) is a *stability* bound: at half the
limit an undamped oscillation of the stiffest mode loses ~8 % of its energy a step
(|R(1.41 i)|^2 = 0.92), so a run at that step can be stable and still fail its own energy
balance.  The rule:

1. Run at the scenario's step h0 (the run `gpme simulate` always made: no extra cost when it
   passes, and the paper's crane keeps the paper's steps).
2. Judge it by the checks `simulate` prints (crosscheck.run_checks.run_rows, whose
   tolerances are used as they are): |Phi_i| after the Baumgarte transient <= PHI_TOL
   (1e-8) and the energy balance |E - E(0) - W| <= ENERGY_TOL (1e-6 of the largest work
   term).  Both quantities are zero for the exact motion (after the transient the Baumgarte
   envelope is below PHI_TOL / 1000 by construction; the balance is an identity), so each is
   the run's own global RK4 error in that quantity, measured over the whole run, not
   extrapolated from a pilot.  A run whose gated checks all pass is kept.
3. Else, with rho = error / tolerance of the worst check, halve the step
   k = ceil(log2(rho / MARGIN) / ORDER) times: RK4's global error falls as h^4, so k
   halvings predict every check at <= MARGIN (1/10) of its tolerance.  The margin is for
   the prediction only (a run not yet in RK4's asymptotic regime falls slower: measured on
   an undamped stiff joint, 2.7x for the first halving instead of 16x); a measured run is
   judged by its checks as they are.
4. Run at the new step and judge it.  If it still fails, the observed order of each failing
   check between the two runs, p = log2(rho_before / rho_after) / halvings (Richardson's
   estimate), says whether halving helps: p < MIN_ORDER means the error does not come from
   the step (a model, a tolerance or round-off) and the search stops; otherwise step 3
   again from this run.
5. Budget (gpme_io/budget.py): at most MAX_STEP_HALVINGS halvings of h0 in all, and the runs of
   one model together within MAX_WALL_S unless --force.  When a halving with the margin does
   not fit, the least number predicted to pass without it is run if that fits; when nothing
   fits the search stops with one line (the step reached, the worst check's error and
   tolerance, the step predicted to pass and its estimated cost, the remedy).  The checks
   then judge the last run.

Steps are halvings of the step actually used (gpme_core.integrate.rk4_step_plan fits h0 to
whole steps per output interval; its halves fit too), so every run samples the same times.
An explicit ``--dt`` is used as given, and RadauIIA and the adaptive methods are run as
asked: the checks judge those runs.
"""
import math
from dataclasses import dataclass
from enum import Enum
from typing import Callable, Optional, Sequence

from gpme_core.run_cost import format_seconds
from gpme_core.stability import round_down
from gpme_io.budget import MAX_STEP_HALVINGS, BudgetError, step_search_problem

from .compare import FAIL, PASS

# RK4's global order: in its asymptotic regime each halving divides the error by 2^4
ORDER = 4
# a step chosen by prediction aims every check at this fraction of its tolerance
MARGIN = 0.1
# observed order below this between two runs: halving does not reduce the check's error
MIN_ORDER = 1.0


class Outcome(Enum):
    """How the search ended."""
    KEPT = "the starting step passes its checks"
    REFINED = "halved until the checks pass"
    NO_CHECKS = "no gated check to judge the step by"
    OUT_OF_BUDGET = "the budget ran out before the checks passed"
    NOT_FROM_STEP = "the failing checks do not converge with the step"


@dataclass(frozen=True)
class CheckError:
    """One gated check of a run: its quantity, error, tolerance (same unit) and where.

    error     : |value| the check gates (abs_error of its row; inf for NaN)
    tolerance : tol_abs + tol_rel * scale of its row
    entry     : where the worst value sits ("t = 0.4080 s ...")
    """
    quantity: str
    error: float
    tolerance: float
    entry: str

    @property
    def ratio(self) -> float:
        """error / tolerance (0 for no error, inf for an error against a zero tolerance)."""
        if self.error == 0.0:
            return 0.0
        if not math.isfinite(self.error) or self.tolerance <= 0.0:
            return math.inf
        return self.error / self.tolerance

    def describe(self) -> str:
        """'energy balance 1.6e-05 at t = 2.0000 s (tolerance 3.3e-06)'."""
        return (f"{self.quantity} {self.error:.2g} at {self.entry} "
                f"(tolerance {self.tolerance:.2g})")


def gated_errors(rows: Sequence[dict]) -> tuple:
    """CheckError of every row of ``rows`` (crosscheck.compare rows) that passes or fails;
    information rows are left out."""
    out = []
    for r in rows:
        if r["status"] not in (PASS, FAIL):
            continue
        err = float(r["abs_error"])
        out.append(CheckError(r["quantity"], err if math.isfinite(err) else math.inf,
                              float(r["tol_abs"]) + float(r["tol_rel"]) * float(r["scale"]),
                              str(r.get("entry", ""))))
    return tuple(out)


@dataclass(frozen=True)
class Trial:
    """One run of the search: its step (s), halvings of the starting step, the gated
    checks' errors and its wall time (s)."""
    dt: float
    halvings: int
    errors: tuple
    wall_s: float

    @property
    def passed(self) -> bool:
        return all(e.ratio <= 1.0 for e in self.errors)

    @property
    def worst(self) -> Optional[CheckError]:
        return max(self.errors, key=lambda e: e.ratio) if self.errors else None


@dataclass(frozen=True)
class StepChoice:
    """The run the search keeps and how it was reached.

    df      : its history (gpme_core.integrate.simulate)
    rows    : its check rows (``checks(df)``)
    trials  : every run made, in order (the last is ``df``'s)
    outcome : Outcome
    note    : one line on the step: which, why, and the remedy when the search stopped short
    """
    df: object
    rows: list
    trials: tuple
    outcome: Outcome
    note: str

    @property
    def dt(self) -> float:
        return self.trials[-1].dt


def halvings_needed(ratio: float, margin: float = MARGIN) -> int:
    """Halvings of the step that bring an error of ``ratio`` x its tolerance to ``margin`` x
    it at RK4's order (at least 1)."""
    return max(1, math.ceil(math.log2(ratio / margin) / ORDER - 1e-12))


def _observed_order(before: Trial, after: Trial) -> float:
    """Lowest observed order of the checks ``after`` fails, from their errors in ``before``
    (inf when it fails none that ``before`` measured)."""
    k = after.halvings - before.halvings
    earlier = {e.quantity: e.ratio for e in before.errors}
    orders = [math.log2(earlier[e.quantity] / e.ratio) / k for e in after.errors
              if e.ratio > 1.0 and e.quantity in earlier and math.isfinite(e.ratio)
              and earlier[e.quantity] > 0]
    return min(orders) if orders else math.inf


def _fmt(dt):
    return f"{dt:.3g} s"


def run_accurately(run: Callable, checks: Callable, estimate: Optional[Callable] = None,
                   force: bool = False, report: Optional[Callable] = None,
                   max_halvings: int = MAX_STEP_HALVINGS,
                   start: str = "the scenario's step") -> StepChoice:
    """The run at the default RK4 step chosen by the rule of this module.

    run      : run(dt) -> history DataFrame with attrs "dt" (s, the step used) and
               "wall_time_s"; run(None) is the run at the scenario's own step
    checks   : checks(df) -> check rows (crosscheck.run_checks.run_rows of the scenario)
    estimate : estimate(dt) -> gpme_core.run_cost.RunCost of a run at dt, for the budget
               (None: no cost limit, only ``max_halvings``)
    force    : no cost limit (--force)
    report   : report(line) is given one line before each further run (None: silent)
    start    : what run(None)'s step is, in words for the note ("the model file's step")
    """
    say = report or (lambda line: None)
    df = run(None)
    rows = checks(df)
    h0 = float(df.attrs["dt"])
    trials = [Trial(h0, 0, gated_errors(rows), float(df.attrs.get("wall_time_s", 0.0)))]
    if not trials[0].errors:
        return StepChoice(df, rows, tuple(trials), Outcome.NO_CHECKS,
                          f"RK4 step {_fmt(h0)}: no gated check to judge it by")
    if trials[0].passed:
        return StepChoice(df, rows, tuple(trials), Outcome.KEPT, _kept_note(trials, start))
    while True:
        last = trials[-1]
        worst = last.worst
        if not math.isfinite(worst.ratio):
            return StepChoice(df, rows, tuple(trials), Outcome.NOT_FROM_STEP,
                              f"RK4 step {_fmt(last.dt)}: {worst.describe()} cannot be "
                              "reduced by a shorter step (not a finite error against a "
                              "positive tolerance); the checks judge this run")
        spent = sum(t.wall_s for t in trials)
        left = max_halvings - last.halvings
        wanted = halvings_needed(worst.ratio)
        least = halvings_needed(worst.ratio, 1.0)
        chosen, why_not = None, ""
        for k in (wanted, least) if least < wanted else (wanted,):
            if k > left:
                why_not = (f"{k} more halving{'s' * (k > 1)} would pass the limit of "
                           f"{max_halvings} (dt >= {_fmt(h0 / 2 ** max_halvings)})")
                continue
            problem = None if estimate is None else step_search_problem(
                spent, estimate(h0 / 2 ** (last.halvings + k)), force)
            if problem:
                why_not = f"a run at dt = {_fmt(h0 / 2 ** (last.halvings + k))}: {problem}"
                continue
            chosen = k
            break
        if chosen is None:
            return StepChoice(df, rows, tuple(trials), Outcome.OUT_OF_BUDGET,
                              _budget_note(trials, start, wanted, why_not, estimate))
        dt = h0 / 2 ** (last.halvings + chosen)
        say(f"RK4 step {_fmt(last.dt)}: {worst.describe()}, {worst.ratio:.3g}x its "
            f"tolerance; running at dt = {_fmt(dt)} ({chosen} halving{'s' * (chosen > 1)}: "
            f"RK4's error falls as dt^{ORDER}"
            + (f", aiming at {MARGIN:g} of the tolerance)" if chosen == wanted else ")"))
        try:
            new_df = run(dt)
        except BudgetError as exc:   # its own estimate came out above the limits
            return StepChoice(df, rows, tuple(trials), Outcome.OUT_OF_BUDGET,
                              _budget_note(trials, start, wanted, str(exc), estimate))
        df, rows = new_df, checks(new_df)
        trials.append(Trial(float(df.attrs["dt"]), last.halvings + chosen,
                            gated_errors(rows), float(df.attrs.get("wall_time_s", 0.0))))
        if trials[-1].passed:
            return StepChoice(df, rows, tuple(trials), Outcome.REFINED,
                              _kept_note(trials, start))
        order = _observed_order(last, trials[-1])
        if order < MIN_ORDER:
            now = trials[-1].worst
            return StepChoice(df, rows, tuple(trials), Outcome.NOT_FROM_STEP,
                              f"RK4 step {_fmt(trials[-1].dt)}: halving from "
                              f"{_fmt(last.dt)} left {now.describe()} at {now.ratio:.3g}x "
                              f"its tolerance (observed order {order:.2g} < {MIN_ORDER:g}): "
                              "its error does not come from the step; the checks judge "
                              "this run")


def _kept_note(trials, start):
    last = trials[-1]
    worst = last.worst
    how = (start if last.halvings == 0 else
           f"{last.halvings} halving{'s' * (last.halvings > 1)} of {start} "
           f"{_fmt(trials[0].dt)}; {len(trials)} runs, "
           f"{sum(t.wall_s for t in trials):.1f} s")
    return (f"RK4 step {_fmt(last.dt)} ({how}): every check within its tolerance, the "
            f"closest {worst.quantity} at {worst.ratio:.2g} of it")


def _budget_note(trials, start, wanted, why_not, estimate):
    last = trials[-1]
    worst = last.worst
    target = round_down(last.dt / 2 ** wanted)
    cost = ""
    if estimate is not None:
        wall = estimate(target).wall_s
        cost = "" if wall is None else f", estimated at {format_seconds(wall)},"
    how = start if last.halvings == 0 else (f"{last.halvings} halving"
                                            f"{'s' * (last.halvings > 1)} of {start} "
                                            f"{_fmt(trials[0].dt)}")
    return (f"budget reached at RK4 step {_fmt(last.dt)} ({how}): {worst.describe()}, "
            f"{worst.ratio:.3g}x its tolerance; dt = {target:.2g} s is predicted to pass"
            f"{cost} but {why_not}; give --dt {target:.2g} (and --force above the limits) "
            "to run it. The checks judge this run")

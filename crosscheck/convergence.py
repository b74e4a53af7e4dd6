"""Is an engine's step-halving error estimate the error, at every compared time?

A gate of a whole run (crosscheck.run_gates, crosscheck.halving_gates) takes an engine's
integration error from three runs at h, h/2, h/4 of one scheme of nominal global order p:

    d1(t) = |x_h(t) - x_h/2(t)|,   d2(t) = |x_h/2(t) - x_h/4(t)|

and, over the lowest order the order rows accept (p - 1), the run-wide bound

    E = max_t d2 / (2^(p-1) - 1)          (error of the finest run, halving_gates), or
    E = max_t d1 2^(p-1) / (2^(p-1) - 1)  (error of the coarsest run, run_gates).

A run-wide observed order p_obs = log2(max d1 / max d2) in [p - 1, p + 1] does not show
that this bound holds at *every* compared time: a start transient (generalized-alpha's
first steps on an index-3 DAE, a stiff mode that the coarse step does not resolve yet)
can converge slower than p at a few samples while the rest of the run sets the maxima.
At such a sample the difference between two engines can exceed the gate although both
are right (measured: Exudyn 1.0-4.1 x its gate at t = 0.01 s only, Drake 1.4 x at
t = 0.01 s, on models the gates were not tuned on).

Local check.  At each compared sample i, with window maxima D1_i, D2_i of d1, d2 over the
samples i - WINDOW .. i + WINDOW (a zero crossing of the error's leading term would make a
single sample's ratio meaningless; its neighbours carry the size of the error there), or
i - CROSSING_WINDOW .. i + CROSSING_WINDOW where x_h - x_h/2 or x_h/2 - x_h/4 changes sign
within that wider window (the next error term moves the crossing between the two step
pairs, so d1 and d2 vanish at different samples), the
locally observed contraction r_i = D1_i / D2_i extrapolates the remaining error of the
compared run geometrically (each further halving removes a factor r_i):

    finest run:   e_i = D2_i / (r_i - 1)          coarsest run:  e_i = D1_i r_i / (r_i - 1)

(r_i <= 1: the differences do not shrink there; see "noise" below).  The bound holds at sample i
when e_i <= E + floor (the engine's round-off and solver floor of the column); that is, when
the local order log2(r_i) is at least the order needed there,

    finest:  p_need = log2(1 + D2_i / B)        coarsest: p_need = log2(B / (B - D1_i)),

B = E + floor.  p_need <= p - 1 everywhere and = p - 1 where d is largest, so in the
asymptotic regime every sample passes, and a sample where the error is small needs only
to shrink at all.  Samples whose D2_i is within RESOLVED round-off floors are not judged
(round-off decides their ratio).

Noise.  A sample whose differences do not shrink (r_i <= 1) carries no extrapolation.  In
a column whose run-wide order is inside the accepted band the scheme converges, and what
does not shrink at one sample is noise superposed on a converged solution: round-off
accumulated over the run's steps (it grows as the step shrinks, ~eps N) or the solver's
tolerance.  The compared run's own noise there is at most the largest difference seen,
so e_i = max(D1_i, D2_i).  Measured: Exudyn's flexible crane (n = 3) over 10 s at
4e-5 s (250,000 steps), z4 at t = 6.76 s, r = 0.65 with D2 at 7 % of the bound, which
read as infinite error made the full report fail "NOT CONVERGED".  In a column whose
run-wide order is outside the band, e_i stays infinite (nothing shows that it converges).

A run set passes when its run-wide order (over the resolved columns) is within
ORDER_TOLERANCE of p and no sample fails the local check; otherwise the engine's step is
halved (crosscheck.convergence.refine: the coarsest run is dropped and one at the next
finer step added) within a budget (:class:`RefinementBudget`), and when the budget runs
out the outcome is "not converged", a failed check naming the engine, the time, the local
order and the remedy: never a pass.
"""
from dataclasses import dataclass
from typing import Callable, Mapping, Optional, Sequence

import numpy as np

from gpme_core.errors import SimulationError

ORDER_TOLERANCE = 1.0    # |p_obs - p| <= 1 (the ratio within a factor 2 of 2^p)
RESOLVED = 10.0          # a difference counts when above this many round-off floors
WINDOW = 1               # samples each side of the local window
# samples each side of the window at a zero crossing of the error (a sign change of
# x_h - x_h/2 or x_h/2 - x_h/4 within it): the next error term moves the crossing between
# the step pairs, so the two differences vanish at different samples (measured: Exudyn's
# flexible crane n = 3, z4, d1 changes sign at 6.775 s and d2 at 6.785 s; with +-1 sample
# the window at 6.75 s saw D1 ~ D2, "order 0.06", while the error converges at order 2
# run-wide and at r ~ 3 on both sides of the crossing)
CROSSING_WINDOW = 3
FINEST, COARSEST = "finest", "coarsest"


@dataclass(frozen=True)
class LocalPoint:
    """The sample where a column's error estimate is least supported.

    column : run column;  time : s;  order : local observed order log2(D1/D2) there
    needed : the local order the gate's bound needs there (module docstring)
    ratio  : extrapolated local error / the bound it must stay under (> 1: fails)
    """

    column: str
    time: float
    order: float
    needed: float
    ratio: float

    def describe(self) -> str:
        order = f"{self.order:.2f}" if np.isfinite(self.order) else "none (not shrinking)"
        return (f"{self.column} at t = {self.time:.4g} s: local order {order}, needs >= "
                f"{self.needed:.2f} there (extrapolated error {self.ratio:.2g} x the bound)")


@dataclass(frozen=True)
class Convergence:
    """Whether one engine's three runs are in the asymptotic regime at the compared times.

    order, column, resolved : run-wide observed order over the resolved columns (smallest),
                              the column it comes from, whether any column was resolved
    worst    : the LocalPoint with the largest ratio over all columns (None if no sample
               was resolved)
    nominal  : the scheme's nominal order p
    """

    order: float
    column: Optional[str]
    resolved: bool
    worst: Optional[LocalPoint]
    nominal: float

    @property
    def band_ok(self) -> bool:
        return (not self.resolved) or abs(self.order - self.nominal) <= ORDER_TOLERANCE

    @property
    def local_ok(self) -> bool:
        return self.worst is None or self.worst.ratio <= 1.0

    @property
    def converged(self) -> bool:
        return self.band_ok and self.local_ok

    def decisive_order(self):
        """(order, label) the order row shows: the local order at the failing sample when
        the local check fails, else the run-wide order and its column."""
        if not self.local_ok:
            return self.worst.order, f"{self.worst.column}, t={self.worst.time:.4g}"
        return self.order, str(self.column)

    def describe(self) -> str:
        run_wide = (f"run-wide observed order {self.order:.2f} ({self.column})"
                    if self.resolved else "no column resolved above round-off")
        local = ("; " + ("worst sample " if self.local_ok else "NOT converged at ")
                 + self.worst.describe()) if self.worst is not None else ""
        return run_wide + local


def _window_max(d: np.ndarray, half: int = WINDOW) -> np.ndarray:
    """(samples,) max of d over the samples i - half .. i + half (clipped at the ends)."""
    padded = np.pad(d, half, mode="edge")
    return np.max(np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1), axis=1)


def _sign_changes(d: np.ndarray) -> np.ndarray:
    """(samples,) bool: d changes sign between sample i - 1 and i (zeros skipped)."""
    s = np.sign(d)
    out = np.zeros(len(d), dtype=bool)
    out[1:] = s[1:] * s[:-1] < 0
    return out


def _local_maxima(d1: np.ndarray, d2: np.ndarray) -> tuple:
    """(D1, D2): window maxima of |d1|, |d2| over +-WINDOW samples, and over
    +-CROSSING_WINDOW samples where d1 or d2 (signed) changes sign within that wider window
    (a zero crossing of the error; absolute differences carry no sign and see none)."""
    a1, a2 = np.abs(d1), np.abs(d2)
    flips = (_sign_changes(d1) | _sign_changes(d2)).astype(float)
    near = _window_max(flips, CROSSING_WINDOW) > 0.0
    wide1, wide2 = _window_max(a1, CROSSING_WINDOW), _window_max(a2, CROSSING_WINDOW)
    return (np.where(near, wide1, _window_max(a1)), np.where(near, wide2, _window_max(a2)))


def local_point(column: str, t: np.ndarray, d1: np.ndarray, d2: np.ndarray, order: float,
                floor: float, compared: str, converges: bool = False) -> Optional[LocalPoint]:
    """The worst LocalPoint of one column, or None when no sample is resolved.

    t (samples,) s; d1, d2 (samples,) x_h - x_h/2, x_h/2 - x_h/4 in the column's unit
    (signed: their sign changes mark the error's zero crossings; absolute values are
    accepted and then see none);
    order: nominal p; floor: the engine's round-off (and solver) floor of the column;
    compared: FINEST (halving_gates compares the h/4 runs) or COARSEST (run_gates, h);
    converges: the column's run-wide order is in the accepted band (a sample whose
    differences do not shrink is then noise, bounded by max(D1, D2); module docstring)."""
    if len(t) == 0:
        return None
    D1, D2 = _local_maxima(np.asarray(d1, float), np.asarray(d2, float))
    low = 2.0 ** (order - ORDER_TOLERANCE)
    if compared == FINEST:
        bound = float(np.max(np.abs(d2))) / (low - 1.0) + floor
    elif compared == COARSEST:
        bound = float(np.max(np.abs(d1))) * low / (low - 1.0) + floor
    else:
        raise ValueError(f"compared = {compared!r}; give {FINEST!r} or {COARSEST!r}")
    # a sample where all three runs agree exactly (the common start) is not judged: its
    # window would only repeat its neighbour's verdict at the wrong time
    resolved = (D2 > RESOLVED * floor) & ((np.abs(d1) > 0) | (np.abs(d2) > 0))
    if not resolved.any() or bound <= 0.0:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        r = D1 / D2
        shrinking = r > 1.0
        noise = np.maximum(D1, D2) if converges else np.inf
        if compared == FINEST:
            err = np.where(shrinking, D2 / (r - 1.0), noise)
            needed = np.log2(1.0 + D2 / bound)
        else:
            err = np.where(shrinking, D1 * r / (r - 1.0), noise)
            needed = np.where(D1 < bound, np.log2(bound / np.maximum(bound - D1, 1e-300)),
                              np.inf)
        local = np.where(r > 0, np.log2(r), -np.inf)
    ratio = np.where(resolved, err / bound, -np.inf)
    i = int(np.argmax(ratio))
    return LocalPoint(column, float(t[i]), float(local[i]), float(needed[i]), float(ratio[i]))


def convergence(runs: Sequence, columns: Sequence[str], floors: Mapping[str, float],
                order: float, compared: str) -> Convergence:
    """:class:`Convergence` of three runs (DataFrames at h, h/2, h/4 with column "t" and
    ``columns``, same output times) of a scheme of nominal ``order``; floors {column:
    round-off (+ solver) floor in the column's unit}."""
    t = runs[0]["t"].to_numpy(float)
    best, closest = (np.nan, None), (np.nan, None, -np.inf)
    worst = None
    for c in columns:
        x1, x2, x4 = (r[c].to_numpy(float) for r in runs)
        d1, d2 = x1 - x2, x2 - x4              # signed: local_point finds the crossings
        m1, m2 = float(np.abs(d1).max(initial=0.0)), float(np.abs(d2).max(initial=0.0))
        p = float(np.log2(m1 / m2)) if m1 > 0 and m2 > 0 else np.nan
        f = float(floors.get(c, 0.0))
        above = m2 / f if f > 0 else np.inf
        if np.isfinite(p) and above > closest[2]:
            closest = (p, c, above)
        if np.isfinite(p) and above > RESOLVED and (best[1] is None or p < best[0]):
            best = (p, c)
        converges = bool(np.isfinite(p) and abs(p - order) <= ORDER_TOLERANCE)
        point = local_point(c, t, d1, d2, order, f, compared, converges)
        if point is not None and (worst is None or point.ratio > worst.ratio):
            worst = point
    if best[1] is not None:
        return Convergence(best[0], best[1], True, worst, order)
    return Convergence(closest[0], closest[1], False, worst, order)


@dataclass(frozen=True)
class RefinementBudget:
    """How far an engine's step may be halved to reach the asymptotic regime.

    max_halvings : halvings beyond the first three runs (each adds one run at the next
                   finer step: costs 2, 4, 8 x the finest first run)
    max_run_wall_s : s, a further halving is not made when its run is projected (2 x the
                   last run's wall time) to take longer than this
    """

    max_halvings: int = 3
    max_run_wall_s: float = 120.0

    def describe(self) -> str:
        return (f"at most {self.max_halvings} halvings, no run projected above "
                f"{self.max_run_wall_s:g} s")


@dataclass(frozen=True)
class Refinement:
    """The record of one refinement: steps tried (s, coarsest of each triple), why each
    halving was made, whether the last triple converged, and the budget."""

    steps: tuple
    reasons: tuple
    converged: bool
    budget: RefinementBudget
    stopped_by: str = ""

    @property
    def halvings(self) -> int:
        return len(self.steps) - 1

    def describe(self, engine: str) -> str:
        """Report text of the halvings made ('' when none): how far, why each one."""
        if self.halvings == 0:
            return ""
        return (f"; {engine}'s step halved {self.halvings}x to dt = {self.steps[-1]:.3g} s to "
                f"reach the asymptotic regime ({self.budget.describe()}): "
                + " | ".join(self.reasons))

    def remedy(self, engine: str, key: str) -> str:
        """What a user can do when the budget ran out."""
        finer = self.steps[-1] / 4.0
        return (f"{self.stopped_by}; set a finer first step for {engine} in the model file "
                f"([[engine_step]] engine = \"{engine}\", dt = {finer:.3g}, with the reason; "
                f"docs/models.md), or shorten the compared run ({key})")


def refine(run_at: Callable[[float], object], dt: float, columns: Sequence[str],
           floors_of: Callable[[tuple], Mapping[str, float]], order: float, compared: str,
           budget: RefinementBudget = RefinementBudget(), log=None,
           first: Optional[tuple] = None):
    """(runs (3 DataFrames at h, h/2, h/4), h, Convergence, Refinement).

    run_at(step) -> DataFrame: one run of the engine at that step (attrs wall_time_s);
    dt: s, the first coarsest step; floors_of(runs) -> {column: floor}; first: the three
    first runs when already made.  While the runs are not converged (:class:`Convergence`)
    and the budget allows, h is halved: the coarsest run is dropped and one at the new
    h/4 added.  A first run that fails (SimulationError: the engine's solver gave up) halves
    the first step within the same budget."""
    log = log or (lambda msg: None)
    steps, reasons = [dt], []
    while first is None:
        # an engine's own solver may fail outright at a step too coarse for the model (a
        # Newton iteration that does not converge: a fast-turning mechanism at a step that
        # turns it by a radian); that is the step's fault, not a discrepancy: halve it, as
        # for a run that is not converged, within the same budget
        try:
            first = [run_at(dt / k) for k in (1, 2, 4)]
        except SimulationError as exc:
            if len(steps) - 1 >= budget.max_halvings:
                raise SimulationError(f"{exc} (also after {len(steps) - 1} halvings of the "
                                      f"first step, to {dt:.3g} s)") from exc
            reasons.append(f"h = {dt:.3g} s: a run failed ({str(exc)[:160]})")
            log(f"halving the step: {reasons[-1]}")
            dt /= 2.0
            steps.append(dt)
    runs = list(first)
    while True:
        conv = convergence(runs, columns, floors_of(tuple(runs)), order, compared)
        if conv.converged:
            return tuple(runs), dt, conv, Refinement(tuple(steps), tuple(reasons), True, budget)
        stop = ""
        projected = 2.0 * float(runs[-1].attrs.get("wall_time_s", 0.0))
        if len(steps) - 1 >= budget.max_halvings:
            stop = f"the budget's {budget.max_halvings} halvings are spent"
        elif projected > budget.max_run_wall_s:
            stop = (f"the next run is projected to take {projected:.0f} s, above the budget's "
                    f"{budget.max_run_wall_s:g} s per run")
        if stop:
            return tuple(runs), dt, conv, Refinement(tuple(steps), tuple(reasons), False,
                                                     budget, stop)
        reasons.append(f"h = {dt:.3g} s: {conv.describe()}")
        log(f"halving the step: {reasons[-1]}")
        dt /= 2.0
        steps.append(dt)
        runs = runs[1:] + [run_at(dt / 4.0)]

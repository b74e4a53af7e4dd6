"""The states at which the term-by-term checks compare gpme with an engine (Pinocchio, Drake;
docs/crosscheck-pinocchio.md "States"): a plan (how many states), seeded random states within
a scenario's ranges (crosscheck.sampling.state_ranges) where the GPME is solvable, and states
evenly spaced along a short Radau run from the scenario's start.

    RunPlan, FULL, QUICK   how many random and run states, and the run's length
    state_counts           the plan's counts for a model with n coordinates
    scenario_seed          one seed per scenario name (SEED and a CRC of the name)
    random_states          seeded random states (t, q, q_dot) of a system
    run_states             states along a Radau run of a system
    scenario_states        the random and run states of a scenario under a plan

Imports no engine.
"""
import zlib
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np
from numpy.typing import NDArray

from gpme_core.errors import ConstraintError, SimulationError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate

from .sampling import state_ranges

SEED = 20240611          # of every scenario's random states, with its name (scenario_seed)


@dataclass(frozen=True)
class State:
    """case name (str), t (s), q (n,), q_dot (n,) ordered as the model's coordinates."""

    case: str
    t: float
    q: NDArray[np.float64]
    q_dot: NDArray[np.float64]


def random_states(system: ProgrammedMotion, count: int, rng: np.random.Generator,
                  t_max: float, flexible: Sequence[str] = (), q0: Optional[NDArray] = None,
                  max_draws: Optional[int] = None) -> list:
    """``count`` seeded random states (crosscheck.sampling.state_ranges, t uniform in
    [0, t_max] s) where the GPME is solvable; a draw with a singular dependent block is replaced by
    the next draw, at most ``max_draws`` (default 20 count + 20) draws in all."""
    lo, hi, rate = state_ranges(system.model, flexible, q0)
    max_draws = 20 * count + 20 if max_draws is None else max_draws
    out, draws, last = [], 0, ""
    while len(out) < count:
        if draws >= max_draws:
            raise ConstraintError(f"{system.model.name}: only {len(out)} of {count} random "
                                  f"states are solvable after {draws} draws (last: {last}); "
                                  "the constraints are singular over most of the sampling "
                                  "range (state_ranges)")
        draws += 1
        t = float(rng.uniform(0.0, t_max))
        q = rng.uniform(lo, hi)
        q_dot = rng.uniform(-rate, rate)
        try:
            system.solve(t, q, q_dot)
        except ConstraintError as exc:
            last = str(exc)[:200]
            continue
        out.append(State(f"random {len(out):03d}", t, q, q_dot))
    return out


def run_states(system: ProgrammedMotion, count: int, t_end: float, q0: NDArray,
               q_dot0: NDArray) -> list:
    """``count`` states evenly spaced along a Radau run of ``system`` from (q0, q_dot0).

    Radau with rtol 1e-4: only realistic states are needed here, not an accurate run,
    and RFEM torsion modes (~1e6 rad/s) make explicit integrators crawl.
    """
    df = simulate(system, t_end, q0, q_dot0, method="Radau", output_dt=t_end / count,
                  rtol=1e-4, atol=1e-6)
    names = list(system.model.coordinate_names)
    rows = np.linspace(0, len(df) - 1, count).round().astype(int)
    return [State(f"run t={df['t'].iloc[r]:.4f}", float(df["t"].iloc[r]),
                  df[names].iloc[r].to_numpy(float),
                  df[[f"{n}_dot" for n in names]].iloc[r].to_numpy(float)) for r in rows]


@dataclass(frozen=True)
class RunPlan:
    """How much to compare per model: random states, states along a run of t_run s.
    Scaled down for large models by :func:`state_counts`."""

    n_random: int
    n_run: int
    t_run: float


FULL = RunPlan(n_random=300, n_run=100, t_run=1.0)
QUICK = RunPlan(n_random=3, n_run=2, t_run=0.05)
# The full plan's counts hold up to N_FULL coordinates (the crane with 10 RFEM segments,
# n = 34, ~2 ms per state and case); above, the cost of one state grows ~n^2 (trace-form
# M and h) and the counts shrink as (N_FULL / n)^2, never below MIN_RANDOM + MIN_RUN.
N_FULL = 34
MIN_RANDOM, MIN_RUN = 30, 10


def state_counts(plan: RunPlan, n: int) -> tuple:
    """(random states, run states) of ``plan`` for a model with n coordinates."""
    if n <= N_FULL:
        return plan.n_random, plan.n_run
    f = (N_FULL / n) ** 2
    return (max(min(plan.n_random, MIN_RANDOM), round(plan.n_random * f)),
            max(min(plan.n_run, MIN_RUN), round(plan.n_run * f)))


def scenario_seed(name: str) -> int:
    """Seed of a scenario's random states: SEED and a CRC of its name, so that adding a
    scenario changes no other's states."""
    return zlib.crc32(name.encode("utf-8")) ^ SEED


def scenario_states(scenario, plan: RunPlan) -> list:
    """Random and run states of ``scenario`` under ``plan``."""
    system = scenario.system
    if system.dependent is None:        # the scenario's system is not changed
        system = system.with_pivoted_dependent(0.0, scenario.q0, scenario.q_dot0)
    n_random, n_run = state_counts(plan, system.model.n_coordinates)
    rng = np.random.default_rng(scenario_seed(scenario.name))
    states = random_states(system, n_random, rng, scenario.t_end, scenario.flexible_coordinates,
                           scenario.q0)
    t_run = min(plan.t_run, scenario.t_end)
    try:
        along = run_states(system, n_run, t_run, scenario.q0, scenario.q_dot0)
    except (ConstraintError, SimulationError) as exc:
        raise type(exc)(f"scenario {scenario.name!r}: the Radau run for the states along "
                        f"the run ({t_run:g} s from q0) failed: {exc}") from exc
    return states + along

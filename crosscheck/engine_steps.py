"""The first step and refinement budget of an engine that integrates with its own scheme.

Drake (Runge-Kutta 5) and Exudyn (generalized-alpha) run at a first step h, then h/2, h/4,
and halve further while their runs are not in the asymptotic regime at every compared time
(crosscheck.convergence.refine).  A model file can set the first step and the number of
halvings allowed, with its reason ([[engine_step]], docs/models.md); the report's case text
shows the override and its reason.
"""
from .convergence import RefinementBudget


def engine_first_step(scenario, engine: str, default_dt: float,
                      default_budget: RefinementBudget = RefinementBudget()):
    """(dt s, note for the report's case text, RefinementBudget) of ``engine`` for
    ``scenario``: the model file's [[engine_step]] for that engine when it has one, else
    ``default_dt`` and ``default_budget`` with an empty note."""
    steps = getattr(scenario, "engine_steps", None) or {}
    override = steps.get(engine)
    if override is None:
        return float(default_dt), "", default_budget
    budget = default_budget if override.max_halvings is None else RefinementBudget(
        override.max_halvings, default_budget.max_run_wall_s)
    note = (f" ({engine}'s first step {override.dt:g} s set for this model ([[engine_step]]): "
            f"{override.reason})")
    return float(override.dt), note, budget

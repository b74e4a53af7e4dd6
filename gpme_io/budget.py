"""The command line's budget for one run: its estimated cost printed before it starts, and a
refusal above the limits unless ``--force`` is given (gpme_core.run_cost estimates it); and
the budget of `gpme simulate`'s search for an accurate default step (crosscheck/accurate_step.py):
at most MAX_STEP_HALVINGS halvings, all runs of a model within MAX_WALL_S."""
import sys

from gpme_core.errors import GpmeError
from gpme_core.run_cost import format_seconds

# s: a run estimated to take longer is refused without --force (an hour: a verification or a
# study run; longer runs are deliberate and should say so)
MAX_WALL_S = 3600.0
# s: a run still going after this long is stopped unless --force (the estimate of an adaptive
# method is a lower bound or unknown; RK4's may be off by the machine's load, hence 2x)
RUN_WALL_LIMIT_S = 2 * MAX_WALL_S
# bytes: a run whose history CSV is estimated above this is refused without --force
MAX_CSV_BYTES = 2e9
# halvings of the starting RK4 step `gpme simulate` may make to meet its own checks
# (crosscheck/accurate_step.py): the default step is at least 1/16 of the scenario's, a run of at
# most 16x its steps (RK4's errors then fall by 16^4 ~ 6.6e4 in the asymptotic regime)
MAX_STEP_HALVINGS = 4


class BudgetError(GpmeError):
    """A run is estimated above the command line's limits (the message gives the estimate,
    the limit, how to reduce it, and --force)."""


def over_budget(cost):
    """Problems of ``cost`` (a gpme_core.run_cost.RunCost) against the limits ([] if none)."""
    problems = []
    if cost.wall_s is not None and cost.wall_s > MAX_WALL_S:
        problems.append(f"an estimated wall time of {_hours(cost.wall_s)} is above the "
                        f"limit of {_hours(MAX_WALL_S)}")
    if cost.csv_bytes > MAX_CSV_BYTES:
        problems.append(f"an estimated history of {cost.csv_bytes / 1e9:.3g} GB is above the "
                        f"limit of {MAX_CSV_BYTES / 1e9:g} GB")
    return problems


def step_search_problem(spent_s, cost, force=False):
    """The reason (str) a further run of `gpme simulate`'s step search, estimated at ``cost``
    (a gpme_core.run_cost.RunCost), does not fit its budget after ``spent_s`` s of runs: all
    runs of one model together within MAX_WALL_S, as one run is; None when it fits or with
    ``force``."""
    if force or cost.wall_s is None:
        return None
    if spent_s + cost.wall_s > MAX_WALL_S:
        return (f"it is estimated at {format_seconds(cost.wall_s)} after "
                f"{format_seconds(spent_s)} of runs, above the limit of {_hours(MAX_WALL_S)} "
                "for all runs of a model")
    return None


def _hours(s):
    return f"{s / 3600:.3g} h" if s >= 3600 else f"{s / 60:.3g} min"


def wall_limit(force):
    """s: the ``max_wall_s`` of gpme_core.integrate.simulate for a command (None with
    --force)."""
    return None if force else RUN_WALL_LIMIT_S


def run_budget(label, force=False, out=None):
    """A ``before_run`` callable for gpme_core.integrate.simulate: prints the estimate of run
    ``label`` (to ``out``, default the sys.stdout of the moment) and raises BudgetError above
    the limits unless ``force``."""
    def check(cost):
        stream = sys.stdout if out is None else out
        print(f"  estimate: {cost.describe()}", file=stream, flush=True)
        problems = over_budget(cost)
        if problems and not force:
            raise BudgetError(
                f"{label}: {' and '.join(problems)} ({cost.describe()}). Shorten t_end "
                "(--t-end), raise the step (--dt, within its stability limit) or the "
                "recording interval, use fewer RFEM segments, or give --force to run it "
                "anyway")
        if problems:
            print(f"  --force: running although {' and '.join(problems)}", file=stream,
                  flush=True)
    return check

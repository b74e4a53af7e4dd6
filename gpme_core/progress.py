"""Progress of a run as events for a caller's callback (the ``progress`` argument of
gpme_core.integrate.simulate): the engine reports, it draws no bar and prints nothing.
A terminal's bar and a log's lines are gpme_io.progress.

Events, in the order a run sends them:

* :class:`Compiling` (``finished=False``, then ``finished=True`` with the time it took),
  only when the run's first evaluation compiles the numba kernels (or loads them from
  their disk cache) in this process;
* :class:`Progress`: one with ``done = 0`` when the integration starts, then after every
  step (RK4 in Python), every recorded interval (the compiled loops) or every
  1/SCIPY_PROGRESS_UNITS of t_end reached (solve_ivp), and a last one with
  ``finished=True`` when the run ends, also when it fails.

A callback should be cheap (the Python RK4 loop calls it every step) and must not raise:
an exception from it ends the run.
"""
from dataclasses import dataclass
from typing import Callable, Union


@dataclass(frozen=True)
class Progress:
    """Where a run is.

    method : the integrator ("RK4", "RadauIIA", "RK45", ...)
    done   : units done of ``total``: steps for the fixed-step methods, parts of t_end for
             the solve_ivp methods (whose steps are not known before the run)
    total  : units of the whole run
    t      : s, the time reached (t_end done / total)
    t_end  : s, the end of the run
    wall_s : s, wall time since the integration started (compilation is before it)
    finished: True on the run's last event (after its last step, or when it failed)
    """
    method: str
    done: int
    total: int
    t: float
    t_end: float
    wall_s: float
    finished: bool = False


@dataclass(frozen=True)
class Compiling:
    """The run's first evaluation compiles the numba kernels (first call in this process;
    numba keeps them on disk for the next).

    finished : False before the compilation, True after it
    wall_s   : s, how long it took (0.0 before)
    """
    finished: bool
    wall_s: float = 0.0


ProgressEvent = Union[Progress, Compiling]
# what simulate's ``progress`` is: called with each event, returns nothing
ProgressCallback = Callable[[ProgressEvent], None]

"""Where the term-by-term crosschecks draw their random states: one rule for every engine.

    coordinate                      q drawn uniformly in                   q_dot in
    finite limits [lo, hi]          [lo, hi]                               +-1 rad/s or m/s
    revolute, an open end           q0 +- pi rad (cut at a finite end)     +-1 rad/s
    prismatic, an open end          q0 +- 0.2 m (cut at a finite end)      +-1 m/s
    RFEM angle (psi, theta, phi)    spring reference +- 0.02 rad           +-2 rad/s
                                    (within limits, if any)

0.02 rad is ~5x the static bending of the crane's arm per element (~0.004 rad); 2 rad/s is
~7x the rates its runs reach (~0.3 rad/s).  The terms are exact functions of the state, so
the ranges only need to be realistic and to exercise every term, not to be reachable.
Imports neither Pinocchio nor MuJoCo.
"""
from typing import Optional, Sequence

import numpy as np
from numpy.typing import NDArray

RFEM_ANGLE = 0.02         # rad, RFEM angles within +-this of their spring reference
RFEM_RATE = 2.0           # rad/s
RATE = 1.0                # rad/s or m/s, every other coordinate
OPEN_REVOLUTE = np.pi     # rad around q0 where a revolute joint has no (finite) limit
OPEN_PRISMATIC = 0.2      # m around q0 where a prismatic joint has no (finite) limit


def flexible_coordinates(model) -> tuple:
    """Names of the RFEM coordinates of ``model`` (every sde's psi, theta, phi), in model order."""
    return model.flexible_coordinates


def state_ranges(model, flexible: Optional[Sequence[str]] = None,
                 q0: Optional[NDArray] = None):
    """(lo (n,), hi (n,), rate (n,)) of the random states (module docstring), SI units.

    flexible : RFEM coordinate names; None: those of model.flexible_links
    q0       : (n,) centre of the open ranges; None: zeros
    Raises ValueError naming the coordinates whose range is empty (q0 outside its limits).
    """
    n = model.n_coordinates
    flexible = flexible_coordinates(model) if flexible is None else tuple(flexible)
    q0 = np.zeros(n) if q0 is None else np.asarray(q0, dtype=float)
    lo, hi = model.lower_limits.copy(), model.upper_limits.copy()
    flex = np.array([name in set(flexible) for name in model.coordinate_names], dtype=bool)
    half = np.where(flex, RFEM_ANGLE, np.where(model.is_revolute, OPEN_REVOLUTE, OPEN_PRISMATIC))
    centre = np.where(flex, model.spring_reference, q0)
    rate = np.where(flex, RFEM_RATE, RATE)
    open_lo, open_hi = ~np.isfinite(lo) | flex, ~np.isfinite(hi) | flex
    lo = np.where(open_lo, np.maximum(centre - half, lo), lo)
    hi = np.where(open_hi, np.minimum(centre + half, hi), hi)
    bad = [model.coordinate_names[k] for k in np.flatnonzero(~(lo < hi))]
    if bad:
        raise ValueError(f"{model.name}: empty sampling range for {bad} (q0 outside its "
                         "limits?)")
    return lo, hi, rate


# s, spacing of the samples at which two engines' runs are compared
COMPARED_DT = 1e-2
# samples a run shorter than MIN_COMPARED_SAMPLES x COMPARED_DT is compared at instead
MIN_COMPARED_SAMPLES = 10


def compared_output_dt(t_run: float, dt: float) -> float:
    """s, spacing of the compared samples of a run of t_run s at a step of dt s: COMPARED_DT
    when the run holds at least MIN_COMPARED_SAMPLES of them, else the spacing that gives
    it about that many (a benchmark of milliseconds, a short quick run); always a whole
    number of steps dt that divides the run (every engine's step halvings keep both)."""
    t_run, dt = float(t_run), float(dt)
    if t_run >= MIN_COMPARED_SAMPLES * COMPARED_DT - 1e-12:
        return COMPARED_DT
    steps = max(1, int(round(t_run / dt)))
    per_sample = max(1, steps // MIN_COMPARED_SAMPLES)
    while steps % per_sample:
        per_sample -= 1
    return per_sample * dt

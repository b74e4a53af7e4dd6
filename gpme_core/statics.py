"""Static equilibrium of some coordinates with the others held: the gravity sag of a
flexible link before a run starts (so that it does not ring from an undeformed start).

Solves  g_F(q) + f_F(q) - t_F(t) = 0  for the coordinates F (gravity, springs, drives at
time t; velocities zero) by Newton's method with a central-difference Jacobian.
"""
import numpy as np

from .dynamics import gravity_forces, spring_forces
from .errors import ConstraintError, ModelError


def _residual(model, q, free, t):
    return (gravity_forces(model, q) + spring_forces(model, q) - model.drive_forces(t))[free]


def newton_equilibrium(residual, q, free, tol, max_iter=30, step=1e-7):
    """(n,) q with the coordinates at indices ``free`` moved so that residual(q) (a
    (len(free),) generalized force, N or N m) is below ``tol`` in every entry, the rest as
    given; None when Newton's method (central-difference Jacobian, step ``step`` rad or m) does not get there in ``max_iter`` steps, meets a non-finite residual or a
    singular Jacobian.  The one Newton loop of the statics: :func:`static_equilibrium` and
    the benchmarks that need another residual (crosscheck.continuum.bend45) share it."""
    q = np.array(q, dtype=float)
    for _ in range(max_iter):
        r = residual(q)
        if not np.all(np.isfinite(r)):
            return None
        if np.abs(r).max() < tol:
            return q
        jac = np.empty((free.size, free.size))
        for j, k in enumerate(free):
            dq = np.zeros_like(q)
            dq[k] = step
            jac[:, j] = (residual(q + dq) - residual(q - dq)) / (2 * step)
        try:
            q[free] -= np.linalg.solve(jac, r)
        except np.linalg.LinAlgError:
            return None
    return None


def static_equilibrium(model, q, coordinates, t=0.0, tol=1e-10, max_iter=30, step=1e-7):
    """(n,) q with ``coordinates`` (names) moved to static equilibrium, the rest as given.

    tol: N or N m on the largest residual generalized force.  Raises ConstraintError when
    Newton's method does not converge (e.g. a coordinate with no restoring spring).
    """
    q = np.array(q, dtype=float)
    free = np.array([model.index(c) for c in coordinates], dtype=int)
    if free.size == 0:
        return q
    if q.shape != (model.n_coordinates,):
        raise ModelError(f"q must have shape ({model.n_coordinates},), got {q.shape}")
    solved = newton_equilibrium(lambda x: _residual(model, x, free, t), q, free, tol,
                                max_iter, step)
    if solved is not None:
        return solved
    raise ConstraintError(
        f"no static equilibrium of {list(coordinates)} found at t = {t:g} s (largest residual "
        f"{np.abs(_residual(model, q, free, t)).max():.3e} at the start); coordinates without "
        "a restoring spring have none")

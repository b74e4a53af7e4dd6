"""Which constraints make the constraint Jacobian A (m, n) rank-deficient, in words.

When A has rank < m no choice of dependent coordinates can realise the constraints: either
some constraints are dependent (a combination of their rows vanishes: ``x - 0.3`` and
``2*x - 0.6`` fix the same motion) or a constraint has a zero row (no coordinate moves
it).  :func:`dependence_problem` names them from A's singular value decomposition:
each left singular vector u of a negligible singular value gives the relation
sum_i u_i row_i = 0, whose non-negligible u_i name the dependent constraints.
"""
from typing import Optional, Sequence

import numpy as np

# A negligible singular value: at most this fraction of the largest (the same bound as the
# pivoted QR of gpme_core.gpme, SINGULAR_RCOND: 1e-10, ~6 digits above float64 round-off)
NEGLIGIBLE = 1e-10
# weights of a relation below this fraction of its largest weight are round-off, not a
# constraint taking part in it
WEIGHT_FLOOR = 1e-6


def dependence_problem(a: np.ndarray, names: Sequence[str], t: float,
                       q: Optional[np.ndarray] = None) -> Optional[str]:
    """None when A (m, n) has full row rank m, else a message naming the constraints.

    a     : (m, n) constraint Jacobian, rows ordered as ``names`` (units of each row: the
            constraint's unit per coordinate unit)
    names : the m constraint names
    t     : s, and q (n,) the state, for the message
    """
    a = np.asarray(a, dtype=float)
    m = a.shape[0]
    if m == 0 or not np.isfinite(a).all():
        return None
    u, sigma, _ = np.linalg.svd(a, full_matrices=True)
    sigma = np.concatenate([sigma, np.zeros(m - len(sigma))])
    top = float(sigma.max())
    small = [k for k in range(m) if sigma[k] <= NEGLIGIBLE * max(top, 1e-300)]
    if not small:
        return None
    row_norms = np.linalg.norm(a, axis=1)
    where = f"at t = {t:.6g} s" + ("" if q is None else
                                   f", q = {np.round(np.asarray(q, float), 6).tolist()}")
    parts = []
    zero = [k for k in range(m) if row_norms[k] <= NEGLIGIBLE * max(top, 1e-300)]
    for k in zero:
        parts.append(f"constraint {names[k]!r} has a zero Jacobian row: no coordinate moves "
                     "it here (its gradient is perpendicular to every motion of its frame, "
                     "or it does not depend on the coordinates)")
    seen = set()
    for k in small:
        w = u[:, k].copy()
        w[zero] = 0.0
        if not np.abs(w).max() > 0.0:
            continue
        w /= w[np.argmax(np.abs(w))]
        members = tuple(i for i in range(m) if abs(w[i]) > WEIGHT_FLOOR)
        if len(members) < 2 or members in seen:
            continue
        seen.add(members)
        relation = " ".join(f"{'-' if w[i] < 0 else '+'} {_times(abs(w[i]))}row({names[i]!r})"
                            for i in members).lstrip("+ ")
        listed = ", ".join(repr(names[i]) for i in members[:-1]) + f" and {names[members[-1]]!r}"
        parts.append(f"the constraints {listed} are dependent: {relation} = 0 (they "
                     "restrict the same motion; remove one or make them independent)")
    rank = m - len(small)
    return (f"{where} the constraint Jacobian has rank {rank} < {m} constraints "
            f"(smallest singular value {sigma.min():.2g}, largest {top:.2g}): "
            + "; ".join(parts) + "; no choice of dependent coordinates can realise them")


def _times(c: float) -> str:
    """'' for a coefficient of 1 (to 6 digits), else '0.5 x '."""
    return "" if f"{c:.6g}" == "1" else f"{c:.6g} x "

"""The tolerance policy of the term-by-term checks, shared by the Pinocchio and Drake checks
(docs/crosscheck-pinocchio.md "Tolerances, reasons and measured margins"), each tolerance
with its reason:

    TOLERANCES         the closed-form quantities both sides evaluate (poses, frames, M, g, h):
                       round-off only; keyed by the Pinocchio check's quantity names (the Drake
                       check takes them under its own: "bias term C(q,v) v" is h, ...)
    solve_tolerances   the quantities from a linear solve with M, per state: from cond(M),
                       and with constraints from cond(L) of the reduced GPME (reduced_matrix)

A quantity only one engine compares keeps its tolerance in that engine's check (Pinocchio's
applied tau and constraint terms, Drake's spring and damper forces and inverse dynamics).
Imports no engine.
"""
import numpy as np
from numpy.typing import NDArray

from .compare import Tolerance

_ROUND_OFF = ("round-off only: both engines evaluate the same closed-form quantity in double "
              "precision through ~n products of 4x4 transforms or spatial recursions")
_FORCE = ("round-off only: sums of products of inertia, transforms and velocities; normwise "
          "relative to the largest entry")
EPS = np.finfo(float).eps
# eps cond_2(X) is the first-order relative forward error, in the 2-norm, of one
# backward-stable solve with X (an estimate rather than a bound).  The rows measure
# max|dx| / max|x| <= sqrt(n) ||dx||_2 / ||x||_2, hence the factor sqrt(n); two engines'
# errors add (x2) and the estimate's constant gets a margin of 4: SOLVE_FACTOR = 8.
SOLVE_FACTOR = 8.0
_SOLVE = ("linear solve with M (aba in Pinocchio, Cholesky in gpme): forward error ~eps "
          "cond(M) relative; an RFEM link makes M ill-conditioned (element torsion inertias "
          "~1e-9 kg m^2 beside kilograms of robot: cond(M) up to ~3e7 for the crane with "
          "n = 10); tol_rel = max(1e-12, 8 sqrt(n) eps cond_2(M)) (sqrt(n): 2-norm to max-entry "
          "error; x2 two engines, x4 margin), here cond(M) = {cond:.1e}, n = {n}")
_SOLVE_CONSTRAINED = (
    "constrained solve: Pinocchio's forwardDynamics (Cholesky of M, then of the Delassus "
    "matrix D = A M^-1 A^T), error ~eps max(cond(M), cond(D)); gpme's reduced GPME solves "
    "L = [N^T M; A] (N = [I; Gamma], Gamma = -A_dc^-1 A_ic), error ~eps cond(L), and cond(L) "
    "exceeds cond(M) where Gamma is large; tol_rel = max(1e-12, 8 sqrt(n) eps "
    "max(cond_2(M), cond_2(L), cond_2(D))) (sqrt(n): 2-norm to max-entry error; x2 two "
    "engines, x4 margin), here cond(M) = {cond:.1e}, cond(L) = {cond_l:.1e}, "
    "cond(D) = {cond_d:.1e}, n = {n}")
_MULTIPLIER = ("; lambda = A_dc^-T F_dc inherits the reaction error: tol_abs = tol_rel "
               "max|A^T lambda| ||A_dc^-T||_inf = {tol:.1e}")
# Each tolerance: abs (in the quantity's unit, a floor for exact zeros such as h at rest)
# and rel (normwise, to the largest entry of the engine's value), with its reason.
TOLERANCES = {
    "pose position": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m)"),
    "pose rotation": Tolerance(1e-14, 1e-12, _ROUND_OFF),
    "M": Tolerance(1e-14, 1e-12, _FORCE + " (kg, kg m, kg m^2)"),
    "g": Tolerance(1e-12, 1e-12, _FORCE + " (N, N m)"),
    "h": Tolerance(1e-12, 1e-11, _FORCE + "; h cancels terms of size |M| |q_dot|^2, which "
                   "can be 100x its result (crane: measured up to 5e-13)"),
    "frame position": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m)"),
    "frame velocity": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m/s)"),
    "frame jacobian": Tolerance(1e-14, 1e-12, _ROUND_OFF + " (m or m/rad)"),
    "frame drift": Tolerance(1e-12, 1e-11, _ROUND_OFF + "; the drift sums ~n^2 velocity "
                             "products (m/s^2)"),
}


def reduced_matrix(m: NDArray[np.float64], a: NDArray[np.float64], ic: NDArray[np.intp],
                   dc: NDArray[np.intp]) -> NDArray[np.float64]:
    """(n, n) L = [M[ic] + Gamma^T M[dc]; A], Gamma = -A_dc^-1 A_ic: the matrix of the
    reduced GPME (paper eq. 7), built from the other engine's M and the reference A only to
    bound gpme's solve error by its condition number (not used for any compared value)."""
    gamma = -np.linalg.solve(a[:, dc], a[:, ic])
    return np.vstack([m[ic] + gamma.T @ m[dc], a])


def solve_tolerances(m: NDArray[np.float64], reactions: NDArray[np.float64],
                     a: NDArray[np.float64], ic: NDArray[np.intp],
                     dc: NDArray[np.intp]) -> dict:
    """{quantity: Tolerance} of the quantities from a linear solve with M at one state:
    "free q_ddot" and, with constraints (k > 0), "constrained q_ddot", "reactions A^T
    lambda" and "multipliers lambda".

    m (n, n) mass matrix, reactions (n,) A^T lambda (N, N m), a (k, n) constraint
    Jacobian, ic / dc index arrays of the independent / dependent coordinates.
    free q_ddot: rel = max(1e-12, 8 sqrt(n) eps cond_2(M)).  Constrained q_ddot, reactions
    and multipliers: rel = max(1e-12, 8 sqrt(n) eps max(cond_2(M), cond_2(L), cond_2(D))), L
    the reduced GPME matrix (:func:`reduced_matrix`), D = A M^-1 A^T the Delassus matrix of
    Pinocchio's solve; the multipliers get abs = rel max|A^T lambda|
    ||A_dc^-T||_inf as well, because lambda = A_dc^-T (A^T lambda)_dc can be small beside
    the reactions.
    """
    n = m.shape[0]
    factor = SOLVE_FACTOR * np.sqrt(n) * EPS
    cond = float(np.linalg.cond(m))
    rel = max(1e-12, factor * cond)
    out = {"free q_ddot": Tolerance(1e-12, rel, _SOLVE.format(cond=cond, n=n) +
                                    " (m/s^2, rad/s^2)")}
    if a.shape[0] == 0:
        return out
    cond_l = float(np.linalg.cond(reduced_matrix(m, a, ic, dc)))
    # the Delassus matrix Pinocchio's forwardDynamics factorises (Andrews' mechanism at a
    # random state: cond(M) = 94, cond(L) = 220, cond(D) = 2.1e5, and the engines differ
    # by 2.1e-12 of max|q_ddot|, above eps cond(L) but well inside eps cond(D))
    cond_d = float(np.linalg.cond(a @ np.linalg.solve(m, a.T)))
    rel_c = max(1e-12, factor * max(cond, cond_l, cond_d))
    reason = _SOLVE_CONSTRAINED.format(cond=cond, cond_l=cond_l, cond_d=cond_d, n=n)
    lam_abs = rel_c * float(np.max(np.abs(reactions))) * float(
        np.linalg.norm(np.linalg.inv(a[:, dc]).T, np.inf))
    out.update({
        "constrained q_ddot": Tolerance(1e-12, rel_c, reason + " (m/s^2, rad/s^2)"),
        "reactions A^T lambda": Tolerance(1e-12, rel_c, reason + " (N, N m)"),
        "multipliers lambda": Tolerance(max(1e-12, lam_abs), rel_c, reason +
                                        _MULTIPLIER.format(tol=lam_abs) +
                                        " (N or N m per unit of the constraint)")})
    return out

"""Generalized programmed motion equations (GPME) in reduced form (paper eqs. 3, 6, 7).

Constraints Phi(q, t) = 0 (m rows) with Phi_dot = A q_dot + Phi_t and
Phi_ddot = A q_ddot + kappa.  The coordinates are split into independent ones (ic) and
dependent ones (dc, m of them); A_dc (m, m) must be regular.  Then

    dq_dot_dc / dq_dot_ic = Gamma = -A_dc^-1 A_ic                     (paper eq. 6)
    N = [I ; Gamma] (n, n - m)   (rows ordered as q; A N = 0)

and the reduced equations, reactions eliminated, are (paper eq. 7, Lagrange form):

    N^T M q_ddot = N^T (h + Q)                                   (n - m rows)
    A q_ddot     = -kappa - 2 alpha Phi_dot - beta^2 Phi          (m rows, Baumgarte)

The constraint reactions follow from the solution: F_r = M q_ddot - (h + Q) = A^T lambda
(generalized forces that realise the programmed motion), lambda = A_dc^-T F_r[dc].

Baumgarte stabilisation: Phi_ddot + 2 alpha Phi_dot + beta^2 Phi = 0 (alpha, beta in 1/s).
"""
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from . import fast
from .constraints import bind_constraints, evaluate_constraints
from .dynamics import dynamics_terms
from .errors import ConstraintError, ModelError

# A_dc with a reciprocal condition number below this is treated as singular: the
# dependent velocities would lose more than ~10 of 16 significant digits.
SINGULAR_RCOND = 1e-10
DAMPING_FORMS = ("lagrange", "paper-eq7")


@dataclass(frozen=True)
class GpmeSolution:
    """Everything computed at one (t, q, q_dot).  Shapes: n coordinates, m constraints.

    q_ddot (n,), phi (m,), phi_dot (m,), jacobian A (m, n), kappa (m,), multipliers (m,),
    reaction_forces (n,) = A^T multipliers, terms: the DynamicsTerms used.
    """

    t: float
    q_ddot: np.ndarray
    phi: np.ndarray
    phi_dot: np.ndarray
    jacobian: np.ndarray
    kappa: np.ndarray
    multipliers: np.ndarray
    reaction_forces: np.ndarray
    terms: object


class ProgrammedMotion:
    """A model with programmed constraints, reduced to its GPME form.

    model      : gpme_core.model.Model
    constraints: sequence of constraint specs (gpme_core.constraints)
    dependent  : names of the m dependent coordinates, or None to choose them by pivoting
                 on the constraint Jacobian (call :meth:`choose_dependent` with a state,
                 done automatically by gpme_core.integrate.simulate)
    baumgarte  : (alpha, beta) in 1/s for Phi_ddot + 2 alpha Phi_dot + beta^2 Phi = 0
    damping_form: "lagrange" (default, what Lagrange's equations give) or "paper-eq7"
                 (adds the paper's sum_j q_dot_j dQ_j/dq_dot_i term literally, which counts
                 the damper forces twice; kept only to demonstrate docs/paper-notes.md)
    """

    def __init__(self, model, constraints=(), dependent=None, baumgarte=(20.0, 20.0),
                 damping_form="lagrange"):
        self.model = model
        self.constraint_specs = tuple(constraints)
        self.bound = bind_constraints(model, self.constraint_specs)
        self.constraint_names = tuple(b.name for b in self.bound)
        self.n_constraints = len(self.bound)
        alpha, beta = baumgarte
        problems = []
        if not (np.isfinite(alpha) and alpha >= 0 and np.isfinite(beta) and beta >= 0):
            problems.append(f"Baumgarte parameters must be finite and >= 0 (1/s), got "
                            f"alpha={alpha!r}, beta={beta!r}")
        if damping_form not in DAMPING_FORMS:
            problems.append(f"damping_form must be one of {DAMPING_FORMS}, got {damping_form!r}")
        if self.n_constraints > model.n_coordinates:
            problems.append(f"{self.n_constraints} constraints on {model.n_coordinates} "
                            "coordinates: at most as many constraints as coordinates")
        if problems:
            raise ModelError(problems)
        self.alpha, self.beta = float(alpha), float(beta)
        self.damping_form = damping_form
        self.dependent = None
        if dependent is not None:
            self.set_dependent(dependent)
        elif self.n_constraints == 0:
            self.set_dependent(())

    # --------------------------------------------------------------- partition
    def set_dependent(self, names):
        """Fix the dependent coordinates by name (m of them)."""
        names = tuple(names)
        if len(names) != self.n_constraints or len(set(names)) != len(names):
            raise ModelError(f"need {self.n_constraints} distinct dependent coordinates "
                             f"(one per constraint {list(self.constraint_names)}), got {list(names)}")
        dc = np.array([self.model.index(nm) for nm in names], dtype=int)
        self.dependent = names
        self.dc = dc
        self.ic = np.array([k for k in range(self.model.n_coordinates) if k not in set(dc)],
                           dtype=int)
        self.independent = tuple(self.model.coordinate_names[k] for k in self.ic)

    def choose_dependent(self, t, q, q_dot=None):
        """Pick dependent coordinates by column-pivoted QR of A(q, t); returns their names."""
        if self.n_constraints == 0:
            self.set_dependent(())
            return ()
        q_dot = np.zeros_like(q) if q_dot is None else q_dot
        _, _, a, _ = self.constraints(t, q, q_dot)
        _, r, piv = sla.qr(a, pivoting=True, mode="economic")
        diag = np.abs(np.diag(r))
        if diag.min() <= SINGULAR_RCOND * max(diag.max(), 1e-300):
            raise ConstraintError(
                f"at t = {t:.6g} s the constraint Jacobian has rank < {self.n_constraints}: "
                f"the constraints {list(self.constraint_names)} are dependent or cannot be "
                f"controlled by any coordinate at q = {np.round(q, 6).tolist()}")
        names = [self.model.coordinate_names[k] for k in piv[:self.n_constraints]]
        self.set_dependent(names)
        return tuple(names)

    def _require_partition(self):
        if self.dependent is None:
            raise ModelError("dependent coordinates not chosen: pass dependent=[...] or call "
                             "choose_dependent(t, q) first")

    # --------------------------------------------------------------- evaluation
    def constraints(self, t, q, q_dot, kin=None):
        """(Phi (m,), Phi_dot (m,), A (m, n), kappa (m,))."""
        if kin is None:
            from .kinematics import chain_kinematics
            kin = chain_kinematics(self.model, q)
        return evaluate_constraints(self.model, self.bound, t, kin, np.asarray(q_dot, float))

    def velocity_map(self, a, t=0.0, q=None):
        """Gamma = dq_dot_dc/dq_dot_ic = -A_dc^-1 A_ic (m, n - m), checking A_dc."""
        self._require_partition()
        a_dc = a[:, self.dc]
        try:
            inv = np.linalg.inv(a_dc)    # m x m, m small: explicit inverse is cheapest
        except np.linalg.LinAlgError:
            inv = np.full_like(a_dc, np.inf)
        rcond = _rcond(a_dc, inv)
        if not rcond > SINGULAR_RCOND:
            qs = "" if q is None else f" at q = {np.round(q, 6).tolist()}"
            raise ConstraintError(
                f"at t = {t:.6g} s the dependent block K_dc of the constraint Jacobian "
                f"(columns {list(self.dependent)}) is singular (reciprocal condition "
                f"{rcond:.2e} <= {SINGULAR_RCOND:.0e}){qs}: these coordinates cannot realise "
                "the constraints here; choose other dependent coordinates or keep the "
                "programmed path away from this configuration")
        return -inv @ a[:, self.ic], inv

    def solve(self, t, q, q_dot):
        """:class:`GpmeSolution` of the reduced equations at (t, q, q_dot)."""
        self._require_partition()
        q = np.asarray(q, dtype=float)
        q_dot = np.asarray(q_dot, dtype=float)
        terms = dynamics_terms(self.model, t, q, q_dot)
        rhs = terms.rhs
        if self.damping_form == "paper-eq7":
            rhs = rhs - terms.d   # + sum_j q_dot_j dQ_j/dq_dot_i = -D q_dot, taken literally
        n, m = self.model.n_coordinates, self.n_constraints
        if m == 0:
            q_ddot = _solve_spd(terms.M, rhs, t, q)
            z = np.zeros(0)
            return GpmeSolution(t, q_ddot, z, z, np.zeros((0, n)), z, z, np.zeros(n), terms)
        phi, phi_dot, a, kappa = self.constraints(t, q, q_dot, terms.kin)
        constraint_rhs = -kappa - 2.0 * self.alpha * phi_dot - self.beta ** 2 * phi
        if fast.ENABLED:
            q_ddot, lam, rcond, ok = fast.reduced_solve(terms.M, rhs, a, constraint_rhs,
                                                        self.ic, self.dc)
            if not rcond > SINGULAR_RCOND:
                self.velocity_map(a, t, q)      # raises the ConstraintError with details
            if not ok:
                raise ConstraintError(f"at t = {t:.6g} s the reduced GPME matrix is singular "
                                      f"at q = {np.round(q, 6).tolist()}")
            return GpmeSolution(t, q_ddot, phi, phi_dot, a, kappa, lam, a.T @ lam, terms)
        gamma, inv_dc = self.velocity_map(a, t, q)
        # N^T X for X with rows ordered as q: X[ic] + Gamma^T X[dc]
        proj_m = terms.M[self.ic] + gamma.T @ terms.M[self.dc]
        proj_rhs = rhs[self.ic] + gamma.T @ rhs[self.dc]
        lhs = np.empty((n, n))
        lhs[:n - m] = proj_m
        lhs[n - m:] = a
        b = np.empty(n)
        b[:n - m] = proj_rhs
        b[n - m:] = constraint_rhs
        try:
            q_ddot = np.linalg.solve(lhs, b)
        except np.linalg.LinAlgError:
            raise ConstraintError(f"at t = {t:.6g} s the reduced GPME matrix is singular at "
                                  f"q = {np.round(q, 6).tolist()}") from None
        reaction = terms.M @ q_ddot - rhs
        lam = inv_dc.T @ reaction[self.dc]
        return GpmeSolution(t, q_ddot, phi, phi_dot, a, kappa, lam, a.T @ lam, terms)

    def accelerations(self, t, q, q_dot):
        """(n,) q_ddot from the reduced GPME form."""
        return self.solve(t, q, q_dot).q_ddot

    def kkt_accelerations(self, t, q, q_dot):
        """(q_ddot (n,), lambda (m,)) from the Lagrange-multiplier (KKT) form, same Baumgarte:

            [M  -A^T] [q_ddot]   [h + Q]
            [A    0 ] [lambda] = [-kappa - 2 alpha Phi_dot - beta^2 Phi]

        Independent of the reduced form; used to check it."""
        terms = dynamics_terms(self.model, t, q, q_dot)
        n, m = self.model.n_coordinates, self.n_constraints
        phi, phi_dot, a, kappa = self.constraints(t, q, q_dot, terms.kin)
        k = np.zeros((n + m, n + m))
        k[:n, :n] = terms.M
        k[:n, n:] = -a.T
        k[n:, :n] = a
        rhs = np.concatenate([terms.rhs, -kappa - 2 * self.alpha * phi_dot - self.beta ** 2 * phi])
        sol = np.linalg.solve(k, rhs)
        return sol[:n], sol[n:]

    # --------------------------------------------------------------- initial states
    def consistent_state(self, t, q, q_dot, tol=1e-12, max_iter=50):
        """(q, q_dot) on the constraint manifold at time t: the dependent coordinates are
        solved from Phi = 0 by Newton's method and the dependent velocities from
        Phi_dot = 0, the independent ones kept as given."""
        self._require_partition()
        q = np.array(q, dtype=float)
        q_dot = np.array(q_dot, dtype=float)
        if self.n_constraints == 0:
            return q, q_dot                 # no constraints: every state is consistent
        for it in range(max_iter):
            phi, _, a, _ = self.constraints(t, q, q_dot)
            if np.max(np.abs(phi)) < tol:
                break
            _, inv_dc = self.velocity_map(a, t, q)
            q[self.dc] -= inv_dc @ phi
            if not np.all(np.isfinite(q)):
                break
        else:
            it = max_iter
        phi, phi_dot, a, _ = self.constraints(t, q, q_dot)
        if not np.all(np.isfinite(q)) or np.max(np.abs(phi)) >= max(tol, 1e-9):
            raise ConstraintError(
                f"cannot place the model on the constraints at t = {t:.6g} s by moving "
                f"{list(self.dependent)}: |Phi| = {np.abs(phi).tolist()} after {it} Newton "
                "steps; the target may be out of reach of the mechanism")
        outside = self.model.limit_violations(q)
        if outside:
            raise ConstraintError(
                f"cannot place the model on the constraints at t = {t:.6g} s: the solution "
                f"needs {outside}; the target is out of reach of the mechanism")
        gamma, inv_dc = self.velocity_map(a, t, q)
        phi_t = phi_dot - a @ q_dot
        q_dot[self.dc] = gamma @ q_dot[self.ic] - inv_dc @ phi_t
        return q, q_dot


def _rcond(a, inv):
    """Reciprocal 1-norm condition number of a square matrix given its inverse."""
    norm, inv_norm = np.abs(a).sum(axis=0).max(), np.abs(inv).sum(axis=0).max()  # 1-norms
    if not (np.isfinite(norm) and np.isfinite(inv_norm)) or norm == 0.0 or inv_norm == 0.0:
        return 0.0
    return 1.0 / (norm * inv_norm)


def _solve_spd(m, b, t, q):
    try:
        return np.linalg.solve(m, b)
    except np.linalg.LinAlgError:
        raise ConstraintError(f"at t = {t:.6g} s the mass matrix is singular at "
                              f"q = {np.round(q, 6).tolist()}") from None

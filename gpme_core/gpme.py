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

Any partition with a regular A_dc gives the same q_ddot (N spans the null space of A), so
the partition may change during a run without changing the motion: ``solve(...,
switch_below=SWITCH_RCOND)`` re-chooses the dependent coordinates by pivoting when the
given ones are badly conditioned (see :func:`partition_rcond`).
"""
import copy
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from . import fast
from .constraint_rank import dependence_problem
from .constraints import bind_constraints, evaluate_constraints
from .dynamics import dynamics_terms
from .errors import ConstraintError, ModelError
from .kinematics import chain_kinematics

# A partition whose reciprocal condition number (:func:`partition_rcond`: A_dc against the
# whole Jacobian) is below this is treated as singular: the dependent velocities would
# lose more than ~10 of 16 significant digits.
SINGULAR_RCOND = 1e-10
# A run (gpme_core.integrate.simulate) re-chooses the dependent coordinates when the
# partition's reciprocal condition number (:func:`partition_rcond`) falls below this.
# Why 1e-3: a solve with a partition of reciprocal condition r loses about log10(1/r) of
# the 16 significant digits (errors ~ eps / r in Gamma and q_ddot).  Every evaluation that
# finds r < SWITCH_RCOND switches before solving, so no solve of a run loses more than 3
# digits to its partition (12 remain, far below any integrator error we accept), whereas
# without switching the loss is unbounded and the run stops at SINGULAR_RCOND.  A switch
# costs one pivoted QR of A and does not change the motion.  A smaller value (down to
# sqrt(eps) ~ 1.5e-8, half the digits) would be as accurate, but then a path crossing a
# configuration where the partition is singular would mostly pass between two evaluations
# unnoticed, keeping a partition that is poor on both sides of it; at 1e-3 the window in
# which the switch is triggered is wide enough to be hit by the RK4 stages (dt / 2 apart)
# whenever r falls slower than 2e-3 / dt per second.
SWITCH_RCOND = 1e-3
DAMPING_FORMS = ("lagrange", "paper-eq7")


@dataclass(frozen=True)
class GpmeSolution:
    """Everything computed at one (t, q, q_dot).  Shapes: n coordinates, m constraints.

    q_ddot (n,), phi (m,), phi_dot (m,), jacobian A (m, n), kappa (m,), multipliers (m,),
    reaction_forces (n,) = A^T multipliers, terms: the DynamicsTerms used, dependent: the
    names of the dependent coordinates used (the system's own unless ``solve`` switched),
    partition_rcond: their :func:`partition_rcond` (1.0 without constraints).
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
    dependent: tuple = ()
    partition_rcond: float = 1.0


class ProgrammedMotion:
    """A model with programmed constraints, reduced to its GPME form.

    model      : gpme_core.model.Model
    constraints: sequence of constraint specs (gpme_core.constraints)
    dependent  : names of the m dependent coordinates, or None to choose them by pivoting
                 on the constraint Jacobian (:meth:`with_pivoted_dependent` with a state;
                 gpme_core.integrate.simulate chooses them for its run without setting
                 them here)
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
        problems = []
        try:
            alpha, beta = (float(v) for v in baumgarte)
        except (TypeError, ValueError):
            raise ModelError(f"baumgarte must be two numbers (alpha, beta) in 1/s, got "
                             f"{baumgarte!r}") from None
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
            self._set_partition(dependent)
        elif self.n_constraints == 0:
            self._set_partition(())
        self._frozen = True

    def __setattr__(self, name, value):
        """Immutable once built, like Model: a changed partition is a new object
        (:meth:`with_dependent`).  (gpme_core.compiled.for_system keeps its compiled form in
        the instance's __dict__: a cache of what the object already is, not a change.)"""
        if self.__dict__.get("_frozen", False):
            raise AttributeError(f"ProgrammedMotion is immutable: cannot set {name!r}; use "
                                 "with_dependent(names) for another partition")
        object.__setattr__(self, name, value)

    def __getstate__(self):
        """Pickled without the compiled form that gpme_core.compiled.for_system caches on it:
        that holds a module, which cannot be pickled; the receiving process packs its own
        (the compiled code itself comes from numba's disk cache)."""
        state = self.__dict__.copy()
        state.pop("_compiled", None)
        return state

    def __copy__(self):
        """A shallow copy sharing everything, the cached compiled form included (copies made
        by :meth:`with_dependent` differ only in their partition, which the compiled kernels
        take as an argument)."""
        other = object.__new__(type(self))
        other.__dict__.update(self.__dict__)
        return other

    # --------------------------------------------------------------- partition
    def _set_partition(self, names):
        """Fix the dependent coordinates by name (m of them): while the object is built only
        (__init__, with_dependent's fresh copy)."""
        names = tuple(names)
        if len(names) != self.n_constraints or len(set(names)) != len(names):
            raise ModelError(f"need {self.n_constraints} distinct dependent coordinates "
                             f"(one per constraint {list(self.constraint_names)}), got {list(names)}")
        dc = np.array([self.model.index(nm) for nm in names], dtype=int)
        d = self.__dict__
        d["dependent"] = names
        d["dc"] = dc
        d["ic"] = np.array([k for k in range(self.model.n_coordinates) if k not in set(dc)],
                           dtype=int)
        d["independent"] = tuple(self.model.coordinate_names[k] for k in d["ic"])

    def with_dependent(self, names):
        """A copy of this system with dependent coordinates ``names`` (this one unchanged).

        The copy shares the model and the bound constraints (neither is modified by a
        solve); only the partition is its own."""
        other = copy.copy(self)
        other._set_partition(names)
        return other

    def pivoted_dependent(self, t, q, q_dot=None):
        """Names of m dependent coordinates chosen by column-pivoted QR of A(q, t), without
        changing this system; ConstraintError when A has rank < m.

        t s; q (n,), q_dot (n,) ordered as model.coordinate_names (q_dot None = zeros)."""
        if self.n_constraints == 0:
            return ()
        q = np.asarray(q, dtype=float)
        q_dot = np.zeros_like(q) if q_dot is None else np.asarray(q_dot, dtype=float)
        _, _, a, _ = self.constraints(t, q, q_dot)
        return self._pivoted_names(a, t, q)

    def _pivoted_names(self, a, t, q):
        _, r, piv = sla.qr(a, pivoting=True, mode="economic")
        diag = np.abs(np.diag(r))
        if diag.min() <= SINGULAR_RCOND * max(diag.max(), 1e-300):
            raise ConstraintError(
                dependence_problem(a, self.constraint_names, t, q) or
                f"at t = {t:.6g} s the constraint Jacobian has rank < {self.n_constraints}: "
                f"the constraints {list(self.constraint_names)} are dependent or cannot be "
                f"controlled by any coordinate at q = {np.round(q, 6).tolist()}")
        return tuple(self.model.coordinate_names[k] for k in piv[:self.n_constraints])

    def with_pivoted_dependent(self, t, q, q_dot=None):
        """A copy of this system whose dependent coordinates are :meth:`pivoted_dependent`'s
        choice at (t, q, q_dot) (this one unchanged)."""
        return self.with_dependent(self.pivoted_dependent(t, q, q_dot))

    def _require_partition(self):
        if self.dependent is None:
            raise ModelError("dependent coordinates not chosen: pass dependent=[...] or use "
                             "with_pivoted_dependent(t, q) (a new system)")

    # --------------------------------------------------------------- evaluation
    def constraints(self, t, q, q_dot, kin=None):
        """(Phi (m,), Phi_dot (m,), A (m, n), kappa (m,))."""
        if kin is None:
            kin = chain_kinematics(self.model, q)
        return evaluate_constraints(self.model, self.bound, t, kin, np.asarray(q_dot, float))

    def velocity_map(self, a, t=0.0, q=None):
        """Gamma = dq_dot_dc/dq_dot_ic = -A_dc^-1 A_ic (m, n - m), checking A_dc."""
        self._require_partition()
        return self._velocity_map(a, self.ic, self.dc, self.dependent, t, q,
                                  self.constraint_names)

    @staticmethod
    def _velocity_map(a, ic, dc, names, t, q, constraint_names=None):
        a_dc = a[:, dc]
        try:
            inv = np.linalg.inv(a_dc)    # m x m, m small: explicit inverse is cheapest
        except np.linalg.LinAlgError:
            inv = np.full_like(a_dc, np.inf)
        rcond = _relative_rcond(a, dc, _rcond(a_dc, inv))
        if not rcond > SINGULAR_RCOND:
            raise _singular_partition(names, rcond, t, q, a, constraint_names)
        return -inv @ a[:, ic], inv

    def solve(self, t, q, q_dot, switch_below=None):
        """:class:`GpmeSolution` of the reduced equations at (t, q, q_dot).

        t s; q (n,), q_dot (n,) ordered as model.coordinate_names.
        switch_below : None (default) solves with this system's dependent coordinates and
                       raises ConstraintError where their block is singular; a number r
                       (e.g. SWITCH_RCOND) solves with :meth:`pivoted_dependent`'s choice
                       instead when the system's partition has partition_rcond < r and
                       the pivoted one is better (``solution.dependent`` says which was
                       used).  This system is never changed.
        """
        self._require_partition()
        q = np.asarray(q, dtype=float)
        q_dot = np.asarray(q_dot, dtype=float)
        if q.shape != q_dot.shape or q.shape != (self.model.n_coordinates,):
            raise ModelError(f"q and q_dot must have shape ({self.model.n_coordinates},), "
                             f"ordered as {list(self.model.coordinate_names)}; got "
                             f"{q.shape} and {q_dot.shape}")
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
        names, ic, dc = self.dependent, self.ic, self.dc
        q_ddot, lam, rel, ok = _reduced_solve(terms.M, rhs, a, constraint_rhs, ic, dc)
        if switch_below is not None and not rel >= switch_below:
            new = self._pivoted_names(a, t, q)
            if new != names:
                new_dc = np.array([self.model.index(nm) for nm in new], dtype=int)
                new_ic = np.setdiff1d(np.arange(n), new_dc)
                trial = _reduced_solve(terms.M, rhs, a, constraint_rhs, new_ic, new_dc)
                if trial[2] > rel:
                    names, ic, dc = new, new_ic, new_dc
                    q_ddot, lam, rel, ok = trial
        if not rel > SINGULAR_RCOND:
            raise _singular_partition(names, rel, t, q, a, self.constraint_names)
        if not ok:
            raise ConstraintError(f"at t = {t:.6g} s the reduced GPME matrix is singular "
                                  f"at q = {np.round(q, 6).tolist()}")
        return GpmeSolution(t, q_ddot, phi, phi_dot, a, kappa, lam, a.T @ lam, terms,
                            tuple(names), float(rel))

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
                q = self._polished(t, q, q_dot, phi, a)
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


    def _polished(self, t, q, q_dot, phi, a):
        """q after one more Newton step on Phi = 0 (phi (m,), a (m, n) at q): Newton's
        quadratic convergence takes a residual below the tolerance down to round-off, so
        that a start is on its constraints to round-off, as the crosschecks' Phi gates
        assume; kept only when it does not make max |Phi| larger."""
        _, inv_dc = self.velocity_map(a, t, q)
        trial = q.copy()
        trial[self.dc] -= inv_dc @ phi
        if not np.all(np.isfinite(trial)):
            return q
        after = self.constraints(t, trial, q_dot)[0]
        return trial if np.max(np.abs(after)) <= np.max(np.abs(phi)) else q


def _singular_partition(names, rcond, t, q, a=None, constraint_names=None):
    """The error of a singular dependent block; when A itself has rank < m (no partition
    can be regular) the constraints that are dependent, by name
    (gpme_core.constraint_rank)."""
    dependent = (None if a is None or constraint_names is None
                 else dependence_problem(a, constraint_names, t, q))
    if dependent:
        return ConstraintError(dependent)
    qs = "" if q is None else f" at q = {np.round(q, 6).tolist()}"
    return ConstraintError(
        f"at t = {t:.6g} s the dependent block K_dc of the constraint Jacobian "
        f"(columns {list(names)}) is singular (reciprocal condition {rcond:.2e} <= "
        f"{SINGULAR_RCOND:.0e}, measured against the whole Jacobian){qs}: these coordinates "
        "cannot realise the constraints here; choose other dependent coordinates or keep "
        "the programmed path away from this configuration")


def partition_rcond(a, dc):
    """Reciprocal condition of the partition with dependent columns ``dc`` of A:
    1 / (||A_dc^-1||_1 ||A||_1), in [0, 1].

    a : (m, n) constraint Jacobian; dc : (m,) indices of the dependent coordinates.
    It is the reciprocal condition number of A_dc measured against the whole Jacobian
    rather than against A_dc alone: for one constraint (m = 1) rcond(A_dc) is 1 for any
    non-zero entry, however small beside the other columns, whereas this measure is
    |a_dc| / max_j |a_j| and falls to 0 as the dependent column vanishes.  It is at most
    rcond(A_dc), and 0 when A_dc is singular.
    """
    a = np.asarray(a, dtype=float)
    dc = np.asarray(dc, dtype=int)
    a_dc = a[:, dc]
    try:
        inv = np.linalg.inv(a_dc)
    except np.linalg.LinAlgError:
        return 0.0
    return _relative_rcond(a, dc, _rcond(a_dc, inv))


def _relative_rcond(a, dc, rcond):
    """partition_rcond from rcond(A_dc) (1-norm): rcond * ||A_dc||_1 / ||A||_1."""
    col = np.abs(a).sum(axis=0)
    norm_a = col.max()
    if not (rcond > 0.0 and norm_a > 0.0):
        return 0.0
    return float(rcond * col[dc].max() / norm_a)


def _reduced_solve(m, rhs, a, constraint_rhs, ic, dc):
    """(q_ddot (n,), multipliers (k,), partition_rcond, ok) of the reduced equations for the
    partition (ic, dc); never raises (ok False, or partition_rcond <= SINGULAR_RCOND: the
    caller raises).  Two computation paths: the compiled runs' own kernel
    (gpme_core.kernels.reduced_solve, Cholesky of N^T M N) when gpme_core.fast is enabled,
    else the numpy reference below (LU of [N^T M; A]); tests hold them equal to round-off."""
    if fast.ENABLED:
        return _compiled_reduced_solve(m, rhs, a, constraint_rhs, ic, dc)
    q_ddot, lam, rcond, ok = _numpy_reduced_solve(m, rhs, a, constraint_rhs, ic, dc)
    return q_ddot, lam, _relative_rcond(a, dc, rcond), ok


def _compiled_reduced_solve(m, rhs, a, constraint_rhs, ic, dc):
    """_reduced_solve through gpme_core.kernels.reduced_solve (no switching: switch_below
    0; singular at partition_rcond <= SINGULAR_RCOND, as the numpy path's caller)."""
    from . import kernels    # numba's compiled kernels, ~20 ms to load: only when solving
    n, k = m.shape[0], dc.shape[0]
    q_ddot, lam = np.zeros(n), np.zeros(k)
    scratch = np.empty(kernels.reduced_scratch_size(n, k))
    status, rel = fast.run(kernels.reduced_solve, np.ascontiguousarray(m, dtype=float),
                           np.ascontiguousarray(rhs, dtype=float),
                           np.ascontiguousarray(a, dtype=float),
                           np.ascontiguousarray(constraint_rhs, dtype=float),
                           np.ascontiguousarray(ic, dtype=np.int64),
                           np.ascontiguousarray(dc, dtype=np.int64), 0.0, SINGULAR_RCOND,
                           q_ddot, lam, scratch)
    return q_ddot, lam, float(rel), status == kernels.OK


def _numpy_reduced_solve(m, rhs, a, constraint_rhs, ic, dc):
    """(q_ddot (n,), multipliers (k,), rcond(A_dc) (1-norm), ok): the numpy reference."""
    n, k = m.shape[0], dc.shape[0]
    a_dc = a[:, dc]
    try:
        inv = np.linalg.inv(a_dc)    # k x k, k small: explicit inverse is cheapest
    except np.linalg.LinAlgError:
        return np.zeros(n), np.zeros(k), 0.0, False
    rcond = _rcond(a_dc, inv)
    if not rcond > SINGULAR_RCOND:
        return np.zeros(n), np.zeros(k), rcond, False
    gamma = -inv @ a[:, ic]
    # N^T X for X with rows ordered as q: X[ic] + Gamma^T X[dc]
    lhs = np.empty((n, n))
    lhs[:n - k] = m[ic] + gamma.T @ m[dc]
    lhs[n - k:] = a
    b = np.empty(n)
    b[:n - k] = rhs[ic] + gamma.T @ rhs[dc]
    b[n - k:] = constraint_rhs
    try:
        q_ddot = np.linalg.solve(lhs, b)
    except np.linalg.LinAlgError:
        return np.zeros(n), np.zeros(k), rcond, False
    reaction = m @ q_ddot - rhs
    return q_ddot, inv.T @ reaction[dc], rcond, True


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

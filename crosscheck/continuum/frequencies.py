"""Natural frequencies of RFEM (gpme) and of the continuum (Exudyn) at configurations of a run.

**What is computed, on both sides the same.**  The undamped small vibrations of the machine
under its programmed constraints frozen at time t, about a *stress-free* configuration:

* the configuration (:class:`FrequencyConfiguration`, :func:`frequency_configuration`): the
  rigid joint coordinates at time t (from a gpme run, or given), with every beam straight
  (RFEM angles 0), every spring-loaded independent coordinate at its spring reference, the
  dependent coordinates put back on the programmed constraints Phi(q, t) = 0 at that t;
  q_dot = 0;
* the loads off: gravity and drives do not enter (the model is rebuilt without them,
  :func:`unloaded_model`), dampers do not enter (undamped).

Derivation (gpme's side, joint coordinates q, n of them; m constraints).  The equations are
M(q) q_ddot = h(q, q_dot) + Q(q, q_dot, t) + A(q, t)^T lambda with Q = -(g + d + f) + t_dr
(gpme_core.dynamics) and Phi(q, t) = 0.  About a state (q*, q_dot = 0, lambda*) with the time
in the constraints held at t, perturbed by (dq, dq_dot, dlambda):

    M dq_ddot = (dh/dq + dQ/dq) dq + (dh/dq_dot + dQ/dq_dot) dq_dot
                + A^T dlambda + sum_i lambda*_i (d^2 Phi_i / dq^2) dq,      A dq = 0.

h is quadratic in q_dot, so it and its derivatives vanish at q_dot = 0 (no gyroscopic
term); dQ/dq_dot = -D is the damping, dropped (undamped); dQ/dq = -K - dg/dq - dF_ps/dq with
K = diag(k) the joint and RFEM springs and dg/dq the Hessian of the gravity potential.  At a
stress-free point with the loads off, the elastic and gravity forces are zero, so the static
multipliers lambda* are zero and the constraint-curvature term drops; dg/dq = 0 with gravity
off.  On the null space N of A (A N = 0, dq = N x):

    (N^T K N) x = omega^2 (N^T M N) x.

Why stress-free and unloaded: at a configuration that is not an equilibrium the tangent
"stiffness on the constraint manifold" depends on which multipliers are used and on the
coordinates (joint coordinates here, Exudyn's absolute ones in the continuum: their
curvature terms lambda^T Phi_qq differ), so the two sides would not compute the same
quantity.  At a stress-free point both give the same, coordinate-free linearisation.  What
this leaves out: gravity's geometric stiffness, of relative size g / (omega^2 L) in omega^2
(on the crane's arm, omega = 2 pi 27 Hz, L = 0.5 m: 7e-4, i.e. about 3e-4 in the
frequency), the same on both sides and no part of the discretisation error compared here.

The continuum (:func:`continuum_frequencies`): the same unloaded machine in Exudyn
(crosscheck.continuum.system.build_system, the beams straight at q), its mass matrix, the
Jacobian of its ODE2 right-hand side (the stiffness, Exudyn's MainSolverStatic, the solver
functions mbs.ComputeODE2Eigenvalues uses) and its constraint Jacobian C_q at time t
(Exudyn's static solver evaluates its user functions at loadStepStart); the null space of
C_q by SVD; the same generalized eigenproblem.  Nothing of gpme's dynamics is used: only the
model data crosscheck.continuum.layout reads.  The continuum is the Euler-Bernoulli limit
(crosscheck.continuum.section: axial and shear compliance 1e-6 of the bending one), the
limit RFEM converges to.

The eigenproblem is solved shifted and inverted: the eigenvalues mu of
(K + sigma M)^-1 M, omega^2 = 1/mu - sigma, with sigma the squared first bending frequency
of the model's stiffest bare cantilever beam (from its data).  The lowest modes are then the
best resolved (round-off relative to 1/sigma, not to the stiffest axial mode of the
Euler-Bernoulli limit, ~1e16 (rad/s)^2 on a fine mesh).  Rigid modes (a free joint without
spring, the crane's slewing column) have omega^2 = 0 and are counted, not listed.
"""
import time
from dataclasses import dataclass
from types import MappingProxyType
from typing import Callable, Mapping, Sequence

import exudyn as exu
import numpy as np
import pandas as pd
import scipy.linalg as sla
from numpy.typing import NDArray

from gpme_core.dynamics import mass_matrix
from gpme_core.errors import ModelError
from gpme_core.integrate import simulate
from gpme_core.model import Model

from ..exudyn.model import quiet_settings
from .layout import continuum_layout
from .study import REFERENCE_FRACTION
from .system import build_system
from .validity import ORDER_MARGIN, REFERENCE_ORDER_MARGIN, RICHARDSON_ORDER2, straight_start

# first bending root of a clamped-free Euler-Bernoulli beam, beta_1 L (cos cosh = -1)
CANTILEVER_ROOT = 1.8751040687119611
# a mode with omega^2 below this fraction of the shift sigma (omega below 1e-3 of the stiffest
# beam's bare cantilever frequency) is a rigid mode.  Measured round-off of the crane's
# rigid slewing mode: omega^2 / sigma <= 2e-8 in the continuum (256 elements), <= 1e-15 in
# RFEM; its lowest elastic mode (the support, 2.36 Hz) is at 1e-3: the line sits between
# with a factor 50 on one side and 1000 on the other
ZERO_MODE_FRACTION = 1e-6
# |R_jj| of the pivoted QR of Exudyn's constraint Jacobian below this fraction of the
# largest are zero (redundant columns: the generic joints' free axes give zero columns).
# Measured on the crane (8 to 256 elements) and the cantilever: the dropped ones exactly 0,
# the kept ones >= 0.094 of the largest
NULL_SPACE_RCOND = 1e-10
# ... and the gap between the last kept and the first dropped |R_jj| must be at least this
# (the rank decided, not guessed); measured: infinite (the dropped ones are 0)
RANK_GAP = 1e6
FIRST_ELEMENTS = 8                  # the continuum reference's first mesh (per beam)
MAX_ELEMENTS = 256                  # ... and its finest (1837 coordinates on the crane, 20 s)
NS = (1, 2, 3, 5, 10, 20)
ACCURACIES = (1e-2, 1e-3)           # the table says from which n RFEM is within these
# RFEM's bending frequencies converge at order 2 (docs/rfem.md); the n within an accuracy is
# extrapolated at this order from the finest n when no tabulated n reaches it
EXPECTED_ORDER = 2.0


def _frozen(a) -> NDArray[np.float64]:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class FrequencyConfiguration:
    """A configuration at which both sides are compared.

    t : s, the time at which the programmed constraints are frozen;
    joints : {joint name: value (rad or m)} of every joint that is not an RFEM sde (read-only
             mapping); every beam straight, velocities 0;
    source : how it was obtained (one line).
    """

    t: float
    joints: Mapping[str, float]
    source: str


@dataclass(frozen=True)
class Modes:
    """The first natural frequencies of one model at one configuration.

    frequencies_hz : (k,) Hz, the first k non-zero natural frequencies, ascending (NaN where
                     the model has fewer: RFEM at n = 1);
    zero_modes     : number of rigid modes (omega^2 below ZERO_MODE_FRACTION x sigma) skipped;
    dimension      : dimension of the constrained configuration space (columns of N);
    labels         : (k,) what carries each mode's strain energy (RFEM: the coordinate group
                     with the largest share, e.g. 'psi_arm 97 %'; continuum: '');
    asymmetry      : max |K_r - K_r^T| / max |K_r| of the reduced stiffness before it is
                     symmetrised (0 for RFEM's diagonal K);
    notes          : what was built, one line each.
    """

    frequencies_hz: NDArray[np.float64]
    zero_modes: int
    dimension: int
    labels: tuple = ()
    asymmetry: float = 0.0
    notes: tuple = ()


def unloaded_model(model: Model) -> Model:
    """The model without drives and with gravity (0, 0, 0): the same joints, links, frames,
    beams, springs and dampers (a new immutable Model; ``model`` is not changed)."""
    return Model(model.joints, model.links, dict(model.frames), (), (0.0, 0.0, 0.0),
                 model.flexible_links, model.name, model.geometry, model.point_springs)


def shift(model: Model) -> float:
    """sigma, (rad/s)^2: the squared first bending frequency of the stiffest bare
    cantilever among the model's beams, (beta_1 L)^4 E I_max / (rho A L^4) (from each
    beam's data); ModelError for a model without flexible links."""
    beams = [f.beam for f in model.flexible_links]
    if not beams:
        raise ModelError(f"model {model.name!r} has no flexible link: no beam frequencies "
                         "to compare")
    return max(CANTILEVER_ROOT ** 4 * b.youngs_modulus * max(b.second_moment_y, b.second_moment_z)
               / (b.density * b.area * b.length ** 4) for b in beams)


def _check_count(count) -> int:
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ModelError(f"count must be a whole number >= 1 of frequencies, got {count!r}")
    return int(count)


def _check_time(t) -> float:
    try:
        t = float(t)
    except (TypeError, ValueError):
        raise ModelError(f"t must be a time in s, got {t!r}") from None
    if not np.isfinite(t):
        raise ModelError(f"t must be a finite time in s, got {t!r}")
    return t


def _shifted_eigen(k_r, m_r, sigma, count, what):
    """(omega^2 (s,) ascending, vectors (r, s) in the reduced coordinates, number of rigid
    modes among them) of the lowest s modes of k_r x = omega^2 m_r x, through the largest
    eigenvalues mu of (k_r + sigma m_r)^-1 m_r (module docstring); s is enough to hold
    ``count`` non-rigid modes (or all r)."""
    try:
        chol = np.linalg.cholesky(k_r + sigma * m_r)
    except np.linalg.LinAlgError:
        raise ModelError(f"{what}: K + sigma M is not positive definite on the constraints' "
                         f"null space (sigma = {sigma:.4g} (rad/s)^2): the mass matrix is "
                         "singular there or the stiffness is negative (an unstable "
                         "configuration)") from None
    half = sla.solve_triangular(chol, m_r, lower=True)            # L^-1 M
    c = sla.solve_triangular(chol, half.T, lower=True)            # L^-1 M L^-T
    c = 0.5 * (c + c.T)
    r = len(c)
    size = min(r, 2 * count + 8)
    while True:
        mu, z = sla.eigh(c, subset_by_index=[r - size, r - 1])
        mu, z = mu[::-1], z[:, ::-1]          # largest mu first: lowest omega
        if not np.all(mu > 0.0):
            raise ModelError(f"{what}: the reduced mass matrix is not positive definite (an "
                             "eigenvalue of (K + sigma M)^-1 M is <= 0): a motion allowed by "
                             "the constraints carries no mass")
        omega2 = 1.0 / mu - sigma
        rigid = int(np.sum(np.abs(omega2) <= ZERO_MODE_FRACTION * sigma))
        if size == r or size - rigid >= count:
            return omega2, sla.solve_triangular(chol.T, z, lower=False), rigid
        size = min(r, 2 * size)


def _split(omega2, sigma, count, what):
    """(first ``count`` non-zero frequencies Hz (NaN-padded), number of rigid modes,
    indices of the listed modes)."""
    rigid = np.abs(omega2) <= ZERO_MODE_FRACTION * sigma
    negative = (omega2 < 0.0) & ~rigid
    if np.any(negative):
        raise ModelError(f"{what}: negative omega^2 = {omega2[negative].min():.6g} (rad/s)^2 "
                         "beyond round-off: the configuration is unstable, not a vibration")
    idx = np.flatnonzero(~rigid)[:count]
    hz = np.full(count, np.nan)
    hz[:len(idx)] = np.sqrt(omega2[idx]) / (2.0 * np.pi)
    return hz, int(rigid.sum()), idx


def _energy_labels(model, q_vectors) -> tuple:
    """For each column v of q_vectors (n, k): the coordinate group (an sde rotation of a beam,
    'psi_arm', or a joint's name) with the largest share of the strain energy k_i v_i^2."""
    groups = {}
    for k, name in enumerate(model.coordinate_names):
        groups.setdefault(name, []).append(k)
    for f in model.flexible_links:
        for k in f.joint_indices:
            name = model.coordinate_names[k]
            groups.pop(name, None)
            groups.setdefault(f"{name.split('_')[0]}_{f.name}", []).append(k)
    stiffness = np.asarray(model.stiffness, dtype=float)
    out = []
    for v in q_vectors.T:
        energy = stiffness * v * v
        total = energy.sum()
        if not total > 0.0:
            out.append("")
            continue
        share = {g: energy[ks].sum() / total for g, ks in groups.items()}
        best = max(share, key=share.get)
        out.append(f"{best} {100 * share[best]:.0f} %")
    return tuple(out)


def _stress_problems(model, q) -> list:
    force = np.asarray(model.stiffness) * (q - np.asarray(model.spring_reference))
    return [f"{model.coordinate_names[k]} = {q[k]:.6g} is {q[k] - model.spring_reference[k]:.3g} "
            f"from its spring reference (spring force {force[k]:.4g})"
            for k in np.flatnonzero(np.abs(force) > 0.0)]


def rfem_frequencies(system, t: float, q, count: int = 6) -> Modes:
    """The first ``count`` natural frequencies (Hz) of the gpme RFEM model ``system``
    (gpme_core.gpme.ProgrammedMotion) under its constraints frozen at ``t`` (s), about the
    stress-free configuration q (n,) (rad, m; ordered as model.coordinate_names; q_dot = 0),
    with gpme's own mass matrix, springs and constraint Jacobian (module docstring).
    ModelError when q is not stress-free (a spring away from its reference), not on the
    constraints, or the model has point springs (not derived here)."""
    model = system.model
    count, t = _check_count(count), _check_time(t)
    n = model.n_coordinates
    q = np.asarray(q, dtype=float)
    if q.shape != (n,) or not np.all(np.isfinite(q)):
        raise ModelError(f"q must be {n} finite values ordered as {list(model.coordinate_names)}, "
                         f"got shape {q.shape}")
    if model.point_springs:
        raise ModelError(f"model {model.name!r}: point springs' tangent stiffness is not part "
                         "of this comparison (the continuum model does not realise them)")
    problems = _stress_problems(model, q)
    if problems:
        raise ModelError(["the configuration is not stress-free: " + p for p in problems])
    a = np.zeros((0, n))
    if system.n_constraints:
        phi, _, a, _ = system.constraints(t, q, np.zeros(n))
        if np.max(np.abs(phi)) > 1e-9:
            raise ModelError(f"q is not on the constraints at t = {t:.6g} s: |Phi| = "
                             f"{np.abs(phi).tolist()} (use frequency_configuration)")
    null = sla.null_space(a) if a.shape[0] else np.eye(n)
    if null.shape[1] != n - a.shape[0]:
        raise ModelError(f"the constraint Jacobian at t = {t:.6g} s has rank "
                         f"{n - null.shape[1]} < {a.shape[0]}: dependent constraints")
    m_r = null.T @ mass_matrix(model, q) @ null
    k_r = null.T @ (np.asarray(model.stiffness)[:, None] * null)
    sigma = shift(model)
    omega2, vectors, _ = _shifted_eigen(k_r, m_r, sigma, count, f"RFEM {model.name} at "
                                        f"t = {t:.6g} s")
    hz, zero, idx = _split(omega2, sigma, count, f"RFEM {model.name} at t = {t:.6g} s")
    labels = _energy_labels(model, null @ vectors[:, idx])
    labels = labels + ("",) * (count - len(labels))
    return Modes(_frozen(hz), zero, null.shape[1], labels, 0.0,
                 (f"RFEM {model.name}: {n} coordinates, {a.shape[0]} constraints",))


def continuum_matrices(model, t: float, q, specs=(), elements=FIRST_ELEMENTS,
                       euler_bernoulli: bool = True) -> tuple:
    """(M (N, N), K (N, N), C (N, c)) of the unloaded continuum model at the configuration
    q (the beams straight) and time t, from Exudyn's MainSolverStatic: M the mass matrix, K
    = -d(ODE2 right-hand side)/dq (loads, gravity and drives removed; damping not included),
    C the constraint Jacobian C_q^T (position level, columns the algebraic equations);
    N Exudyn's ODE2 coordinates (positions and Euler parameters), plus the system's notes."""
    model_u = unloaded_model(model)
    layout = continuum_layout(model_u)
    q = np.asarray(q, dtype=float)
    system = build_system(model_u, layout, q, np.zeros_like(q), specs, elements,
                          np.zeros(3), euler_bernoulli)
    mbs = system.mbs
    mbs.Assemble()
    settings = quiet_settings()
    settings.staticSolver.verboseMode = 0
    settings.staticSolver.loadStepStart = float(t)   # the user functions' time
    # sparse storage: the same matrices to the last bit (checked at 1165 coordinates), 3x
    # faster, and no Exudyn warning about a dense solver above 1000 coordinates
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    solver = exu.MainSolverStatic()
    solver.InitializeSolver(mbs, settings)
    n2, n1 = solver.GetODE2size(), solver.GetODE1size()
    solver.ComputeMassMatrix(mbs)
    mass = np.array(solver.GetSystemMassMatrix(), dtype=float)
    solver.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=-1.0, scalarFactor_ODE2_t=0.0,
                                  scalarFactor_ODE1=0.0)
    solver.ComputeJacobianAE(mbs, scalarFactor_ODE2=1.0, scalarFactor_ODE2_t=0.0,
                             scalarFactor_ODE1=0.0, velocityLevel=False)
    jac = np.array(solver.GetSystemJacobian(), dtype=float)
    solver.FinalizeSolver(mbs, settings)
    return mass, jac[:n2, :n2], jac[:n2, n2 + n1:], tuple(system.notes)


def continuum_frequencies(model, t: float, q, specs=(), count: int = 6,
                          elements=FIRST_ELEMENTS, euler_bernoulli: bool = True) -> Modes:
    """The first ``count`` natural frequencies (Hz) of the continuum model of ``model`` at
    the configuration q (n,) of gpme's coordinates (only the non-sde joints are read; the
    beams straight) with the constraint specs ``specs`` frozen at t (s); elements per beam
    (int or {beam: int}); euler_bernoulli: the Euler-Bernoulli limit (default) or the
    physical rod.  From Exudyn's matrices only (:func:`continuum_matrices`)."""
    count, t = _check_count(count), _check_time(t)
    mass, stiff, c_q, notes = continuum_matrices(model, t, q, specs, elements, euler_bernoulli)
    what = f"continuum {model.name} at t = {t:.6g} s"
    if c_q.shape[1]:
        # rank-revealing (column-pivoted) QR: |R_jj| falls; the columns of Q beyond the rank
        # span the null space of C_q^T, i.e. the motions the constraints allow
        qq, rr, _ = sla.qr(c_q, pivoting=True, mode="full")
        s = np.abs(np.diag(rr))
        rank = int(np.sum(s > NULL_SPACE_RCOND * s[0]))
        gap = s[rank - 1] / s[rank] if rank < len(s) and s[rank] > 0 else np.inf
        if gap < RANK_GAP:
            raise ModelError(f"{what}: the constraint Jacobian's rank is not clear (|R_jj| "
                             f"{s[rank - 1]:.3g} and {s[rank]:.3g} around the cut "
                             f"{NULL_SPACE_RCOND:g} x {s[0]:.3g})")
        null = qq[:, rank:]
    else:
        null = np.eye(mass.shape[0])
    k_r = null.T @ stiff @ null
    m_r = null.T @ mass @ null
    asym = float(np.abs(k_r - k_r.T).max() / np.abs(k_r).max())
    sigma = shift(model)
    omega2, _, _ = _shifted_eigen(0.5 * (k_r + k_r.T), 0.5 * (m_r + m_r.T), sigma, count, what)
    hz, zero, _ = _split(omega2, sigma, count, what)
    return Modes(_frozen(hz), zero, null.shape[1], ("",) * count, asym,
                 notes + (f"{mass.shape[0]} Exudyn coordinates, {c_q.shape[1]} algebraic "
                          f"equations, null space {null.shape[1]}",))


@dataclass(frozen=True)
class FrequencyReference:
    """The continuum's frequencies refined in the mesh: frequencies_hz (k,) at the finest
    mesh ``elements`` (per beam), mesh_change (k,) Hz their change from the mesh before
    (the reference's measured error), zero_modes, history ((elements, (k,) Hz, wall s), ...)."""

    frequencies_hz: NDArray[np.float64]
    elements: int
    mesh_change: NDArray[np.float64]
    zero_modes: int
    history: tuple
    settled: bool


def continuum_reference(model, t: float, q, specs=(), count: int = 6,
                        elements: int = FIRST_ELEMENTS, max_elements: int = MAX_ELEMENTS,
                        fraction: float = REFERENCE_FRACTION,
                        log: Callable[[str], None] = lambda m: None) -> FrequencyReference:
    """The continuum's first ``count`` frequencies with the mesh doubled from ``elements``
    until every one changes by less than ``fraction`` of itself (default 1e-4: RFEM is
    judged at 1 % and 0.1 %), or ``max_elements`` is reached (settled False; the measured
    last changes are then the reference's error)."""
    if not (isinstance(elements, (int, np.integer)) and elements >= 1
            and isinstance(max_elements, (int, np.integer)) and max_elements >= elements):
        raise ModelError(f"elements must be whole numbers 1 <= elements <= max_elements, got "
                         f"{elements!r} and {max_elements!r}")
    if not (np.isfinite(fraction) and 0.0 < fraction < 1.0):
        raise ModelError(f"fraction must be in (0, 1), got {fraction!r}")
    history, last, ne = [], None, int(elements)
    while True:
        start = time.perf_counter()
        modes = continuum_frequencies(model, t, q, specs, count, ne)
        wall = time.perf_counter() - start
        history.append((ne, modes.frequencies_hz, wall))
        log(f"  continuum at t = {t:g} s: {ne} elements, {np.round(modes.frequencies_hz, 4)} Hz "
            f"({wall:.1f} s)")
        if last is not None:
            change = np.abs(modes.frequencies_hz - last.frequencies_hz)
            settled = bool(np.all(change <= fraction * modes.frequencies_hz))
            if settled or 2 * ne > max_elements:
                return FrequencyReference(modes.frequencies_hz, ne, _frozen(change),
                                          modes.zero_modes, tuple(history), settled)
        last = modes
        ne *= 2


def frequency_configuration(system, t: float, q_run, source: str = "") -> FrequencyConfiguration:
    """The stress-free configuration (module docstring) of ``system`` at time t (s) from the
    state q_run (n,) (e.g. a run's q at t): RFEM angles 0, spring-loaded independent
    coordinates at their spring reference, dependent ones solved from Phi(q, t) = 0 (gpme's
    consistent_state); ModelError when a dependent coordinate's spring is then loaded."""
    t = _check_time(t)
    model = system.model
    q = np.array(q_run, dtype=float)
    if q.shape != (model.n_coordinates,) or not np.all(np.isfinite(q)):
        raise ModelError(f"q_run must be {model.n_coordinates} finite values, got shape "
                         f"{q.shape}")
    sde = {k for f in model.flexible_links for k in f.joint_indices}
    q[list(sde)] = 0.0
    if system.n_constraints and system.dependent is None:
        system = system.with_pivoted_dependent(t, q)
    dependent = set(system.dc.tolist()) if system.n_constraints else set()
    for k in range(model.n_coordinates):
        if k not in dependent and k not in sde and model.stiffness[k] != 0.0:
            q[k] = model.spring_reference[k]
    if system.n_constraints:
        q, _ = system.consistent_state(t, q, np.zeros_like(q))
    problems = _stress_problems(model, q)
    if problems:
        raise ModelError([f"no stress-free configuration with dependent coordinates "
                          f"{list(system.dependent)} at t = {t:.6g} s: " + p for p in problems])
    joints = {model.coordinate_names[k]: float(q[k]) for k in range(model.n_coordinates)
              if k not in sde}
    return FrequencyConfiguration(t, MappingProxyType(joints), source or
                                  f"t = {t:g} s, beams straight, springs at their reference")


def state_of(configuration: FrequencyConfiguration, system) -> NDArray[np.float64]:
    """q (n,) of ``system`` (any RFEM n of the same machine) at the configuration: its joints
    by name, every RFEM angle 0 (ModelError naming a missing joint).  With straight beams
    the joints' values satisfy the constraints at every n; rfem_frequencies checks Phi."""
    model = system.model
    sde = {k for f in model.flexible_links for k in f.joint_indices}
    q = np.zeros(model.n_coordinates)
    missing = [model.coordinate_names[k] for k in range(model.n_coordinates)
               if k not in sde and model.coordinate_names[k] not in configuration.joints]
    if missing:
        raise ModelError(f"the configuration has no value for joints {missing}; it has "
                         f"{sorted(configuration.joints)}")
    for k in range(model.n_coordinates):
        if k not in sde:
            q[k] = configuration.joints[model.coordinate_names[k]]
    return q


def configurations_along_run(scenario, times: Sequence[float], output_dt: float = 1e-3,
                             log: Callable[[str], None] = lambda m: None) -> list:
    """[FrequencyConfiguration] at ``times`` (s, multiples of output_dt) of gpme's run of
    ``scenario`` from its start with straight beams (crosscheck.continuum.validity.
    straight_start), RK4 at gpme's own step: the run gives the free rigid coordinates (the
    crane's slewing angle psi2); :func:`frequency_configuration` the rest."""
    times = [_check_time(t) for t in times]
    if any(t < 0.0 for t in times) or abs(output_dt) <= 0.0:
        raise ModelError(f"times must be >= 0 s and output_dt > 0 s, got {times!r}, "
                         f"{output_dt!r}")
    q0, v0 = straight_start(scenario)
    system = scenario.system
    names = list(system.model.coordinate_names)
    t_end = max(times)
    run = None
    if t_end > 0.0:
        run = simulate(system, t_end, q0, v0, output_dt=output_dt)
        run = run.assign(step=np.round(run["t"] / output_dt).astype(int)).set_index("step")
        log(f"  gpme run of {scenario.name} to {t_end:g} s for the configurations")
    out = []
    for t in times:
        step = int(round(t / output_dt))
        if abs(step * output_dt - t) > 1e-9 * max(1.0, t):
            raise ModelError(f"time {t!r} s is not a multiple of output_dt = {output_dt!r} s")
        q = q0 if step == 0 else run.loc[step, names].to_numpy(dtype=float)
        out.append(frequency_configuration(
            system, t, q, f"t = {t:g} s of gpme's run of {scenario.name} (n = "
            f"{', '.join(str(f.n_segments) for f in system.model.flexible_links)}) from straight "
            "beams; beams straight again, springs at their reference, dependent coordinates on "
            "the constraints"))
    return out


def convergence_table(make_system: Callable, configurations: Sequence[FrequencyConfiguration],
                      references: Sequence[FrequencyReference], ns=NS, count: int = 6,
                      log: Callable[[str], None] = lambda m: None) -> pd.DataFrame:
    """Rows (t, mode, n, rfem_hz, continuum_hz, relative_error, order, label): RFEM at each n
    (``make_system(n)`` a ProgrammedMotion of the machine with n segments per beam) against
    the continuum reference of each configuration; order = log(e_a / e_b) / log(n_b / n_a)
    between successive n of the relative error e."""
    rows = []
    systems = {n: make_system(n) for n in ns}
    for cfg, ref in zip(configurations, references):
        last = {}
        for n in ns:
            system = systems[n]
            modes = rfem_frequencies(system, cfg.t, state_of(cfg, system), count)
            log(f"  RFEM n = {n} at t = {cfg.t:g} s: {np.round(modes.frequencies_hz, 4)} Hz")
            for i in range(count):
                f, f_ref = float(modes.frequencies_hz[i]), float(ref.frequencies_hz[i])
                rel = (f - f_ref) / f_ref
                order = np.nan
                if i in last and np.isfinite(rel) and abs(rel) > 0 and np.isfinite(last[i][1]):
                    order = np.log(abs(last[i][1]) / abs(rel)) / np.log(n / last[i][0])
                rows.append(dict(t=cfg.t, mode=i + 1, n=n, rfem_hz=f, continuum_hz=f_ref,
                                 relative_error=rel, order=order, label=modes.labels[i],
                                 reference_change=float(ref.mesh_change[i]) / f_ref))
                last[i] = (n, rel)
    return pd.DataFrame(rows)


def accuracy_reached(table: pd.DataFrame, accuracies=ACCURACIES) -> pd.DataFrame:
    """Per (t, mode): for each accuracy a, the smallest tabulated n from which every larger
    tabulated n has |relative error| <= a (NaN if none), and the n extrapolated at order
    EXPECTED_ORDER from the finest n, n_max (|e(n_max)| / a)^(1/2) (when not reached)."""
    rows = []
    for (t, mode), g in table.groupby(["t", "mode"], sort=True):
        g = g.sort_values("n")
        err = np.abs(g["relative_error"].to_numpy())
        ns = g["n"].to_numpy()
        row = dict(t=t, mode=mode)
        for a in accuracies:
            ok = np.isfinite(err) & (err <= a)
            first = np.nan
            for j in range(len(ns)):
                if ok[j:].all():
                    first = ns[j]
                    break
            row[f"n within {a:g}"] = first
            row[f"n within {a:g} (order-2 estimate)"] = (
                float(ns[-1] * (err[-1] / a) ** (1.0 / EXPECTED_ORDER))
                if np.isnan(first) and np.isfinite(err[-1]) else np.nan)
        rows.append(row)
    return pd.DataFrame(rows)


@dataclass(frozen=True)
class FrequencyCheck:
    """One frequency's comparison: RFEM at n and 2 n, the continuum (Hz), the continuum's
    mesh change (Hz); tolerance = ORDER_MARGIN x (4/3) |f(n) - f(2n)| + REFERENCE_ORDER_MARGIN
    x mesh change (crosscheck.continuum.validity's gate, for a frequency); passed."""

    mode: int
    rfem_n: float
    rfem_2n: float
    continuum: float
    continuum_change: float
    difference: float
    tolerance: float
    passed: bool


def frequency_checks(rfem_n: Modes, rfem_2n: Modes, reference: FrequencyReference) -> list:
    """[FrequencyCheck] per listed frequency: |f_RFEM(n) - f_continuum| against RFEM's own
    error at n predicted by Richardson at order 2 from n and 2 n (x ORDER_MARGIN: an observed
    order down to 0.8) plus 3 x the continuum's last mesh change (an observed order down to
    0.42); the gate of crosscheck.continuum.validity applied to a frequency.  A NaN (a mode
    RFEM at n does not have) fails."""
    out = []
    for i, f_ref in enumerate(reference.frequencies_hz):
        a, b = float(rfem_n.frequencies_hz[i]), float(rfem_2n.frequencies_hz[i])
        tol = (ORDER_MARGIN * RICHARDSON_ORDER2 * abs(a - b)
               + REFERENCE_ORDER_MARGIN * float(reference.mesh_change[i]))
        diff = abs(a - float(f_ref))
        out.append(FrequencyCheck(i + 1, a, b, float(f_ref), float(reference.mesh_change[i]),
                                  diff, tol, bool(diff <= tol)))
    return out

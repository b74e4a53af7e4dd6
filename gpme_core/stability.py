"""Linear stability of a fixed-step RK4 run: the modes of the linearised GPME at a state and
the largest step RK4 keeps stable for them.

The integrated first-order system is y = (q, q_dot), y' = f(t, y) = (q_dot, q_ddot(t, q,
q_dot)), with q_ddot from the reduced GPME solve (constraints and Baumgarte stabilisation
included).  Its Jacobian J = df/dy at a state has eigenvalues lambda (1/s); classical RK4
with step h is stable for a mode when |R(h lambda)| <= 1, R(z) = 1 + z + z^2/2 + z^3/6 +
z^4/24 (on the imaginary axis: h |lambda| <= 2 sqrt 2).  A mode with Re(lambda) > 0
beyond round-off grows physically (an inverted pendulum) and limits no step.

Two ways to get J:
- ``"linearised"`` (default up to :data:`MAX_LINEARISED` coordinates): central finite
  differences of the real right-hand side (2 x 2n reduced solves): constraints, gravity,
  velocity terms and the Baumgarte modes s^2 + 2 alpha s + beta^2 = 0 all included.
- ``"springs"``: [[0, I], [-M^-1 K, -M^-1 D]] from the joint and RFEM springs and dampers
  and the mass matrix at q, plus the Baumgarte roots (cheap for large models; constraints
  only lower the highest frequency (Rayleigh quotient on a subspace), so its step is the
  more cautious one).
"""
from dataclasses import dataclass

import numpy as np

from .dynamics import mass_matrix
from .kinematics import chain_kinematics
from .errors import ModelError
from .gpme import SWITCH_RCOND
from .point_springs import point_spring_matrices

# above this many coordinates the linearisation by finite differences (2 x 2n solves and an
# eigen-decomposition of a 2n x 2n matrix) gives way to the springs-and-inertia estimate
MAX_LINEARISED = 150
# Re(lambda) / |lambda| below this is taken as round-off of a purely oscillatory mode
OSCILLATORY_SLACK = 1e-2
# a suggested step is this fraction of the stability limit (RK4 loses accuracy before
# stability: half the limit keeps the stiffest mode's amplitude error below ~1 % per period)
STEP_SAFETY = 0.5
# coordinates named as carrying a mode: those with |shape| above this fraction of the largest
SHAPE_SHARE = 0.3
# a mode whose shape v has |A v| above this fraction of |A| |v| moves off the constraints
VIOLATION_SHARE = 0.5


def _rk4_growth(z):
    return abs(1 + z + z * z / 2 + z ** 3 / 6 + z ** 4 / 24)


def rk4_stability_step(eigenvalue):
    """s: largest h with |R(h lambda)| <= 1 for classical RK4 along the ray of ``eigenvalue``
    (1/s); inf for lambda = 0 or a growing mode (Re lambda > 0 beyond
    OSCILLATORY_SLACK |lambda|, which no step makes decay)."""
    lam = complex(eigenvalue)
    if abs(lam) == 0.0:
        return np.inf
    if lam.real > 0:
        if lam.real > OSCILLATORY_SLACK * abs(lam):
            return np.inf
        lam = complex(0.0, lam.imag)
        if lam == 0:
            return np.inf
    lo, hi = 0.0, 4.0 / abs(lam)          # |z| <= 2.9 inside the stability region
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _rk4_growth(mid * lam) <= 1.0 + 1e-12 else (lo, mid)
    return lo


@dataclass(frozen=True)
class Mode:
    """One eigenvalue of the linearised first-order system.

    eigenvalue   : 1/s (complex); frequency_hz = |Im| / 2 pi; damping_ratio = -Re / |lambda|
    coordinates  : names of the coordinates holding most of its spring energy (the springs
                   that make it stiff), or of its amplitude when no spring takes part
    rk4_step     : s, RK4 stability limit for it (inf: limits no step)
    """
    eigenvalue: complex
    coordinates: tuple
    rk4_step: float

    @property
    def frequency_hz(self):
        return abs(self.eigenvalue.imag) / (2 * np.pi)

    @property
    def damping_ratio(self):
        return -self.eigenvalue.real / abs(self.eigenvalue) if self.eigenvalue else 0.0

    def describe(self):
        """'860 Hz, damping ratio 0.01 (eigenvalue -54+5400j 1/s), mostly psi3_2, theta3_1'."""
        lam = self.eigenvalue
        kind = (f"{self.frequency_hz:.4g} Hz, damping ratio {self.damping_ratio:.2g}"
                if abs(lam.imag) > 1e-9 * abs(lam) else "non-oscillating")
        return (f"{kind} (eigenvalue {lam.real:.4g}{lam.imag:+.4g}j 1/s), mostly "
                f"{', '.join(self.coordinates)}")


def _shape_names(names, vector, n, stiffness):
    """The coordinates holding most of the mode's spring energy K_k |v_k|^2 (the springs that
    make it stiff), or of its amplitude when no spring takes part."""
    q_part = vector[:n] if np.abs(vector[:n]).max() > 0 else vector[n:]
    shape = stiffness * np.abs(q_part) ** 2
    if not shape.max() > 0:
        shape = np.abs(q_part)
    order = np.argsort(-shape)
    keep = [k for k in order if shape[k] >= SHAPE_SHARE * shape[order[0]]][:3]
    return tuple(names[k] for k in keep)


def _violation_name(system, a, q_part):
    """('constraint violation (Baumgarte alpha, beta)',) when the mode's shape mostly leaves
    the constraint manifold (|A v| above VIOLATION_SHARE |A| |v|), else None."""
    if a is None or not np.abs(q_part).max() > 0:
        return None
    leaving = np.linalg.norm(a @ q_part) / (np.linalg.norm(a, 2) * np.linalg.norm(q_part))
    if leaving > VIOLATION_SHARE:
        return (f"constraint violation (Baumgarte alpha = {system.alpha:g}, "
                f"beta = {system.beta:g} 1/s)",)
    return None


def _baumgarte_modes(system):
    if not system.n_constraints:
        return []
    roots = np.roots([1.0, 2.0 * system.alpha, system.beta ** 2])
    name = (f"constraint violation (Baumgarte alpha = {system.alpha:g}, beta = "
            f"{system.beta:g} 1/s)",)
    return [Mode(complex(r), name, rk4_stability_step(r))
            for r in roots]


def springs_jacobian(model, q):
    """(2n, 2n) 1/s: [[0, I], [-M^-1 K, -M^-1 D]] of the joint and RFEM springs and dampers,
    the point springs (gpme_core.point_springs.point_spring_matrices) and the mass matrix
    at q (gravity, velocity terms and constraints left out)."""
    n = model.n_coordinates
    m_inv = np.linalg.inv(mass_matrix(model, q))
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -m_inv * model.stiffness[None, :]
    a[n:, n:] = -m_inv * model.damping[None, :]
    if model.point_springs:
        k_ps, d_ps = point_spring_matrices(model, chain_kinematics(model, q))
        a[n:, :n] -= m_inv @ k_ps
        a[n:, n:] -= m_inv @ d_ps
    return a


def safe_step(limit, cap=np.inf, safety=STEP_SAFETY):
    """s: the RK4 step taken for a stability limit ``limit`` (s): ``safety`` x limit, at
    most ``cap`` (an output spacing, a run's length, an engine's largest step)."""
    return float(min(safety * limit, cap))


def rk4_step(system, q, q_dot=None, cap=np.inf, how="springs", t=0.0):
    """s: the RK4 step gpme takes where none is given: STEP_SAFETY x the stability limit
    (rk4_limit) of ``system`` (gpme_core.gpme.ProgrammedMotion) at (t, q, q_dot), at most
    ``cap``.  The one step policy of the project: `simulate` without dt (``how`` None: the
    linearised run up to MAX_LINEARISED coordinates), a model file without [run] dt, a
    scenario built in code without one, the crane's finer arms, the sweep's points and the
    engines' fallbacks (``how`` "springs": springs, dampers, inertia and the Baumgarte
    rates, cheap at any size).
    q, q_dot : (n,) initial state (q_dot default zeros: the springs estimate ignores it)."""
    q = np.asarray(q, dtype=float)
    q_dot = np.zeros_like(q) if q_dot is None else np.asarray(q_dot, dtype=float)
    limit, _ = rk4_limit(system, t, q, q_dot, how)
    return safe_step(limit, cap)


def suggest_rk4_step(model, q, safety=0.5):
    """s: a stable RK4 step for small oscillations of a bare model (no constraints) about q
    (springs, dampers, inertia); the step of a run is :func:`rk4_step`'s.

    Eigenvalues of the linearised first-order system [[0, I], [-M^-1 K, -M^-1 D]] at q
    (gravity stiffness and constraints neglected: they are slow here); returns ``safety``
    times the smallest RK4 stability step over them.  With Kelvin-Voigt RFEM dampers the
    limit can come from the overdamped high modes (real eigenvalues ~ -eta/E omega^2).
    """
    a = springs_jacobian(model, q)
    steps = [rk4_stability_step(lam) for lam in np.linalg.eigvals(a)]
    return safe_step(min(steps), safety=safety)


def _linearised_jacobian(system, t, q, q_dot):
    n = system.model.n_coordinates
    y = np.concatenate([q, q_dot])

    def f(yy):     # the partition re-chosen where it is badly conditioned, as in a run
        sol = system.solve(t, yy[:n], yy[n:], switch_below=SWITCH_RCOND)
        return np.concatenate([yy[n:], sol.q_ddot])
    a = np.empty((2 * n, 2 * n))
    for j in range(2 * n):
        h = 1e-6 * max(1.0, abs(y[j]))
        up, down = y.copy(), y.copy()
        up[j] += h
        down[j] -= h
        a[:, j] = (f(up) - f(down)) / (2 * h)
    return a


def linear_modes(system, t, q, q_dot, how=None):
    """Modes of the linearised run at (t, q, q_dot), the most step-limiting first.

    system : gpme_core.gpme.ProgrammedMotion (not changed; without dependent coordinates the
             pivoted choice at (t, q) is used)
    q, q_dot : (n,) m or rad, m/s or rad/s, ordered as model.coordinate_names
    how    : "linearised", "springs" or None (linearised up to MAX_LINEARISED coordinates)
    Returns a list of :class:`Mode`, sorted by rk4_step (ascending).
    """
    model = system.model
    n = model.n_coordinates
    q = np.asarray(q, dtype=float)
    q_dot = np.asarray(q_dot, dtype=float)
    how = how or ("linearised" if n <= MAX_LINEARISED else "springs")
    if how not in ("linearised", "springs"):
        raise ModelError(f"how must be 'linearised' or 'springs', got {how!r}")
    if how == "linearised":
        if system.dependent is None and system.n_constraints:
            system = system.with_dependent(system.pivoted_dependent(t, q, q_dot))
        jac = _linearised_jacobian(system, t, q, q_dot)
        extra = []
    else:
        jac = springs_jacobian(model, q)
        extra = _baumgarte_modes(system)
    if not np.all(np.isfinite(jac)):
        raise ModelError(f"the linearisation at t = {t:.6g} s is not finite; the state is "
                         "outside where the model is defined")
    values, vectors = np.linalg.eig(jac)
    names = list(model.coordinate_names)
    stiffness = np.asarray(model.stiffness, dtype=float)
    a = system.constraints(t, q, q_dot)[2] if (how == "linearised" and
                                                system.n_constraints) else None
    modes = [Mode(complex(lam), _violation_name(system, a, vectors[:n, k]) or
                  _shape_names(names, vectors[:, k], n, stiffness), rk4_stability_step(lam))
             for k, lam in enumerate(values)] + extra
    return sorted(modes, key=lambda m: m.rk4_step)


def rk4_limit(system, t, q, q_dot, how=None):
    """(s, Mode): the largest stable RK4 step at (t, q, q_dot) and the mode that sets it."""
    stiffest = linear_modes(system, t, q, q_dot, how)[0]
    return stiffest.rk4_step, stiffest


def round_down(step, digits=2):
    """``step`` rounded down to ``digits`` significant figures (a step to suggest)."""
    if not np.isfinite(step) or step <= 0:
        return step
    scale = 10.0 ** (np.floor(np.log10(step)) - digits + 1)
    mantissa = np.floor(step / scale * (1 + 1e-12))      # 0.29 / 0.01 = 28.999...: 29
    return float(f"{mantissa * scale:.{digits}g}")


def unstable_step_message(dt, limit, mode, where):
    """Text of the error for an RK4 step above the stability limit ``limit`` (s)."""
    return (f"the RK4 step dt = {dt:.3g} s is unstable {where}: it is above the stability "
            f"limit {limit:.3g} s of the stiffest mode ({mode.describe()}); use dt <= "
            f"{round_down(STEP_SAFETY * limit):.2g} s (half the limit), or an adaptive "
            "method (Radau for stiff models)")

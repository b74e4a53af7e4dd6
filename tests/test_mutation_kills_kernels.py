"""Kill tests for gpme_core.kernels (docs/mutation.md, "gpme_core/kernels.py"): what the
compiled evaluation and the Radau IIA loop must give on systems small enough to be solved
by hand, with expected values from closed forms (never from the kernels).

* A single programmed axis (n = m = 1, the smallest constrained system: the kernels'
  workspace is sized for it exactly): a slider along the vertical whose coordinate follows
  f(t).  Its acceleration is Baumgarte's f'' - 2 alpha (q_dot - f') - beta^2 (q - f) and
  the multiplier is the force the programme needs, m q_ddot + m g + k (q - q_ref) + d q_dot
  - T(t); the info rates are d q_dot^2, q_dot T and q_dot lambda.  Without the programme
  (n = 1, m = 0) the slider moves under its forces alone.
* The Radau IIA loop given a kept Jacobian that no longer fits: simplified Newton with its
  matrix diverges, the loop must compute a fresh Jacobian and take the step again.  On a
  linear oscillator y' = L y a step of Radau IIA is y -> R(h L) y with the method's
  stability function R(z) = (1 + 2z/5 + z^2/20) / (1 - 3z/5 + 3z^2/20 - z^3/60) (the (2, 3)
  Pade approximant of exp; Hairer & Wanner, Solving ODEs II, IV.5).
* The Cholesky solve of the reduced matrix on both of its paths (its own loops below
  kernels.LAPACK_FROM rows, LAPACK's factor from there on): the solution of a symmetric
  positive definite system (against numpy's LU), and False for a symmetric matrix with a
  positive diagonal that is not positive definite (a negative eigenvalue by construction).
* The compiled reduced solve at the singular-partition threshold, where gpme_core.gpme's
  rule (singular when rcond <= the threshold) decides, on an rcond exact in floating point.
"""
import numpy as np
import pytest

from gpme_core import compiled, compiled_runs, fast, kernels
from gpme_core.constraints import JointProgramme
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.model import PRISMATIC, ChainBuilder
from gpme_core.time_functions import Sine

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: no compiled path")

MASS, K, Q_REF, D, G0 = 2.5, 40.0, 0.3, 1.2, 9.81        # kg, N/m, m, N s/m, m/s^2
DRIVE = (0.4, 3.0, 0.7, 0.2)           # Sine: offset N, amplitude N, period s, phase rad
PROGRAMME = (0.1, 0.25, 1.3, -0.5)     # Sine: offset m, amplitude m, period s, phase rad
ALPHA, BETA = 7.0, 11.0                # Baumgarte, 1/s


def sine(p, t):
    """(f, f', f'') of offset + amplitude sin(2 pi t / period + phase)."""
    off, amp, period, phase = p
    w = 2.0 * np.pi / period
    return (off + amp * np.sin(w * t + phase), amp * w * np.cos(w * t + phase),
            -amp * w * w * np.sin(w * t + phase))


def vertical_slider():
    """One prismatic joint along world z (gravity -G0 z acts along it) carrying MASS, with
    a spring K to Q_REF, a damper D and a sinusoidal drive force."""
    b = ChainBuilder("vertical_slider", gravity=(0.0, 0.0, -G0))
    b.add_joint("z", PRISMATIC, (0, 0, 1), stiffness=K, spring_reference=Q_REF, damping=D)
    b.add_body(cuboid(MASS, (0.2, 0.1, 0.3), com=(0.05, -0.02, 0.1)))
    b.add_drive("z", Sine(*DRIVE))
    return b.build()


def _evaluate(system, t, q, q_dot):
    form, reason = compiled.for_system(system)
    assert form is not None, reason
    return form.evaluate(t, np.array([q]), np.array([q_dot]), system.ic, system.dc)


@pytest.mark.parametrize("t, q, q_dot", [(0.0, 0.1, 0.0), (0.37, -0.2, 1.5), (1.9, 0.45, -2.0)])
def test_single_programmed_axis_needs_the_force_of_its_programme(t, q, q_dot):
    system = ProgrammedMotion(vertical_slider(), [JointProgramme("z", Sine(*PROGRAMME))],
                              dependent=("z",), baumgarte=(ALPHA, BETA))
    status, q_ddot, lam, info = _evaluate(system, t, q, q_dot)
    assert status == kernels.OK
    f, f_t, f_tt = sine(PROGRAMME, t)
    drive = sine(DRIVE, t)[0]
    # the states are off the programme: Baumgarte's terms are part of the answer
    expected = f_tt - 2.0 * ALPHA * (q_dot - f_t) - BETA ** 2 * (q - f)
    force = MASS * expected + MASS * G0 + K * (q - Q_REF) + D * q_dot - drive
    # O(10) flops on values of O(100): round-off ~1e-13
    np.testing.assert_allclose(q_ddot, [expected], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(lam, [force], rtol=1e-12, atol=1e-12)
    # info: partition rcond of A = [1] (1 / (|A_dc^-1|_1 |A|_1) = 1), the power of the
    # damper, of the drive and of the programme's force
    np.testing.assert_allclose(info[:4], [1.0, D * q_dot ** 2, q_dot * drive, q_dot * force],
                               rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("t, q, q_dot", [(0.0, 0.1, 0.0), (0.37, -0.2, 1.5)])
def test_single_free_axis_moves_under_its_forces(t, q, q_dot):
    system = ProgrammedMotion(vertical_slider())
    status, q_ddot, lam, info = _evaluate(system, t, q, q_dot)
    assert status == kernels.OK and lam.shape == (0,)
    drive = sine(DRIVE, t)[0]
    expected = (-MASS * G0 - K * (q - Q_REF) - D * q_dot + drive) / MASS
    np.testing.assert_allclose(q_ddot, [expected], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(info[1:3], [D * q_dot ** 2, q_dot * drive], rtol=1e-12,
                               atol=1e-12)


# ---------------------------------------------------------------- Radau IIA, stale Jacobian
OMEGA2, DAMP = 100.0, 1.0              # q'' = -OMEGA2 q - DAMP q' (per unit mass)
STEP = 0.05                            # s: h omega = 0.5
STALE_JQ = 4000.0                      # the kept d q_ddot / d q (the true one: -OMEGA2)
_S6 = np.sqrt(6.0)
RADAU_IIA = np.array([                 # Butcher matrix of the 3-stage Radau IIA method
    [(88 - 7 * _S6) / 360, (296 - 169 * _S6) / 1800, (-2 + 3 * _S6) / 225],
    [(296 + 169 * _S6) / 1800, (88 + 7 * _S6) / 360, (-2 - 3 * _S6) / 225],
    [(16 - _S6) / 36, (16 + _S6) / 36, 1 / 9]])


def horizontal_oscillator():
    """Unit mass on a spring OMEGA2 N/m and a damper DAMP N s/m, sliding along x (gravity
    -z does no work on it)."""
    b = ChainBuilder("oscillator")
    b.add_joint("x", PRISMATIC, (1, 0, 0), stiffness=OMEGA2, damping=DAMP)
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    return b.build()


def radau_step_matrix(h):
    """R(h L) of the oscillator's y' = L y, y = (q, q_dot): the Radau IIA step."""
    z = h * np.array([[0.0, 1.0], [-OMEGA2, -DAMP]])
    eye = np.eye(2)
    p = eye + 0.4 * z + z @ z / 20.0
    den = eye - 0.6 * z + 0.15 * z @ z - z @ z @ z / 60.0
    return np.linalg.solve(den, p)


def test_stale_simplified_newton_would_diverge():
    """The premise of the next test, from the method alone: simplified Newton on the stage
    velocities with the matrix of the kept Jacobian multiplies the error by
    W_kept^-1 (W_kept - W_true), W = I - h A J_v - h^2 A^2 J_q; its spectral radius is > 1."""
    a2 = RADAU_IIA @ RADAU_IIA
    eye = np.eye(3)
    w_true = eye - STEP * RADAU_IIA * -DAMP - STEP ** 2 * a2 * -OMEGA2
    w_kept = eye - STEP * RADAU_IIA * -DAMP - STEP ** 2 * a2 * STALE_JQ
    growth = np.linalg.solve(w_kept, w_kept - w_true)
    assert np.abs(np.linalg.eigvals(growth)).max() > 2.0


@pytest.mark.parametrize("n_steps", [1, 4])
def test_radau_iia_renews_a_kept_jacobian_that_no_longer_fits(n_steps):
    """Two steps keep the Jacobian computed at the first (the oscillator is linear: each
    stage solve converges in a few iterations); then the kept Jacobian is made to no longer
    fit (as after a change in the motion) and the loop asked to rebuild its Newton matrix
    from it.  The first Newton attempt diverges (test above); the step must be taken again
    with a fresh Jacobian, not fail, and every step must be the Radau IIA step R(h L)."""
    system = ProgrammedMotion(horizontal_oscillator())
    form, reason = compiled.for_system(system)
    assert form is not None, reason
    w_inv, jq, jv, v_prev, ctrl = work = compiled_runs.radau_work(1)
    y0 = np.array([0.1, 0.5, 0.0, 0.0, 0.0])
    y, fail_y = y0.copy(), np.empty_like(y0)
    args = (form.md, form.cd, form.options(), system.ic, system.dc, work, fail_y)
    status, done, _ = kernels.radau_advance(0.0, y, STEP, 2, *args)
    assert status == kernels.OK and done == 2
    # one Jacobian, computed at the first step's start and kept for two steps
    assert ctrl[kernels.R_JACOBIANS] == 1 and ctrl[kernels.R_JAC_AGE] == 2.0
    jq[:] = STALE_JQ
    ctrl[kernels.R_STEP] = np.nan          # rebuild the Newton matrix from the kept Jacobian
    status, done, _ = kernels.radau_advance(2 * STEP, y, STEP, n_steps, *args)
    assert status == kernels.OK and done == n_steps
    assert ctrl[kernels.R_JACOBIANS] == 2                  # the fresh one
    expected = np.linalg.matrix_power(radau_step_matrix(STEP), 2 + n_steps) @ y0[:2]
    # stage velocities converged to 1e-10 (1 + |v|) (compiled_runs.NEWTON_TOL): q and
    # q_dot agree to ~1e-10 per step
    np.testing.assert_allclose(y[:2], expected, rtol=0, atol=1e-9)
    # the work integral of the damper: positive, and below what it can dissipate (the
    # energy at the start, 0.5 (q_dot^2 + OMEGA2 q^2))
    assert 0.0 < y[2] < 0.5 * (y0[1] ** 2 + OMEGA2 * y0[0] ** 2)


# ---------------------------------------------------------------- Cholesky solve
@pytest.mark.parametrize("r", [5, kernels.LAPACK_FROM, kernels.LAPACK_FROM + 6])
def test_cholesky_solve_of_positive_definite_and_indefinite_matrices(r):
    rng = np.random.default_rng(r)
    b = rng.normal(size=r)
    half = rng.normal(size=(r, r))
    spd = half @ half.T + r * np.eye(r)            # eigenvalues >= r
    x, low = np.zeros(r), np.zeros((r, r))
    assert kernels._cholesky_solve(spd, b, low, x)
    np.testing.assert_allclose(x, np.linalg.solve(spd, b), rtol=1e-12, atol=1e-14)
    # diagonal 1, one off-diagonal pair 2: the block [[1, 2], [2, 1]] has eigenvalue -1
    indefinite = np.eye(r)
    indefinite[r - 2, r - 1] = indefinite[r - 1, r - 2] = 2.0
    assert np.linalg.eigvalsh(indefinite).min() == pytest.approx(-1.0)
    assert not kernels._cholesky_solve(indefinite, b, np.zeros((r, r)), np.zeros(r))


# ---------------------------------------------------------------- singular partition
def test_partition_exactly_at_the_singular_threshold_is_singular():
    """gpme_core.gpme's rule, which the compiled reduced solve shares: a partition is
    singular when its rcond does not exceed the threshold (rcond <= singular_rcond).  One
    constraint 2^-40 x_0 + x_1 = 0 with x_0 dependent: A_dc^-1 = 2^40 and ||A||_1 = 1, so
    the partition rcond 1 / (||A_dc^-1||_1 ||A||_1) is 2^-40 exactly (powers of two)."""
    tiny = 2.0 ** -40
    a = np.array([[tiny, 1.0]])
    ic, dc = np.array([1]), np.array([0])
    for threshold, status_expected in ((tiny, kernels.SINGULAR_PARTITION), (tiny / 2, kernels.OK)):
        q_ddot, lam = np.zeros(2), np.zeros(1)
        ws = np.empty(kernels.reduced_scratch_size(2, 1))
        status, rel = kernels.reduced_solve(np.eye(2), np.array([0.3, -0.2]), a, np.zeros(1),
                                            ic, dc, 0.0, threshold, q_ddot, lam, ws)
        assert rel == tiny
        assert status == status_expected, (threshold, status)

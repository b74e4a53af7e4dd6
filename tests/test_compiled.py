"""The fused compiled right-hand side (gpme_core.compiled, gpme_core.kernels.evaluate)
against the Python reference (ProgrammedMotion.solve on the numpy path).

The reference is computed with gpme_core.fast disabled, so nothing of it runs in numba:
kinematics, trace-form terms, springs, dampers, drives, constraint rows and the reduced
solve (LU of [N^T M; A]) are the readable numpy code.  The compiled kernel solves the same
equations through the Cholesky factor of N^T M N.  At seeded random states (off the
constraint manifold, so Baumgarte's terms count) each case checks:

* q_ddot (n,) and the multipliers (m,) against the reference, to the round-off a solve of
  that conditioning allows (the condition number is computed from the reference's M and A);
* the compiled pair put into the reference's equations, row by row: M q_ddot - (h + Q) =
  A^T lambda and A q_ddot = -kappa - 2 alpha Phi_dot - beta^2 Phi (a wrong or missing
  term shows here at its own size, however small beside the stiff rows);
* the info entries: partition rcond and the work rates q_dot.(D q_dot), q_dot.t(t),
  q_dot.(A^T lambda) in W.

Also: which systems compile (a user subclass or a plain function keeps the Python path,
with the reason naming it), the cache of the compiled form on a system, and where the
generated code of SymPy parts is written.

The SymPy parts of these tests all live in one system (:func:`sympy_crane`, shared with
tests/test_compiled_runs.py), so one generated kernels module serves them all: compiled
once when the kernel cache (GPME_KERNEL_CACHE, default ~/.cache/gpme/kernels) is cold
(about 30 s for the evaluation, 20 s more for the RK4 loop), loaded from it afterwards.
"""
import numpy as np
import pytest

from conftest import spatial_arm, spatial_tree
from gpme_core import compiled, fast, kernels
from gpme_core import transforms as tf
from gpme_core.constraints import (CoordinateProgramme, EllipseConstraint, JointProgramme,
                                   PointConstraint, SympyPointConstraint)
from gpme_core.dynamics import dynamics_terms
from gpme_core.errors import ConstraintError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.model import Drive, Frame, Model, validate_model
from gpme_core.time_functions import (Constant, Cosine, QuinticRamp, Sine,
                                      SympyTimeFunction, Tabulated, TimeFunction)
from gpme_examples.crane import build_crane, crane_constraints, crane_system, initial_state

pytestmark = pytest.mark.skipif(not fast.ENABLED, reason="GPME_NO_JIT=1: no compiled path")

# ---------------------------------------------------------------- models
# time functions of every built-in kind, with the times that reach each branch: QuinticRamp
# before (t < 0), inside and after its ramp (0.3 s, end exactly); Tabulated before, at its
# first knot, at an interior knot, inside a piece and after its last knot (0.4 s, exactly)
TABLE = Tabulated((0.0, 0.1, 0.25, 0.4), (0.05, 0.3, -0.1, 0.2))
LINE = Tabulated((0.0, 0.3), (0.1, -0.2))           # two points: a straight line
TIME_FUNCTIONS = {
    "constant": Constant(0.15),
    "cosine": Cosine(0.1, 0.2, 0.7),
    "sine": Sine(-0.05, 0.25, 0.45, phase=0.6),
    "quintic_ramp": QuinticRamp(0.3, 0.3),
    "tabulated": TABLE,
}
TIMES = (-0.1, 0.0, 0.1, 0.17, 0.25, 0.3, 0.4, 0.55)   # s


def arm_with_drives():
    """The spatial arm of tests/conftest.py (5 coordinates, skewed axes, springs and
    dampers) with frames M1 on link 1 and M2 on link 2 (not the last link) and a drive of
    every built-in kind, two of them on q0 (their sum acts)."""
    base = spatial_arm()
    frames = dict(base.frames)
    frames["M1"] = Frame("M1", 1, tf.translation(0.05, 0.2, -0.1))
    frames["M2"] = Frame("M2", 2, tf.translation(0.3, -0.05, 0.04) @ tf.rot_z(0.3))
    drives = (Drive("q0", Constant(0.4)), Drive("q1", Cosine(0.2, -1.5, 0.8)),
              Drive("q2", Sine(0.1, 0.7, 0.35, phase=-0.4)), Drive("q3", QuinticRamp(-0.6, 0.3)),
              Drive("q4", TABLE), Drive("q0", LINE))
    model = Model(base.joints, base.links, frames, drives, base.gravity, base.flexible_links,
                  "spatial_arm_driven")
    validate_model(model)
    return model


ARM = arm_with_drives()

# the SymPy parts: two point constraints and two time functions, all distinct so that a
# mix-up of their indices in the generated dispatch shows.  PHI_HEIGHT holds a term that
# is not finite after t = 0.05 s (a square root) and divides by zero at t = 0.05 s exactly
# (its time derivatives): tests/test_compiled_runs.py runs into both.
SUPPORT = SympyTimeFunction("0.002*sin(7*t) + 0.01*t**2 + 0.003*exp(-t) - 0.003",
                            name="support")                  # m, programme of z1; 0 at t = 0
TORQUE = SympyTimeFunction("0.5*(1 - cos(4*t)) + 0.2*t", name="torque")   # N m, on psi2
PHI_ELLIPSE = "(x/0.375)**2 + (y/0.75)**2 - 1 + 0.01*z*sin(2*t)"
PHI_HEIGHT = ("z - 1 - 0.5*cos(0.8*pi*t) + 0.1*x*y*sin(3*t) + 0.05*(x - z)**2*exp(-t)"
              " + 1e-9*sqrt(0.05 - t)")
SINGULAR_AT = 0.05          # s, where PHI_HEIGHT's time derivatives divide by zero


def sympy_crane():
    """The rigid crane with SymPy constraints on E (an ellipse moving with z, the paper's
    height programme with couplings), a SymPy programme of the support z1 and a SymPy drive
    on psi2 besides the paper's QuinticRamp; dependent coordinates chosen by pivoting."""
    base = build_crane(0)
    model = Model(base.joints, base.links, base.frames, base.drives + (Drive("psi2", TORQUE),),
                  base.gravity, base.flexible_links, "crane_sympy")
    validate_model(model)
    return ProgrammedMotion(model, [SympyPointConstraint(PHI_ELLIPSE, frame="E", name="Phi_1s"),
                                    SympyPointConstraint(PHI_HEIGHT, frame="E", name="Phi_2s"),
                                    JointProgramme("z1", SUPPORT, name="Phi_z1")])


def _arm_constraints():
    fns = TIME_FUNCTIONS
    cases = {
        "ellipse": [EllipseConstraint(0.5, 0.3, center=(0.1, -0.2), frame="E", name="ell")],
        "coordinate_x": [CoordinateProgramme(fns["sine"], axis=0, frame="E", name="px")],
        "coordinate_y": [CoordinateProgramme(fns["tabulated"], axis=1, frame="E", name="py")],
        "coordinate_z": [CoordinateProgramme(fns["quintic_ramp"], axis=2, frame="E", name="pz")],
        "joint": [JointProgramme("q2", fns["cosine"], name="j2")],
        "frame_not_last": [EllipseConstraint(0.4, 0.6, center=(0.2, 0.1), frame="M2", name="e2"),
                           CoordinateProgramme(fns["constant"], axis=0, frame="M1", name="h1")],
        # four rows: two on E (one point shared), one on M1, one joint
        "combined": [EllipseConstraint(0.5, 0.4, frame="M1", name="e1"),
                     CoordinateProgramme(fns["tabulated"], axis=2, frame="E", name="pz"),
                     CoordinateProgramme(fns["quintic_ramp"], axis=0, frame="E", name="px"),
                     JointProgramme("q4", fns["sine"], name="j4")],
    }
    # each kind of time function as the programme of a point and of a joint
    for kind, fn in fns.items():
        cases[f"programmes_{kind}"] = [CoordinateProgramme(fn, axis=1, frame="M2", name="py2"),
                                       JointProgramme("q3", fn, name="j3")]
    return cases


def _crane_paper_eq7():
    return ProgrammedMotion(build_crane(2), crane_constraints(), dependent=("psi3", "z4"),
                            damping_form="paper-eq7")


SYSTEMS = {
    "crane_rigid": lambda: crane_system(0),
    "crane_flexible_n3": lambda: crane_system(3),
    "crane_n2_paper_eq7": _crane_paper_eq7,
    "crane_n2_no_constraints": lambda: ProgrammedMotion(build_crane(2)),
    "arm_no_constraints": lambda: ProgrammedMotion(ARM),
    **{f"arm_{name}": (lambda c=c: ProgrammedMotion(ARM, c))
       for name, c in _arm_constraints().items()},
    "tree_no_constraints": lambda: ProgrammedMotion(spatial_tree()),
    "tree_pair_constraints": lambda: ProgrammedMotion(spatial_tree(), _pair_constraints()),
}


def _pair_constraints():
    """Every kind of gpme_core.pair_constraints between frames E and F of the tree (two
    branches), time dependent where it can be; the SymPy one is generated code."""
    from gpme_core.pair_constraints import (AxisAlignment, Distance, RelativeCoordinate,
                                            SympyPairConstraint)
    return [RelativeCoordinate("E", "F", "x", Cosine(0.1, 0.2, 3.0), name="rel_x"),
            Distance("E", "F", QuinticRamp(0.5, 1.0), name="rod"),
            AxisAlignment("E", "y", "F", "z", Sine(0.0, 0.1, 2.0, 0.3), name="angle"),
            SympyPairConstraint("(x_b - x_a)**2 + y_b*z_a - 0.1*sin(3*t)", "E", "F",
                                name="sym")]


# ---------------------------------------------------------------- the comparison
def _reference(system, t, q, q_dot, monkeypatch):
    """(GpmeSolution, DynamicsTerms) of the numpy path (gpme_core.fast disabled)."""
    monkeypatch.setattr(fast, "ENABLED", False)
    try:
        return system.solve(t, q, q_dot), dynamics_terms(system.model, t, q, q_dot)
    finally:
        monkeypatch.undo()


def _reduced_matrix(system, mass, a):
    """N^T M N of the partition of ``system`` ((n - m) x (n - m); M itself without
    constraints), from the reference's M (n, n) and A (m, n)."""
    if system.n_constraints == 0:
        return mass
    n = mass.shape[0]
    null = np.zeros((n, n - system.n_constraints))
    null[system.ic] = np.eye(n - system.n_constraints)
    null[system.dc] = -np.linalg.solve(a[:, system.dc], a[:, system.ic])
    return null.T @ mass @ null


def assert_evaluation_matches(cs, system, t, q, q_dot, monkeypatch, label=""):
    """The compiled evaluation of ``cs`` (CompiledSystem) at (t s, q (n,), q_dot (n,)) with
    the partition of ``system`` against the numpy reference (module docstring)."""
    status, q_ddot, lam, info = cs.evaluate(t, q, q_dot, system.ic, system.dc)
    assert status == kernels.OK, label
    sol, terms = _reference(system, t, q, q_dot, monkeypatch)
    a, mass = sol.jacobian, terms.M
    rcond = sol.partition_rcond
    cond = np.linalg.cond(_reduced_matrix(system, mass, a))
    # Forward error of a backward-stable solve: ~ c n eps cond of its matrix (here <= 0.13
    # eps cond measured); the partition adds Gamma = -A_dc^-1 A_ic, relative error ~
    # eps / rcond.  1e-14 (~45 eps) x cond / rcond covers c n for n <= 14 with margin.
    amplification = cond / rcond
    tol_q = 1e-14 * amplification * np.abs(sol.q_ddot).max()
    np.testing.assert_allclose(q_ddot, sol.q_ddot, rtol=0, atol=tol_q,
                               err_msg=f"{label} q_ddot (cond {cond:.2e}, rcond {rcond:.2e})")
    d_forces = terms.d * (2.0 if system.damping_form == "paper-eq7" else 1.0)
    rhs = terms.h - terms.g - terms.f - d_forces + terms.t
    term_sizes = (np.abs(terms.h) + np.abs(terms.g) + np.abs(terms.f) + np.abs(d_forces)
                  + np.abs(terms.t))
    if system.n_constraints:
        # lambda = A_dc^-T (M q_ddot - h - Q)_dc: the forward error of q_ddot through M,
        # plus the round-off of the force sum (~ eps x the size of its terms, the stiff
        # springs of the RFEM arm cancel against M q_ddot), both through A_dc^-T
        inv_dc = np.linalg.inv(a[:, system.dc])
        force_size = (np.abs(mass) @ np.abs(sol.q_ddot) + term_sizes).max()
        tol_lam = np.abs(inv_dc).sum(axis=0).max() * (
            np.abs(mass).sum(axis=1).max() * tol_q + 1e-14 * amplification * force_size)
        np.testing.assert_allclose(lam, sol.multipliers, rtol=0, atol=tol_lam,
                                   err_msg=f"{label} multipliers")
    else:
        assert lam.shape == (0,) and sol.multipliers.shape == (0,)
        tol_lam = 0.0
    # Row-wise backward error of the compiled pair in the reference's equations, relative
    # to the sum of the magnitudes of each row's terms.  Measured <= 1.5e-12 (the normwise
    # backward error of the Cholesky solve, ~n eps ||N^T M N|| ||z||, seen in a light row
    # beside the stiff RFEM rows); 1e-10 bounds it, while a wrong or missing term (a
    # drive, spring, damper, constraint or Baumgarte term) is off by its own size.
    force_residual = mass @ q_ddot - rhs - a.T @ lam
    force_scale = np.abs(mass) @ np.abs(q_ddot) + term_sizes + np.abs(a.T) @ np.abs(lam)
    assert np.all(np.abs(force_residual) <= 1e-10 * force_scale), (
        label, force_residual / force_scale)
    if system.n_constraints:
        alpha, beta = system.alpha, system.beta
        c = -sol.kappa - 2.0 * alpha * sol.phi_dot - beta ** 2 * sol.phi
        row_residual = a @ q_ddot - c
        row_scale = (np.abs(a) @ np.abs(q_ddot) + np.abs(sol.kappa)
                     + 2.0 * alpha * np.abs(sol.phi_dot) + beta ** 2 * np.abs(sol.phi))
        assert np.all(np.abs(row_residual) <= 1e-10 * row_scale), (
            label, row_residual / row_scale)
    # info: partition rcond = 1 / (||A_dc^-1||_1 ||A||_1) from the same A up to round-off;
    # ||A_dc^-1|| carries eps cond(A_dc) <= eps / rcond relative
    assert info[0] == pytest.approx(rcond, rel=1e-14 / rcond, abs=0.0), label
    # work rates (W): sums of n products of the same numbers (same damper and drive forces)
    abs_qd = np.abs(q_dot)
    assert abs(info[1] - q_dot @ terms.d) <= 1e-14 * (abs_qd @ np.abs(terms.d)), label
    assert abs(info[2] - q_dot @ terms.t) <= 1e-14 * (abs_qd @ np.abs(terms.t)), label
    # q_dot.(A^T lambda): the multipliers' tolerance through |q_dot| |A^T|
    reaction = sol.reaction_forces
    assert abs(info[3] - q_dot @ reaction) <= (
        abs_qd @ np.abs(a.T) @ np.full(system.n_constraints, tol_lam)
        + 1e-14 * (abs_qd @ np.abs(reaction))), label


def _random_state(model, rng):
    """(q (n,), q_dot (n,)): the crane near its paper start (psi3 = pi/4, z4 = 0.2 m), any
    other model around zero; both off any constraint manifold."""
    n = model.n_coordinates
    if model.name.startswith("crane"):
        q0, _ = initial_state(model)
        return q0 + rng.normal(0.0, 0.1, n), rng.normal(0.0, 0.5, n)
    return rng.uniform(-1.0, 1.0, n), rng.uniform(-2.0, 2.0, n)


def _partitions(system, t, q, q_dot, monkeypatch):
    """Copies of ``system`` with the pivoted partition at the state and, when it has one
    that is not badly conditioned there, its own."""
    out = [system.with_dependent(system.pivoted_dependent(t, q, q_dot))]
    if system.dependent is not None and system.n_constraints:
        if _reference(system, t, q, q_dot, monkeypatch)[0].partition_rcond > 1e-3:
            out.append(system)
    return out


# ---------------------------------------------------------------- 1. evaluation
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_compiled_evaluation_equals_python_reference(name, rng, monkeypatch):
    system = SYSTEMS[name]()
    cs, reason = compiled.for_system(system)
    assert cs is not None, reason
    times = TIMES if name.startswith("arm") else rng.uniform(0.0, 2.0, 3)
    for t in times:
        q, q_dot = _random_state(system.model, rng)
        for part in _partitions(system, t, q, q_dot, monkeypatch):
            assert_evaluation_matches(cs, part, float(t), q, q_dot, monkeypatch,
                                      f"{name} t = {t} dependent {part.dependent}")


def test_compiled_sympy_parts_equal_python_reference(rng, monkeypatch):
    """SymPy point constraints, a SymPy programme and a SymPy drive (generated code)."""
    system = sympy_crane()
    cs, reason = compiled.for_system(system)
    assert cs is not None, reason
    assert cs.module is not kernels                       # the generated module
    for t in np.concatenate([[0.0], rng.uniform(0.0, 0.045, 5)]):   # before PHI_HEIGHT's end
        q, q_dot = _random_state(system.model, rng)
        for part in _partitions(system, t, q, q_dot, monkeypatch):
            assert_evaluation_matches(cs, part, float(t), q, q_dot, monkeypatch,
                                      f"sympy t = {t} dependent {part.dependent}")


def test_compiled_sympy_constraint_out_of_its_domain_is_a_status(rng, monkeypatch):
    """After t = 0.05 s PHI_HEIGHT's square root is not real: the compiled evaluation
    returns NOT_FINITE (never NaN results), the Python reference raises the error."""
    system = sympy_crane()
    cs, _ = compiled.for_system(system)
    q, q_dot = _random_state(system.model, rng)
    part = system.with_dependent(system.pivoted_dependent(0.0, q, q_dot))
    status, *_ = cs.evaluate(0.06, q, q_dot, part.ic, part.dc)
    assert status == kernels.NOT_FINITE
    with pytest.raises(ConstraintError, match=r"constraint 'Phi_2s'.*not finite at t = 0\.06 s"):
        part.solve(0.06, q, q_dot)


def test_compiled_sympy_constraint_at_its_pole_is_a_status(rng, monkeypatch):
    """At t = 0.05 s exactly PHI_HEIGHT's time derivatives divide by zero: the compiled
    evaluation must return NOT_FINITE like any other value that is not finite."""
    system = sympy_crane()
    cs, _ = compiled.for_system(system)
    q, q_dot = _random_state(system.model, rng)
    part = system.with_dependent(system.pivoted_dependent(0.0, q, q_dot))
    with pytest.raises(ConstraintError, match=r"constraint 'Phi_2s'.*not finite at t = 0\.05 s"):
        part.solve(SINGULAR_AT, q, q_dot)
    status, *_ = cs.evaluate(SINGULAR_AT, q, q_dot, part.ic, part.dc)
    assert status == kernels.NOT_FINITE


# ---------------------------------------------------------------- 2. what compiles
class Ring(PointConstraint):
    """A user's constraint: x^2 + y^2 - r^2 on frame E (r = 0.5 m)."""

    name, frame = "ring", "E"

    def local_terms(self, p, t):
        return (p[0] ** 2 + p[1] ** 2 - 0.25, np.array([2 * p[0], 2 * p[1], 0.0]),
                np.diag([2.0, 2.0, 0.0]), 0.0, np.zeros(3), 0.0)


class MyEllipse(EllipseConstraint):
    """A subclass of a built-in constraint (it may override what it computes)."""


class Ramp(TimeFunction):
    """A user's time function: f = 0.1 t."""

    def value(self, t):
        return 0.1 * t

    def rate(self, t):
        return 0.1

    def acceleration(self, t):
        return 0.0


class MySine(Sine):
    """A subclass of a built-in time function."""


def push(t):
    """A drive given as a plain Python function, N m."""
    return 0.3


def _arm_with_drive(function):
    base = spatial_arm()
    model = Model(base.joints, base.links, base.frames, (Drive("q1", function),),
                  base.gravity, base.flexible_links, "arm_user_drive")
    validate_model(model)
    return model


NOT_COMPILABLE = {
    "point_constraint_subclass": (lambda: ProgrammedMotion(spatial_arm(), [Ring()]),
                                  "constraint 'ring' is a Ring,"),
    "builtin_constraint_subclass": (
        lambda: ProgrammedMotion(spatial_arm(), [MyEllipse(0.5, 0.3, name="e")]),
        "constraint 'e' is a MyEllipse,"),
    "time_function_subclass_in_programme": (
        lambda: ProgrammedMotion(spatial_arm(), [JointProgramme("q2", Ramp(), name="j")]),
        "the programme of constraint 'j' is a Ramp,"),
    "builtin_time_function_subclass_in_programme": (
        lambda: ProgrammedMotion(spatial_arm(), [CoordinateProgramme(MySine(0.0, 0.1, 1.0),
                                                                     name="pz")]),
        "the programme of constraint 'pz' is a MySine,"),
    "time_function_subclass_in_drive": (lambda: ProgrammedMotion(_arm_with_drive(Ramp())),
                                        "the drive on 'q1' is a Ramp,"),
    "plain_function_drive": (lambda: ProgrammedMotion(_arm_with_drive(push)),
                             "the drive on 'q1' is a function,"),
}


@pytest.mark.parametrize("name", list(NOT_COMPILABLE))
def test_user_classes_and_functions_keep_the_python_path(name):
    build, expected = NOT_COMPILABLE[name]
    system = build()
    cs, reason = compiled.for_system(system)
    assert cs is None
    assert reason.startswith(expected), reason
    assert "which the compiled kernels do not know" in reason
    # cached like a compiled form: asked again, the same answer without packing again
    assert compiled.for_system(system)[1] is reason


def test_compiled_form_is_cached_on_the_system_and_its_copies():
    system = crane_system(0)
    first = compiled.for_system(system)
    assert first[0] is not None and first[1] == ""
    assert compiled.for_system(system)[0] is first[0]
    # a copy with another partition shares the constraints, so the compiled form
    copy = system.with_dependent(("psi2", "z4"))
    assert compiled.for_system(copy)[0] is first[0]


def test_generated_code_is_written_under_the_kernel_cache(tmp_path, monkeypatch):
    """A SymPy system's generated module is written under GPME_KERNEL_CACHE (nothing is
    compiled here: numba compiles on the first call).  A second system with the same SymPy
    expressions uses the same module."""
    monkeypatch.setenv("GPME_KERNEL_CACHE", str(tmp_path))
    # an expression no other test uses, so its module is not already loaded
    expr = "z - 0.812345 - 0.1*sin(2.5*t)*x"
    system = ProgrammedMotion(spatial_arm(), [SympyPointConstraint(expr, name="s")])
    cs, reason = compiled.for_system(system)
    assert cs is not None, reason
    written = list(tmp_path.glob("gpme_kernels_*.py"))
    assert len(written) == 1
    assert cs.module.__file__ == str(written[0])
    source = written[0].read_text(encoding="utf-8")
    assert "def _user_point_0(x, y, z, t, out):" in source
    assert "0.812345" in source and "_user_point_1" not in source
    again = ProgrammedMotion(spatial_arm(), [SympyPointConstraint(expr, name="other_name")])
    assert compiled.for_system(again)[0].module is cs.module


def test_a_compiled_system_pickles_and_runs_the_same_after():
    """A system whose compiled form is cached on it pickles (a Dask worker receives it)
    without that cache, which holds a module; the unpickled system compiles again and runs
    the same steps (identical histories: same kernels, same arithmetic)."""
    import pickle
    from gpme_core.integrate import simulate
    system = crane_system(1)
    q0, q_dot0 = initial_state(system.model)
    first = simulate(system, 0.02, q0, q_dot0, output_dt=0.01)
    assert first.attrs["compiled"] and compiled.for_system(system)[0] is not None
    again = pickle.loads(pickle.dumps(system))
    second = simulate(again, 0.02, q0, q_dot0, output_dt=0.01)
    assert second.attrs["compiled"]
    assert np.array_equal(first.to_numpy(), second.to_numpy())

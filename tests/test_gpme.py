"""Reduced GPME form against the Lagrange-multiplier form; constraint rows against finite
differences; Baumgarte behaviour; partition choice; errors for unmeetable constraints."""
import numpy as np
import pytest
import sympy as sp

from gpme_core.constraints import (CoordinateProgramme, EllipseConstraint, JointProgramme,
                                   SympyPointConstraint)
from gpme_examples.crane import CraneParameters, crane_constraints, crane_system, initial_state
from gpme_core.errors import ConstraintError, ModelError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.integrate import simulate
from gpme_core.kinematics import chain_kinematics
from gpme_core.time_functions import Cosine, SympyTimeFunction

pytestmark = pytest.mark.both_computation_paths


@pytest.mark.parametrize("n_rfe", [0, 3])
def test_reduced_form_equals_lagrange_multiplier_form(n_rfe, rng):
    system = crane_system(n_rfe)
    model = system.model
    q0, _ = initial_state(model)
    for _ in range(10):
        t = rng.uniform(0, 10)
        q = q0 + rng.normal(0, 0.05, model.n_coordinates)
        qd = rng.normal(0, 1.0, model.n_coordinates)
        sol = system.solve(t, q, qd)
        qdd, lam = system.kkt_accelerations(t, q, qd)
        # both solve the same regular linear system; differences are round-off amplified
        # by its condition number (~1e4 here): 1e-9 relative leaves a margin of ~100
        np.testing.assert_allclose(sol.q_ddot, qdd, rtol=0, atol=1e-9 * np.abs(qdd).max())
        np.testing.assert_allclose(sol.multipliers, lam, rtol=0, atol=1e-9 * np.abs(lam).max())
        # the reactions are orthogonal to every admissible velocity (ideal constraints)
        gamma, _ = system.velocity_map(sol.jacobian)
        null = np.zeros((model.n_coordinates, len(system.ic)))
        null[system.ic] = np.eye(len(system.ic))
        null[system.dc] = gamma
        assert np.abs(null.T @ sol.reaction_forces).max() < 1e-9 * np.abs(sol.reaction_forces).max()


def test_constraint_rows_and_kappa_match_finite_differences_in_time(rng):
    system = crane_system(2)
    model = system.model
    n = model.n_coordinates
    q = initial_state(model)[0] + rng.normal(0, 0.1, n)
    qd, qdd = rng.normal(0, 1, n), rng.normal(0, 1, n)
    t0 = 0.7

    def phi(s):
        return system.constraints(t0 + s, q + qd * s + 0.5 * qdd * s * s, qd + qdd * s)[0]

    p0, pd0, a, kappa = system.constraints(t0, q, qd)
    h = 1e-4
    np.testing.assert_allclose(pd0, (phi(h) - phi(-h)) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(a @ qdd + kappa, (phi(h) - 2 * p0 + phi(-h)) / h ** 2, atol=2e-5)


def test_sympy_constraint_equals_builtin_ellipse_and_programme(rng):
    p = CraneParameters()
    x, y, z, t = sp.symbols("x y z t")
    user = [SympyPointConstraint((x / p.ellipse_a) ** 2 + (y / p.ellipse_b) ** 2 - 1, name="Phi_1"),
            SympyPointConstraint(z - (p.z0 + p.amplitude * sp.cos(2 * sp.pi * t / p.period)),
                                 name="Phi_2")]
    builtin = crane_system(1)
    mine = ProgrammedMotion(builtin.model, user, dependent=("psi3", "z4"))
    q0, _ = initial_state(builtin.model)
    for _ in range(5):
        tt = rng.uniform(0, 5)
        q = q0 + rng.normal(0, 0.1, len(q0))
        qd = rng.normal(0, 1, len(q0))
        for u, v in zip(builtin.constraints(tt, q, qd), mine.constraints(tt, q, qd)):
            np.testing.assert_allclose(u, v, rtol=1e-12, atol=1e-12)


def test_sympy_constraint_rejects_unknown_symbols():
    with pytest.raises(ModelError, match=r"uses \['w'\]"):
        SympyPointConstraint("x + w")


def test_joint_programme_drives_a_coordinate(arm):
    f = SympyTimeFunction("0.3*sin(2*t)")
    system = ProgrammedMotion(arm, [JointProgramme("q2", f)], dependent=["q2"])
    zero = np.zeros(arm.n_coordinates)
    df = simulate(system, 1.0, zero, zero, dt=2e-3, on_manifold=True)
    np.testing.assert_allclose(df["q2"], 0.3 * np.sin(2 * df["t"]), atol=1e-8)
    assert df["lambda_Phi_q2"].abs().max() > 0.1   # the programme needs a real torque


def test_baumgarte_pulls_off_manifold_start_onto_the_constraints():
    system = crane_system(0)
    q, qd = initial_state(system.model)
    df = simulate(system, 2.0, q, qd, dt=1e-3)
    start = df[["Phi_1", "Phi_2"]].abs().iloc[0]
    assert start["Phi_1"] > 0.5  # the paper's start: the end-effector outside the ellipse
    late = df[df.t > 1.5][["Phi_1", "Phi_2"]].abs().max()
    assert late.max() < 1e-8, late


def test_on_manifold_start_stays_on_manifold():
    system = crane_system(0)
    q, qd = initial_state(system.model)
    df = simulate(system, 2.0, q, qd, dt=1e-3, on_manifold=True)
    assert df[["Phi_1", "Phi_2"]].abs().max().max() < 1e-8


def test_automatic_partition_is_well_conditioned_and_gives_the_same_motion(rng):
    paper = crane_system(0)
    model = paper.model
    auto = ProgrammedMotion(model, crane_constraints())
    q, qd = initial_state(model)
    auto = auto.with_pivoted_dependent(0.0, q, qd)
    names = auto.dependent
    assert len(names) == 2 and len(set(names)) == 2
    a = auto.constraints(0.0, q, qd)[2]
    assert np.linalg.cond(a[:, auto.dc]) < 1e3
    # the solution of the reduced equations does not depend on the partition
    for _ in range(5):
        qq, qqd, t = q + rng.normal(0, 0.05, 4), rng.normal(0, 1, 4), rng.uniform(0, 5)
        np.testing.assert_allclose(auto.accelerations(t, qq, qqd), paper.accelerations(t, qq, qqd),
                                   rtol=0, atol=1e-10 * np.abs(paper.accelerations(t, qq, qqd)).max())


def test_singular_dependent_block_names_time_state_and_cause():
    model = crane_system(0).model
    # z1 (support) and psi2 cannot realise the ellipse when the end-effector is on the
    # column axis plane... use z1 for both rows: K_dc singular
    with pytest.raises(ModelError, match="need 2 distinct dependent coordinates"):
        ProgrammedMotion(model, crane_constraints(), dependent=("z1", "z1"))
    system = ProgrammedMotion(model, crane_constraints(), dependent=("z1", "psi2"))
    q, qd = initial_state(model)
    q[model.index("psi2")] = 0.0   # EE on the x axis: psi2 moves it tangentially, z1 vertically
    with pytest.raises(ConstraintError, match=r"at t = 0\.1 s the dependent block K_dc .*"
                                              r"\['z1', 'psi2'\].* singular"):
        system.solve(0.1, q, qd)


def test_unreachable_target_is_reported():
    params = CraneParameters(z0=5.0)   # 4.5 m above the pivot: beyond the slider's stroke
    system = crane_system(0, params)
    q, qd = initial_state(system.model)
    with pytest.raises(ConstraintError, match=r"z4 = .* m outside its range \[-0\.3, 0\.5\]"):
        system.consistent_state(0.0, q, qd)
    with pytest.raises(ConstraintError, match=r"at t = .* s the motion reaches z4 = .* outside its range"):
        simulate(system, 2.0, q, qd, dt=1e-3)


def test_bad_baumgarte_and_too_many_constraints():
    model = crane_system(0).model
    with pytest.raises(ModelError, match="Baumgarte parameters must be finite and >= 0"):
        ProgrammedMotion(model, crane_constraints(), baumgarte=(-1.0, 20.0))
    many = [JointProgramme(nm, Cosine(0, 0, 1)) for nm in model.coordinate_names] + \
        [EllipseConstraint(1, 1, name="extra")]
    with pytest.raises(ModelError, match="at most as many constraints as coordinates"):
        ProgrammedMotion(model, many)

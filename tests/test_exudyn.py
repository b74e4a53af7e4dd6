"""Exudyn as a reference engine (crosscheck/exudyn, docs/crosscheck-exudyn.md): the model as
Exudyn's kinematic tree against Pinocchio, the spring/damper and multiplier sign conventions
derived by hand, and short programmed runs of the crane against gpme inside the halving
gates (and a perturbed Exudyn side outside them)."""
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("exudyn")
pin = pytest.importorskip("pinocchio")

from crosscheck.exudyn import check as exu_check                      # noqa: E402
from crosscheck.exudyn.model import axis_rotation, mass_and_forces, tree_layout  # noqa: E402
from crosscheck.exudyn.runs import programmed_run, run_section         # noqa: E402
from crosscheck.pinocchio.model import from_gpme                       # noqa: E402
from gpme_core.constraints import JointProgramme, SympyPointConstraint  # noqa: E402
from gpme_core.errors import ConstraintError, ModelError, SimulationError  # noqa: E402
from gpme_core.gpme import ProgrammedMotion                            # noqa: E402
from gpme_core.inertia import RigidBodyInertia                         # noqa: E402
from gpme_core.model import ChainBuilder                               # noqa: E402
from gpme_core.time_functions import Constant                          # noqa: E402
from gpme_io.scenario import Scenario, crane_scenario                  # noqa: E402

EPS = np.finfo(float).eps


def _origin(rng):
    r, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if np.linalg.det(r) < 0:
        r[:, 0] *= -1.0
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = rng.normal(size=3) * 0.3
    return t


def unaligned_chain():
    """Six joints, four of them about/along axes that are not coordinate axes (one -z, one
    -x), random origins, inertias with off-diagonal terms, springs and dampers."""
    rng = np.random.default_rng(3)
    b = ChainBuilder("unaligned", gravity=(0.3, -1.0, -9.81))
    axes = [(0, 0, 1), (0, 1 / np.sqrt(2), 1 / np.sqrt(2)), (0, 0, -1), (0.6, 0, 0.8),
            (-1, 0, 0), (0.36, 0.48, 0.8)]
    kinds = ["revolute", "revolute", "prismatic", "prismatic", "revolute", "revolute"]
    for k, (axis, kind) in enumerate(zip(axes, kinds)):
        b.add_joint(f"j{k}", kind, axis, _origin(rng), stiffness=10.0 * k,
                    spring_reference=0.1 * k, damping=0.5 * k)
        r, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        b.add_body(RigidBodyInertia(1.0 + k, rng.normal(size=3) * 0.2,
                                    r @ np.diag(rng.uniform(0.1, 0.2, 3)) @ r.T))
    return b.build()


def pinocchio_terms(model, t, q, v):
    ps = from_gpme(model)
    data = ps.model.createData()
    m = np.array(pin.crba(ps.model, data, q))
    m = np.triu(m) + np.triu(m, 1).T
    f = ps.applied_forces(q, v, model.drive_forces(t)) - pin.rnea(ps.model, data, q, v,
                                                                   np.zeros_like(q))
    return m, f


@pytest.mark.parametrize("which", ["crane_flexible_n3", "unaligned"])
def test_kinematic_tree_matches_pinocchio(which):
    model = crane_scenario(3).model if which != "unaligned" else unaligned_chain()
    rng = np.random.default_rng(11)
    n = model.n_coordinates
    q, v, t = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), 2.0
    m_exu, f_exu = mass_and_forces(model, t, q, v)
    m_pin, f_pin = pinocchio_terms(model, t, q, v)
    # round-off of two recursions over <= 13 bodies; cond(M) <= 1e5 here, the free
    # accelerations below carry eps cond(M)
    assert np.abs(m_exu - m_pin).max() <= 1e-12 * np.abs(m_pin).max()
    assert np.abs(f_exu - f_pin).max() <= 1e-11 * np.abs(f_pin).max()
    cond = np.linalg.cond(m_pin)
    a_exu, a_pin = np.linalg.solve(m_exu, f_exu), pin.aba(from_gpme(model).model,
                                                          from_gpme(model).model.createData(),
                                                          q, v, from_gpme(model).applied_forces(
                                                              q, v, model.drive_forces(t)))
    assert np.abs(a_exu - a_pin).max() <= 8 * np.sqrt(n) * EPS * cond * np.abs(a_pin).max()
    if which == "unaligned":
        assert tree_layout(model).unaligned == ("j1", "j2", "j3", "j4", "j5")


def test_unaligned_axis_rotation_by_hand():
    # axis -z: half turn about x (R e_z = -e_z); a COM (1, 2, 3) in the gpme link frame is
    # R^T (1, 2, 3) = (1, -2, -3) in Exudyn's joint frame
    c, r = axis_rotation((0.0, 0.0, -1.0))
    assert c == 2
    assert np.allclose(r @ [0, 0, 1], [0, 0, -1], atol=1e-15)
    assert np.allclose(r.T @ [1.0, 2.0, 3.0], [1.0, -2.0, -3.0], atol=1e-15)
    c, r = axis_rotation((0.6, 0.0, 0.8))
    assert c == 2 and np.allclose(r @ [0, 0, 1], [0.6, 0, 0.8], atol=1e-15)
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-15)


def slider(stiffness=50.0, reference=0.1, damping=3.0, drive=7.0):
    b = ChainBuilder("slider", gravity=(0.0, 0.0, 0.0))
    b.add_joint("s", "prismatic", (0, 0, 1), stiffness=stiffness, spring_reference=reference,
                damping=damping)
    b.add_body(RigidBodyInertia(2.0))
    b.add_drive("s", Constant(drive))
    return b.build()


def test_spring_damper_and_drive_signs_by_hand():
    # f = -K (q - q_ref) - D q_dot + F = -50 (0.3 - 0.1) - 3 (0.2) + 7 = -3.6 N
    _, f = mass_and_forces(slider(), 0.0, np.array([0.3]), np.array([0.2]))
    assert f[0] == pytest.approx(-3.6, abs=1e-12)
    # static: f = 0 at q = q_ref + F / K = 0.24 m, at rest
    _, f = mass_and_forces(slider(), 0.0, np.array([0.24]), np.array([0.0]))
    assert abs(f[0]) <= 1e-12


def test_paper_eq7_damping_is_refused():
    from crosscheck.exudyn.model import add_tree
    import exudyn as exu
    mbs = exu.SystemContainer().AddSystem()
    with pytest.raises(ModelError, match="paper-eq7"):
        add_tree(mbs, slider(), [0.0], [0.0], damping_form="paper-eq7")


def pendulum_scenario(constraints, q0, q_dot0, mass=2.0, l_com=0.5):
    """A pendulum about z (gravity -y), COM at (l_com, 0, 0), frame "tip" at (1, 0, 0)."""
    b = ChainBuilder("pendulum", gravity=(0.0, -9.81, 0.0))
    b.add_joint("q", "revolute", (0, 0, 1))
    b.add_body(RigidBodyInertia(mass, (l_com, 0.0, 0.0), np.diag([0.01, 0.02, 0.02])))
    tip = np.eye(4)
    tip[0, 3] = 1.0
    b.add_frame("tip", tip)
    model = b.build()
    system = ProgrammedMotion(model, constraints)
    return Scenario(name="pendulum", model=model, constraints=tuple(constraints), system=system,
                    q0=q0, q_dot0=q_dot0, t_end=1.0, quick_t_end=0.1)


def test_multiplier_sign_on_a_held_pendulum():
    # held horizontal: gravity torque (r x F)_z = l (-m g) = -m g l; gpme's
    # M q_ddot = h + Q + A^T lambda with A = [1] and q_ddot = 0 gives lambda = +m g l
    sc = pendulum_scenario([JointProgramme("q", Constant(0.0), name="hold")], [0.0], [0.0])
    df = programmed_run(sc, 0.05, 1e-3)
    mgl = 2.0 * 9.81 * 0.5
    assert np.allclose(df["lambda_hold"], mgl, rtol=1e-10, atol=0)
    assert np.abs(df["q"]).max() <= 1e-12


def test_start_off_the_constraints_is_refused():
    sc = pendulum_scenario([JointProgramme("q", Constant(0.1), name="hold")], [0.0], [0.0])
    with pytest.raises(ConstraintError, match="not on the programmed constraints.*hold"):
        programmed_run(sc, 0.05, 1e-3)


def test_unreachable_programme_gives_a_clear_error():
    # the tip's y must follow 2 t m: reachable until y = 1 m (t = 0.5 s), then not
    sc = pendulum_scenario([SympyPointConstraint("y - 2*t", frame="tip", name="rise")],
                           [0.0], [2.0])
    with pytest.raises(SimulationError, match="Exudyn run of pendulum failed"):
        programmed_run(sc, 0.6, 1e-3)


@pytest.fixture(scope="module")
def rigid_crane():
    return replace(crane_scenario(0, on_constraints=True), quick_t_end=0.1)


@pytest.fixture(scope="module")
def rigid_rows(rigid_crane):
    return run_section(rigid_crane, quick=True)


def test_rigid_crane_run_agrees_with_gpme_inside_the_gates(rigid_rows):
    bad = [r["quantity"] for r in rigid_rows if r["status"] == "fail"]
    assert not bad
    compared = [r for r in rigid_rows if r["quantity"].startswith("exact programmed run ")
                and "order" not in r["quantity"]]
    assert len(compared) == 12             # 4 q, 4 q_dot, 2 Phi, 2 lambda
    assert all(r["status"] == "pass" for r in compared)


def test_exudyn_observed_order_is_two(rigid_rows):
    row = next(r for r in rigid_rows if "observed order of exudyn" in r["quantity"])
    assert row["status"] == "pass"
    assert abs(row["gpme_value"] - 2.0) <= 0.2


def test_perturbed_exudyn_side_fails_the_gates(rigid_crane):
    # the slider 2 % heavier on Exudyn's side only: the runs differ by more than both
    # integrators' errors (~1e-7 rad, m over 0.1 s)
    old = rigid_crane.model.links[-1].inertia
    heavier = rigid_crane.model.with_changes(link_inertias={
        "slider": RigidBodyInertia(1.02 * old.mass, old.com, old.inertia)})
    rows = run_section(rigid_crane, quick=True, model=heavier)
    failed = {r["quantity"] for r in rows if r["status"] == "fail"}
    assert "exact programmed run lambda_Phi_1" in failed
    assert "exact programmed run z1" in failed


def test_check_run_writes_rows_and_page(tmp_path, rigid_crane):
    df = exu_check.run(tmp_path, scenarios=[rigid_crane], quick=True, sections=("model",))
    assert set(df["section"]) == {"model"} and (df["status"] == "pass").all()
    page = (tmp_path / "exudyn.html").read_text()
    import exudyn
    assert f"Exudyn {exudyn.__version__}" in page
    assert (tmp_path / "checks" / "exudyn").is_dir()


def test_a_start_off_the_constraints_is_compared_from_its_projection(tmp_path):
    """The paper's own start is off the constraints: an index-3 run would project it in
    its first step, gpme's Baumgarte run would not, so both begin from its projection and
    an information row says so; the comparison then passes (measured 0.3 of the gates)."""
    off = replace(crane_scenario(0), quick_t_end=0.1)
    df = exu_check.run(tmp_path, scenarios=[off], quick=True, sections=("runs",))
    note = df[df["quantity"].str.contains("start projected")]
    assert len(note) == 1 and note["status"].iloc[0] == "info"
    assert "off the programmed constraints" in note["reason"].iloc[0]
    assert "Phi_1" in note["reason"].iloc[0]
    assert not (df["status"] == "fail").any(), df[df["status"] == "fail"][["quantity", "reason"]]


def test_check_run_turns_a_refused_run_into_a_failed_row(tmp_path, monkeypatch):
    # a start that cannot be projected onto the constraints: one failed row naming why
    from gpme_core.errors import ConstraintError
    from gpme_core.gpme import ProgrammedMotion

    def unreachable(self, t, q, q_dot, *args, **kwargs):
        raise ConstraintError("the constraints Phi_1 cannot be reached from this start")

    monkeypatch.setattr(ProgrammedMotion, "consistent_state", unreachable)
    off = replace(crane_scenario(0), quick_t_end=0.1)
    df = exu_check.run(tmp_path, scenarios=[off], quick=True, sections=("runs",))
    assert len(df) == 1 and df["status"].iloc[0] == "fail"
    assert "cannot be reached" in df["reason"].iloc[0]
    assert "Phi_1" in df["reason"].iloc[0]

@pytest.mark.parametrize("which", ["crane", "two_arms_rod"])
def test_position_level_callbacks_equal_the_full_evaluation(which):
    """Exudyn's index-3 callbacks take Phi and dPhi/dq from ProgrammedConstraints.
    position_terms (no frame velocities); they must be the very numbers evaluate gives
    (the same Pinocchio kinematics and SymPy expressions), and the Jacobian must be the
    derivative of Phi (central differences, truncation ~h^2 |Phi'''| and round-off
    ~eps |Phi| / h with h = 1e-6)."""
    from crosscheck.constraint_reference import with_reference_frames_of
    from crosscheck.exudyn.constraints import ProgrammedConstraints
    if which == "crane":
        sc = crane_scenario(3, on_constraints=True)
    else:
        from gpme_io.modelfile import load_model_file
        from pathlib import Path
        sc = load_model_file(Path(__file__).resolve().parents[1] / "examples" / "five_bar"
                             / "two_arms_rod.toml")
    sc = with_reference_frames_of(sc)
    pc = ProgrammedConstraints(sc.constraints, sc.model)
    rng = np.random.default_rng(11)
    for k in range(4):
        t = 0.37 * k
        q = np.asarray(sc.q0, float) + 0.05 * rng.normal(size=pc.n)
        v = rng.normal(size=pc.n)
        phi, _, a = pc.evaluate(t, q, v)
        phi_p, a_p = pc.position_terms(t, q)
        assert np.array_equal(phi, phi_p) and np.array_equal(a, a_p)
        assert pc.constraint_function(None, t, None, np.r_[q, 0, 0, 0], np.r_[v, 0, 0, 0],
                                      False) == phi.tolist()
        assert np.array_equal(pc.jacobian_function(None, t, None, np.r_[q, 0, 0, 0],
                                                   np.r_[v, 0, 0, 0], False), a)
        h = 1e-6
        fd = np.column_stack([(pc.position_terms(t, q + h * e)[0]
                               - pc.position_terms(t, q - h * e)[0]) / (2 * h)
                              for e in np.eye(pc.n)])
        assert np.allclose(fd, a, rtol=0, atol=1e-7 * max(1.0, np.abs(a).max())), \
            np.abs(fd - a).max()

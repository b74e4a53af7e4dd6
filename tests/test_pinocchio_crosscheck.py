"""The term-by-term Pinocchio crosscheck (crosscheck/pinocchio/check.py) on any Scenario:
a quick run on the crane and on a small non-crane arm, the original-URDF case on a URDF
tree with a frozen branch, the sampling rule, and proof that the harness fails the right
quantity when one engine is perturbed."""
import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

from crosscheck.pinocchio import check as pc
from crosscheck.pinocchio.model import from_gpme
from crosscheck.reports.rows import read_rows
from crosscheck.sampling import state_ranges
from crosscheck.states import FULL, QUICK, random_states, scenario_states, state_counts
from gpme_core.constraints import JointProgramme, SympyPointConstraint
from gpme_core.errors import ConstraintError, ModelFileError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import RigidBodyInertia, cuboid
from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder
from gpme_core.time_functions import Cosine, SympyTimeFunction
from gpme_examples.crane import CraneParameters, crane_constraints
from gpme_io.scenario import Scenario, ToleranceOverride, crane_scenario

DATA = Path(__file__).parent / "data" / "pinocchio"
PERTURBATION = 1e-6      # relative change of one inertia entry or one stiffness
ALL_QUANTITIES = set(pc.TOLERANCES) | set(pc.SOLVED)


def _h(rotation=np.eye(3), xyz=(0.0, 0.0, 0.0)):
    t = np.eye(4)
    t[:3, :3] = rotation
    t[:3, 3] = xyz
    return t


def _rpy(roll, pitch, yaw):
    """URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll) (fixed axes x, y, z), from SciPy."""
    return Rotation.from_euler("xyz", [roll, pitch, yaw]).as_matrix()


def small_scenario(name="small_arm", tolerances=None):
    """4 joints (revolute, prismatic, two revolute), a tool frame rotated and offset from
    its link, a SymPy sphere constraint on it whose centre (hence gradient) moves with
    time along the yaw axis, and a joint programme on the last joint; starts on the
    constraints."""
    b = ChainBuilder(name)
    b.add_joint("yaw", REVOLUTE, (0, 0, 1), stiffness=2.0, spring_reference=0.1, damping=0.05)
    b.add_body(cuboid(3.0, (0.3, 0.3, 0.2), com=(0.0, 0.02, 0.1)))
    b.add_drive("yaw", Cosine(0.5, 0.3, 2.0))
    b.add_joint("lift", PRISMATIC, np.array([0.0, 0.6, 0.8]), origin=_h(xyz=(0.1, 0.0, 0.2)),
                stiffness=2000.0, spring_reference=0.1, damping=20.0, limits=(-0.1, 0.3))
    b.add_body(cuboid(1.5, (0.1, 0.1, 0.5), com=(0.0, 0.0, 0.1)))
    b.add_joint("pitch", REVOLUTE, (0, 1, 0), origin=_h(_rpy(0.1, 0.0, 0.4), (0.0, 0.05, 0.4)),
                limits=(-1.5, 1.5))
    b.add_body(cuboid(1.0, (0.6, 0.08, 0.08), com=(0.3, 0.0, 0.0)))
    b.add_joint("roll", REVOLUTE, (1, 0, 0), origin=_h(xyz=(0.6, 0.0, 0.0)), stiffness=5.0)
    b.add_body(cuboid(0.4, (0.15, 0.1, 0.1), com=(0.05, 0.01, 0.0)))
    b.add_frame("tool", _h(_rpy(0.3, -0.5, 0.7), (0.12, 0.04, -0.03)))
    model = b.build()
    constraints = (SympyPointConstraint("x**2 + y**2 + (z - 0.05*sin(2*t))**2 - 0.935**2",
                                        frame="tool", name="Phi_sphere"),
                   JointProgramme("roll", SympyTimeFunction("0.2*sin(3*t)"), name="Phi_roll"))
    system = ProgrammedMotion(model, constraints, dependent=("pitch", "roll"),
                              baumgarte=(10.0, 10.0))
    q0, q_dot0 = system.consistent_state(0.0, np.array([0.0, 0.1, 0.3, 0.0]), np.zeros(4))
    return Scenario(name=name, model=model, constraints=constraints, system=system,
                    q0=q0, q_dot0=q_dot0, t_end=2.0, quick_t_end=0.5,
                    tolerances=tolerances or {}, on_constraints=True)


def branch_arm_model(finger=0.3):
    """tests/data/pinocchio/branch_arm.urdf built by hand as a gpme chain (shoulder,
    elbow, slide), the finger branch frozen at ``finger`` rad merged into link2."""
    b = ChainBuilder("branch_arm")
    b.add_joint("shoulder", REVOLUTE, (0, 0, 1), origin=_h(xyz=(0, 0, 0.1)), damping=0.2,
                link="link1")
    b.add_body(RigidBodyInertia(2.0, (0.01, 0.02, 0.15),
                                ((0.02, 0.001, 0.0), (0.001, 0.025, 0.002), (0.0, 0.002, 0.01))))
    b.add_joint("elbow", REVOLUTE, (0, 1, 0), origin=_h(_rpy(0.2, 0, 0), (0.05, 0, 0.3)),
                damping=0.3, limits=(-2, 2), link="link2")
    b.add_body(RigidBodyInertia(1.2, (0, 0, 0), ((0.002, 0, 0.0005), (0, 0.02, 0),
                                                 (0.0005, 0, 0.021))),
               origin=_h(_rpy(0, 0.1, 0), (0.2, 0, 0.01)))
    finger_frame = _h(xyz=(0.3, 0.05, 0)) @ _h(Rotation.from_rotvec([0, 0, finger]).as_matrix())
    b.add_body(RigidBodyInertia(0.3, (0, 0, 0), np.diag([1e-4, 3e-4, 3e-4])),
               origin=finger_frame @ _h(xyz=(0.04, 0, 0)))
    b.add_joint("slide", PRISMATIC, (1, 0, 0), origin=_h(_rpy(0, 0, 0.3), (0.4, 0, 0)),
                damping=1.0, limits=(-0.1, 0.2), link="link3", stiffness=500.0,
                spring_reference=0.05)     # the spring is the model's (a URDF has none)
    b.add_body(RigidBodyInertia(0.5, (0.05, 0, 0), np.diag([5e-4, 1e-3, 1e-3])))
    b.add_frame("tool", _h(_rpy(0.3, -0.2, 0.5), (0.1, 0.02, -0.03)))
    return b.build()


def branch_arm_scenario(frozen=None, built_finger=0.3):
    model = branch_arm_model(built_finger)
    constraints = (SympyPointConstraint("z - 0.5 - 0.05*sin(2*t)", frame="tool", name="Phi_z"),)
    system = ProgrammedMotion(model, constraints, dependent=("elbow",), baumgarte=(10.0, 10.0))
    q0, q_dot0 = system.consistent_state(0.0, np.array([0.0, 0.5, 0.05]), np.zeros(3))
    return Scenario(name="branch_arm", model=model, constraints=constraints, system=system,
                    q0=q0, q_dot0=q_dot0, t_end=1.0, on_constraints=True,
                    quick_t_end=0.2, urdf=DATA / "branch_arm.urdf", chain=("base", "tool"),
                    frozen={"finger": 0.3} if frozen is None else frozen)


# --------------------------------------------------------------------------- whole runs
@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    scenarios = [crane_scenario(1), small_scenario()]
    return out, pc.run(out, scenarios, quick=True, sections=("terms",))


def test_quick_run_passes_on_crane_and_small_arm_and_writes_reports(quick_run):
    out, df = quick_run
    bad = df[df["status"] != "pass"]
    assert bad.empty, bad[["model", "quantity", "case", "rel_error", "tol_rel"]].to_string()
    assert set(df["quantity"]) == ALL_QUANTITIES
    assert set(df["model"]) == {"crane_flexible_n1", "crane_flexible_n1 (URDF)", "small_arm",
                                "small_arm (URDF)"}
    assert (df.groupby("model")["case"].nunique() == QUICK.n_random + QUICK.n_run).all()
    assert (df["section"] == "terms").all()
    csv = read_rows(out, "pinocchio")
    assert len(csv) == len(df) and list(csv.columns) == list(df.columns)
    page = (out / "pinocchio.html").read_text()
    assert "all comparisons pass" in page and "Worst cases" in page and "Model cases" in page
    assert (out / "urdf" / "small_arm.urdf").exists()


def test_every_frame_and_constraint_is_compared(quick_run):
    _, df = quick_run
    small = df[df["model"] == "small_arm"]
    assert set(small.loc[small["quantity"] == "constraint kappa", "entry"]) <= \
        {"Phi_sphere", "Phi_roll"}
    # the tool frame's Jacobian rows are compared entry by entry (labels name them)
    assert small.loc[small["quantity"] == "frame jacobian", "entry"].str.startswith("[tool.").all()


def test_loose_tolerances_only_for_solves_and_explained(quick_run):
    _, df = quick_run
    loose = df[df["tol_rel"] > 1e-9]
    assert set(loose["quantity"]) <= set(pc.SOLVED)
    assert loose["reason"].str.contains("cond").all()
    assert (df["reason"].str.len() > 20).all()


def test_unknown_section_is_rejected(tmp_path):
    with pytest.raises(ValueError, match="unknown sections"):
        pc.run(tmp_path, [small_scenario()], quick=True, sections=("term",))


# --------------------------------------------------------------------------- states
def test_states_within_limits_and_rfem_ranges():
    s = crane_scenario(1)
    model = s.model
    lo, hi, rate = state_ranges(model, s.flexible_coordinates, s.q0)
    flex = [model.index(c) for c in s.flexible_coordinates]
    assert len(flex) == 3 and np.allclose(hi[flex] - lo[flex], 0.04) and np.all(rate[flex] == 2.0)
    psi3 = model.index("psi3")
    assert (lo[psi3], hi[psi3]) == (model.lower_limits[psi3], model.upper_limits[psi3])
    psi2, z1 = model.index("psi2"), model.index("z1")        # no limits: +-pi, +-0.2 m
    assert hi[psi2] - lo[psi2] == pytest.approx(2 * np.pi) and hi[z1] - lo[z1] == pytest.approx(0.4)
    states = random_states(s.system, 20, np.random.default_rng(3), s.t_end,
                           s.flexible_coordinates, s.q0)
    q = np.array([st.q for st in states])
    assert np.all(q >= lo) and np.all(q <= hi)
    assert np.all(q >= model.lower_limits) and np.all(q <= model.upper_limits)
    assert all(0.0 <= st.t <= s.t_end for st in states)


def test_unsolvable_scenario_stops_after_bounded_draws():
    s = small_scenario()
    system = ProgrammedMotion(s.model, s.constraints[1:], dependent=("yaw",))   # A_dc = 0
    with pytest.raises(ConstraintError, match=r"only 0 of 3 random states .* after 11 draws"):
        random_states(system, 3, np.random.default_rng(1), 1.0, max_draws=11)


def test_state_counts_shrink_for_large_models():
    assert state_counts(FULL, 34) == (300, 100)
    assert state_counts(FULL, 68) == (75, 25)
    assert state_counts(FULL, 500) == (30, 10)
    assert state_counts(QUICK, 500) == (3, 2)


# --------------------------------------------------------------------------- original URDF
def test_original_urdf_with_frozen_branch_compares_at_round_off(tmp_path):
    s = branch_arm_scenario()
    cases = pc.model_cases(s, tmp_path)
    assert [c.kind for c in cases] == ["direct", "URDF", "original URDF"]
    orig = cases[2]
    assert dict(orig.pin.locked) == {"finger": 0.3}
    assert orig.pin.model.nq == 4 and orig.pin.model.nv == 3      # continuous shoulder: cos, sin
    assert list(orig.pin.continuous) == [True, False, False]
    states = scenario_states(s, QUICK)
    df = pc.compare_case(orig, states)
    bad = df[df["status"] != "pass"]
    assert bad.empty, bad[["quantity", "case", "rel_error", "tol_rel"]].to_string()
    assert set(df["quantity"]) == ALL_QUANTITIES
    assert df.loc[df["quantity"] == "M", "rel_error"].max() < 1e-14


def test_original_urdf_locked_elsewhere_fails_mass_terms(tmp_path):
    """gpme merged the finger at 0.3 rad, Pinocchio locks it at 0 (frozen not given):
    the mass matrix and gravity must differ; the kinematics of the chain must not."""
    s = branch_arm_scenario(frozen={})
    case = pc.original_urdf_case(s)
    df = pc.compare_case(case, random_states(s.system, 3, np.random.default_rng(5), 1.0))
    failed = set(df.loc[df["status"] == "fail", "quantity"])
    assert {"M", "g"} <= failed
    assert not failed & {"pose position", "pose rotation", "frame position", "frame jacobian"}


def test_original_urdf_rejects_a_frozen_chain_joint():
    s = branch_arm_scenario(frozen={"elbow": 0.1, "nope": 0.0})
    with pytest.raises(ModelFileError,
                       match=r"(?s)\['elbow'\] are both frozen.*\['nope'\] are not joints"):
        pc.original_urdf_case(s)


# --------------------------------------------------------------------------- perturbations
def _states(scenario, count=3, seed=7):
    return random_states(scenario.system, count, np.random.default_rng(seed), scenario.t_end,
                         scenario.flexible_coordinates, scenario.q0)


def _failed(case, states):
    df = pc.compare_case(case, states)
    return df, set(df.loc[df["status"] == "fail", "quantity"])


@pytest.fixture(scope="module")
def small():
    s = small_scenario()
    return s, pc.direct_case(s), _states(s)


def test_unperturbed_small_arm_passes(small):
    _, case, states = small
    assert not _failed(case, states)[1]


def test_link_mass_changed_in_pinocchio_only_fails_mass_terms(small):
    _, case, states = small
    pm = case.pin.model.copy()
    k = case.system.model.index("pitch") + 1
    old = pm.inertias[k]
    pm.inertias[k] = pin.Inertia(old.mass * (1 + PERTURBATION), old.lever, old.inertia)
    df, failed = _failed(dataclasses.replace(case, pin=dataclasses.replace(case.pin, model=pm)),
                         states)
    assert {"M", "g"} <= failed
    assert not failed & {"pose position", "pose rotation", "frame position", "frame velocity",
                         "frame jacobian", "frame drift", "Phi", "Phi_dot",
                         "constraint jacobian A", "constraint kappa", "applied tau"}


def test_joint_axis_sign_flipped_in_pinocchio_only_fails_kinematics(small):
    s, case, states = small
    flipped = s.model.with_changes(joint_changes={"pitch": {"axis": (0.0, -1.0, 0.0)}})
    df, failed = _failed(dataclasses.replace(case, pin=from_gpme(flipped)), states)
    assert {"pose rotation", "frame position", "frame jacobian", "M", "Phi"} <= failed
    rot = df[(df["quantity"] == "pose rotation") & (df["status"] == "fail")]
    assert set(rot["entry"].str.split(",").str[0]) <= {"[pitch", "[roll", "[tool"}


def test_frame_offset_changed_in_pinocchio_only_fails_frame_and_constraint(small):
    _, case, states = small
    pm = case.pin.model.copy()
    fid = case.pin.frames["tool"]
    placement = pm.frames[fid].placement.copy()
    placement.translation = placement.translation + np.array([0.0, 0.0, 1e-6])
    pm.frames[fid].placement = placement
    df, failed = _failed(dataclasses.replace(case, pin=dataclasses.replace(case.pin, model=pm)),
                         states)
    assert {"frame position", "pose position", "Phi"} <= failed
    assert not failed & {"M", "g", "h", "applied tau", "free q_ddot"}
    phi = df[(df["quantity"] == "Phi") & (df["status"] == "fail")]
    assert set(phi["entry"]) == {"Phi_sphere"}                   # not the joint programme


def test_inertia_perturbed_in_gpme_only_is_reported():
    s = crane_scenario(1)
    case = pc.direct_case(s)
    states = _states(s)
    column = next(lk for lk in s.model.links if lk.name == "column").inertia
    i = column.inertia_array.copy()
    i[2, 2] *= 1.0 + PERTURBATION
    model = s.model.with_changes(
        link_inertias={"column": RigidBodyInertia(column.mass, column.com, i)})
    p = CraneParameters()
    system = ProgrammedMotion(model, crane_constraints(p), dependent=("psi3", "z4"),
                              baumgarte=(p.baumgarte_alpha, p.baumgarte_beta))
    df, failed = _failed(dataclasses.replace(case, system=system), states)
    assert "M" in failed
    m_rows = df[df["quantity"] == "M"]
    assert (m_rows["status"] == "fail").all() and set(m_rows["entry"]) == {"[psi2, psi2]"}


def test_tolerance_override_from_the_model_file_is_applied(small):
    loose = ToleranceOverride("pinocchio/M", 1.0, 0.0, "test: a deliberately loose gate")
    s = small_scenario(tolerances={"pinocchio/M": loose})
    df = pc.compare_case(pc.direct_case(s), small[2][:1])
    m = df[df["quantity"] == "M"].iloc[0]
    assert (m["tol_abs"], m["tol_rel"]) == (1.0, 0.0) and m["reason"].startswith("model file: ")
    bad = small_scenario(tolerances={"pinocchio/mass": loose})
    with pytest.raises(KeyError, match="'pinocchio/mass' names no compared quantity"):
        pc.direct_case(bad)


# --------------------------------------------------------------------------- crba
def test_upper_triangle_crba_is_mirrored_not_misreported(monkeypatch, small):
    """Older Pinocchio filled only the upper triangle of crba; the harness checks which."""
    _, case, states = small
    real = pin.crba
    monkeypatch.setattr(pc.pin, "crba", lambda m, d, q: np.triu(real(m, d, q)))
    df = pc.compare_case(case, states[:1])
    assert (df.loc[df["quantity"] == "M", "status"] == "pass").all()
    m, whole = pc._crba(case.pin.model, case.pin.model.createData(), states[0].q)
    assert not whole and np.array_equal(m, m.T)


def test_this_pinocchio_fills_the_whole_mass_matrix(small):
    _, case, states = small
    raw = np.array(pin.crba(case.pin.model, case.pin.model.createData(), states[0].q))
    assert np.array_equal(raw, raw.T), "pin.crba no longer returns the whole matrix"


def test_scenario_without_constraints_compares_the_free_terms():
    s = small_scenario()
    free = dataclasses.replace(s, name="small_free", constraints=(),
                               system=ProgrammedMotion(s.model))
    df = pc.compare_case(pc.direct_case(free), _states(free, 2))
    assert (df["status"] == "pass").all()
    assert set(df["quantity"]) == ALL_QUANTITIES - set(pc.CONSTRAINT_QUANTITIES)

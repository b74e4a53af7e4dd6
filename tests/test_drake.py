"""The Drake crosscheck (crosscheck/drake/): terms of a MultibodyPlant read from gpme's URDF
against gpme's terms, sign conventions against hand-derived values, free runs with Drake's
own integrator, and proof that the check fails when one side is perturbed."""
import dataclasses
import json

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("pydrake")

from crosscheck.drake import check as dc                      # noqa: E402
from crosscheck.drake import runs as dr                       # noqa: E402
from crosscheck.drake.model import from_urdf                  # noqa: E402
from crosscheck.reports.rows import read_rows                 # noqa: E402
from crosscheck.states import QUICK, State, scenario_states   # noqa: E402
from gpme_core.errors import ModelFileError                   # noqa: E402
from gpme_core.gpme import ProgrammedMotion                   # noqa: E402
from gpme_core.inertia import RigidBodyInertia, cuboid        # noqa: E402
from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder  # noqa: E402
from gpme_core.time_functions import Cosine                   # noqa: E402
from gpme_io.scenario import Scenario, ToleranceOverride, crane_scenario   # noqa: E402
from gpme_io.urdf import side_file_path, write_urdf           # noqa: E402

PERTURBATION = 1e-6      # relative change of one mass or one stiffness
G = 9.81


def _h(rotation=np.eye(3), xyz=(0.0, 0.0, 0.0)):
    t = np.eye(4)
    t[:3, :3] = rotation
    t[:3, 3] = xyz
    return t


def _rot(axis, angle):
    from scipy.spatial.transform import Rotation
    return Rotation.from_rotvec(np.asarray(axis, float) * angle).as_matrix()


def small_model(name="drake_arm"):
    """4 joints (revolute z, prismatic on an unaligned axis, revolute y, revolute x) with
    springs, dampers, a drive, rotated joint origins, offset centres of mass and a tool frame
    rotated and offset from its link."""
    b = ChainBuilder(name)
    b.add_joint("yaw", REVOLUTE, (0, 0, 1), stiffness=2.0, spring_reference=0.1, damping=0.05)
    b.add_body(cuboid(3.0, (0.3, 0.3, 0.2), com=(0.0, 0.02, 0.1)))
    b.add_drive("yaw", Cosine(0.5, 0.3, 2.0))
    b.add_joint("lift", PRISMATIC, np.array([0.0, 0.6, 0.8]), origin=_h(xyz=(0.1, 0.0, 0.2)),
                stiffness=2000.0, spring_reference=0.1, damping=20.0, limits=(-0.1, 0.3))
    b.add_body(cuboid(1.5, (0.1, 0.1, 0.5), com=(0.0, 0.0, 0.1)))
    b.add_joint("pitch", REVOLUTE, (0, 1, 0), origin=_h(_rot((1, 0, 0), 0.3), (0.0, 0.05, 0.4)),
                limits=(-1.5, 1.5), damping=0.3)
    b.add_body(cuboid(1.0, (0.6, 0.08, 0.08), com=(0.3, 0.0, 0.0)))
    b.add_joint("roll", REVOLUTE, (1, 0, 0), origin=_h(xyz=(0.6, 0.0, 0.0)), stiffness=5.0)
    b.add_body(RigidBodyInertia(0.4, (0.05, 0.01, 0.0), ((2e-3, 1e-4, 0), (1e-4, 3e-3, 2e-4),
                                                         (0, 2e-4, 2.5e-3))))
    b.add_frame("tool", _h(_rot((0.3, -0.5, 0.7), 1.0), (0.12, 0.04, -0.03)))
    return b.build()


def small_scenario(dt=None, quick_t_end=0.2, tolerances=None):
    model = small_model()
    return Scenario(name=model.name, model=model, constraints=(),
                    system=ProgrammedMotion(model), q0=np.array([0.0, 0.1, 0.3, 0.0]),
                    q_dot0=np.array([0.5, 0.0, -0.2, 1.0]), t_end=1.0,
                    quick_t_end=quick_t_end, dt=dt, tolerances=tolerances or {})


def random_states(model, count, seed=7):
    rng = np.random.default_rng(seed)
    lo = np.maximum(model.lower_limits, -np.pi)
    hi = np.minimum(model.upper_limits, np.pi)
    return [State(f"s{k}", float(rng.uniform(0, 2)), rng.uniform(lo, hi),
                  rng.uniform(-1, 1, model.n_coordinates)) for k in range(count)]


def _failing(df):
    return set(df.loc[df["status"] == "fail", "quantity"])


@pytest.fixture(scope="module")
def crane1():
    return crane_scenario(1)


# --------------------------------------------------------------------------- terms
def test_terms_agree_on_a_small_arm(tmp_path):
    scenario = small_scenario()
    case = dc.make_case(scenario, tmp_path)
    df = dc.compare_case(case, random_states(scenario.model, 6))
    assert set(df["quantity"]) == set(dc.QUANTITIES)
    assert not _failing(df), df[df["status"] == "fail"].to_string()
    assert (df["status"] == "pass").all()            # every row gated, none information
    # the springs, dampers and drives are really there (not compared as zeros)
    for quantity in ("spring forces", "damper forces", "gravity tau_g", "bias term C(q,v) v"):
        assert df.loc[df["quantity"] == quantity, "scale"].min() > 1e-3, quantity


def test_terms_agree_on_the_crane_with_one_rfem_segment(tmp_path, crane1):
    case = dc.make_case(crane1, tmp_path)
    df = dc.compare_case(case, scenario_states(crane1, QUICK))
    assert not _failing(df), df[df["status"] == "fail"].to_string()
    # cond(M) of the RFEM crane loosens the solve tolerance above the round-off floor
    assert df.loc[df["quantity"] == "free q_ddot", "tol_rel"].max() > 1e-12


def test_a_perturbed_drake_mass_fails_the_inertial_terms_only(tmp_path, crane1):
    case = dc.make_case(crane1, tmp_path)
    slider = case.drake.bodies["slider"]
    slider.SetMass(case.context, slider.default_mass() * (1 + PERTURBATION))
    df = dc.compare_case(case, scenario_states(crane1, QUICK))
    assert {"M", "gravity tau_g", "free q_ddot", "inverse dynamics tau"} <= _failing(df)
    assert not _failing(df) & {"pose position", "pose rotation", "frame position",
                               "frame jacobian", "spring forces", "damper forces"}


def test_a_perturbed_spring_in_the_side_file_fails_the_spring_forces(tmp_path):
    scenario = small_scenario()
    model = scenario.model
    path = tmp_path / "arm.urdf"
    write_urdf(model, path)
    side = json.loads(side_file_path(path).read_text())
    side["joints"]["lift"]["stiffness"] *= 1 + PERTURBATION
    side_file_path(path).write_text(json.dumps(side))
    ds = from_urdf(path, model.coordinate_names, [lk.name for lk in model.links] +
                   list(model.frames), expected_damping=model.damping)
    df = dc.compare_case(dc.make_case(scenario, tmp_path, ds), random_states(model, 4))
    assert "spring forces" in _failing(df)
    bad = df[(df["quantity"] == "spring forces") & (df["status"] == "fail")]
    assert set(bad["entry"]) == {"lift"}
    assert not _failing(df) & {"M", "gravity tau_g", "bias term C(q,v) v", "damper forces"}


def test_damping_drake_did_not_read_is_a_clear_error(tmp_path):
    model = small_model()
    path = tmp_path / "arm.urdf"
    write_urdf(model, path)
    text = path.read_text().replace('damping="20.0"', 'damping="21.0"')
    path.write_text(text)
    with pytest.raises(ModelFileError, match="lift: Drake read 21.0, gpme has 20.0"):
        from_urdf(path, model.coordinate_names, [], expected_damping=model.damping)
    # without the check, the damper rows catch it
    ds = from_urdf(path, model.coordinate_names, [lk.name for lk in model.links] +
                   list(model.frames))
    scenario = small_scenario()
    df = dc.compare_case(dc.make_case(scenario, tmp_path, ds), random_states(model, 3))
    assert "damper forces" in _failing(df)


# --------------------------------------------------------------------------- signs
def _pendulum():
    """A revolute joint about y carrying a point-like mass of 2 kg at x = 0.5 m, with a
    spring (3 N m/rad, reference 0.1 rad) and a damper (0.7 N m s/rad)."""
    b = ChainBuilder("sign_test")
    b.add_joint("swing", REVOLUTE, (0, 1, 0), stiffness=3.0, spring_reference=0.1,
                damping=0.7)
    b.add_body(RigidBodyInertia(2.0, (0.5, 0.0, 0.0), np.diag([1e-6, 1e-6, 1e-6])))
    return b.build()


def test_sign_of_gravity_spring_and_damper(tmp_path):
    """Pendulum: mass m = 2 kg at x = L = 0.5 m of a link turning about y, gravity -z.
    At q = 0 gravity's torque about +y is r x F = (L, 0, 0) x (0, 0, -m g) = +m g L; the
    spring gives -k (q - q_ref), the damper -c q_dot: generalized forces on the right-hand
    side in Drake and -(g), -(f), -(d) in gpme."""
    model = _pendulum()
    case = dc.make_case(Scenario(name="sign_test", model=model, constraints=(),
                                 system=ProgrammedMotion(model), q0=np.zeros(1),
                                 q_dot0=np.zeros(1), t_end=1.0, quick_t_end=0.1), tmp_path)
    d = dc.drake_terms(case.drake, case.context, 0.0, np.zeros(1), np.array([0.4]),
                       np.zeros(1))
    m, length, k, q_ref, c = 2.0, 0.5, 3.0, 0.1, 0.7
    assert d["tau_g"][0] == pytest.approx(m * G * length, rel=1e-12)
    assert d["springs"][0] == pytest.approx(-k * (0.0 - q_ref), rel=1e-12)
    assert d["dampers"][0] == pytest.approx(-c * 0.4, rel=1e-12)
    terms = case.system.solve(0.0, np.zeros(1), np.array([0.4])).terms
    assert -terms.g[0] == pytest.approx(m * G * length, rel=1e-12)
    assert -terms.f[0] == pytest.approx(k * q_ref, rel=1e-12)
    assert -terms.d[0] == pytest.approx(-c * 0.4, rel=1e-12)
    rows = dc.compare_state(case, State("q = 0", 0.0, np.zeros(1), np.array([0.4])))
    assert all(r["status"] == "pass" for r in rows)


def test_sign_of_the_bias_term(tmp_path):
    """A turntable (revolute z, negligible inertia) carrying a slider (prismatic x) with a
    point-like mass m at r: Drake's bias C v is [2 m r r_dot w, -m r w^2] (Coriolis torque,
    centripetal force on the left-hand side); gpme's h is its negative."""
    b = ChainBuilder("turntable")
    b.add_joint("turn", REVOLUTE, (0, 0, 1))
    b.add_body(RigidBodyInertia(1e-3, (0.0, 0.0, 0.0), np.diag([1e-6, 1e-6, 1e-6])))
    b.add_joint("slide", PRISMATIC, (1, 0, 0))
    b.add_body(RigidBodyInertia(1.5, (0.0, 0.0, 0.0), np.diag([1e-9, 1e-9, 1e-9])))
    model = b.build()
    case = dc.make_case(Scenario(name="turntable", model=model, constraints=(),
                                 system=ProgrammedMotion(model), q0=np.zeros(2),
                                 q_dot0=np.zeros(2), t_end=1.0, quick_t_end=0.1), tmp_path)
    m, r, r_dot, w = 1.5, 0.3, 0.2, 2.0
    q, qd = np.array([0.7, r]), np.array([w, r_dot])
    d = dc.drake_terms(case.drake, case.context, 0.0, q, qd, np.zeros(2))
    np.testing.assert_allclose(d["bias"], [2 * m * r * r_dot * w, -m * r * w ** 2], rtol=1e-12)
    h = case.system.solve(0.0, q, qd).terms.h
    np.testing.assert_allclose(-h, [2 * m * r * r_dot * w, -m * r * w ** 2], rtol=1e-12)


# --------------------------------------------------------------------------- model errors
def test_urdf_drake_cannot_hold_as_n_coordinates_is_a_clear_error(tmp_path):
    model = small_model()
    path = tmp_path / "arm.urdf"
    write_urdf(model, path)
    text = path.read_text()
    floating = text.replace('<joint name="roll" type="revolute">',
                            '<joint name="roll" type="floating">')
    bad = tmp_path / "floating.urdf"
    bad.write_text(floating)
    side_file_path(path).replace(side_file_path(bad))
    with pytest.raises(ModelFileError) as err:
        from_urdf(bad, model.coordinate_names, ["tool"])
    message = str(err.value)
    assert "Drake left link 'roll' free (a floating base: nq 7, nv 6)" in message
    assert "Drake has no joints ['roll']" in message
    assert "Joint 'roll' specified as type floating" in message     # Drake's own warning
    with pytest.raises(ModelFileError, match=r"Drake has no joints \['elbow'\]"):
        from_urdf(bad, list(model.coordinate_names[:3]) + ["elbow"], [], side_file=None)
    with pytest.raises(ModelFileError, match=r"no bodies \(URDF links\) \['gripper'\]"):
        from_urdf(path, model.coordinate_names, ["gripper"], side_file=None)
    broken = tmp_path / "broken.urdf"
    broken.write_text(text.replace("</robot>", ""))
    with pytest.raises(ModelFileError, match="Drake's URDF parser cannot read"):
        from_urdf(broken, model.coordinate_names, [], side_file=None)


def test_a_root_that_is_not_world_is_welded_not_floated(tmp_path):
    model = small_model()
    path = tmp_path / "arm.urdf"
    write_urdf(model, path)
    moved = tmp_path / "rooted.urdf"
    moved.write_text(path.read_text().replace('"world"', '"base_link"').replace(
        '<joint name="roll" type="revolute">', '<joint name="roll" type="continuous">'))
    ds = from_urdf(moved, model.coordinate_names, ["tool"], side_file=side_file_path(path))
    assert ds.welded_root == "base_link"
    assert ds.plant.num_positions() == ds.plant.num_velocities() == 4   # continuous: nq = 1


# --------------------------------------------------------------------------- overrides
def test_model_file_overrides_and_unknown_quantities():
    over = small_scenario(tolerances={"drake/M": ToleranceOverride("drake/M", 1e-9, 0.0,
                                                                   "looser")})
    assert dc.overrides(over)["M"].abs == 1e-9
    assert dc.overrides(over)["M"].reason == "model file: looser"
    wrong = small_scenario(tolerances={"drake/mass matrix": ToleranceOverride(
        "drake/mass matrix", 1.0, 0.0, "x")})
    with pytest.raises(KeyError, match="names no compared quantity"):
        dc.overrides(wrong)


# --------------------------------------------------------------------------- free runs
def test_free_run_rows_pass_and_orders_are_observed(tmp_path):
    """0.2 s of the small arm at dt = 4 ms (springs of ~10 rad/s: truncation well above
    round-off): the finest runs agree within both engines' halving estimates and each
    engine's order is the one of its scheme."""
    scenario = small_scenario(dt=4e-3, quick_t_end=0.2)
    rows = pd.DataFrame(dr.run_section(scenario, quick=True, urdf_dir=tmp_path))
    columns = dr.state_columns(scenario.model)
    assert len(rows) == len(columns) + 2
    assert (rows["status"] == "pass").all(), rows[rows["status"] != "pass"].to_string()
    orders = rows[rows["quantity"].str.contains("observed order")]
    gpme = orders[orders["quantity"].str.contains("RK4")].iloc[0]
    drake = orders[orders["quantity"].str.contains("Runge-Kutta 5")].iloc[0]
    assert abs(gpme["gpme_value"] - 4.0) <= 1.0
    assert abs(drake["gpme_value"] - 5.0) <= 1.0
    # Drake's run is really its own: it differs from gpme's by more than round-off
    run_rows = rows[~rows["quantity"].str.contains("observed order")]
    assert run_rows["abs_error"].max() > 1e-12


def test_a_free_run_leaving_a_joint_range_is_shortened_or_reported(tmp_path):
    """pitch starts at 0.3 rad, 20 rad/s towards its limit 1.5 rad: gpme stops the run at
    ~0.067 s, so the free run is compared over 0.05 s; at 200 rad/s not even that runs,
    which is one information row."""
    fast = dataclasses.replace(small_scenario(dt=4e-3), q_dot0=np.array([0.5, 0.0, 20.0, 1.0]))
    rows = pd.DataFrame(dr.run_section(fast, quick=True, urdf_dir=tmp_path))
    assert (rows["status"] == "pass").all()
    assert "0.05 s (shortened from 0.2 s" in rows["case"].iloc[0]
    assert "pitch = 1.5" in rows["case"].iloc[0]
    faster = dataclasses.replace(fast, q_dot0=np.array([0.5, 0.0, 200.0, 1.0]))
    rows = dr.run_section(faster, quick=True, urdf_dir=tmp_path)
    assert len(rows) == 1 and rows[0]["status"] == "info"
    assert "cannot be run for 0.05 s" in rows[0]["reason"]


def test_a_perturbed_drake_run_fails(tmp_path):
    scenario = small_scenario(dt=4e-3)
    model = scenario.model
    from crosscheck import halving_gates, run_gates
    refined = run_gates.refined_gpme_runs(scenario.system, scenario.q0, scenario.q_dot0, 0.2,
                                          4e-3, dr.OUTPUT_DT)
    path = tmp_path / "heavier.urdf"
    write_urdf(model, path)
    text = path.read_text()
    assert text.count('<mass value="0.4" />') == 1                # the last link
    path.write_text(text.replace('<mass value="0.4" />',
                                 f'<mass value="{0.4 * (1 + PERTURBATION)!r}" />'))
    bodies = [lk.name for lk in model.links] + list(model.frames)
    runs = [dr.drake_free_run(scenario, 0.2, refined.dt / k, dr.OUTPUT_DT, tmp_path,
                              drake_system=from_urdf(path, model.coordinate_names, bodies))
            for k in (1, 2, 4)]
    drake = halving_gates.HalvedRuns("drake", dr.SCHEME_TEXT, dr.SCHEME_ORDER, tuple(runs),
                                     refined.dt)
    rows = pd.DataFrame(halving_gates.run_rows("drake", scenario,
                                               halving_gates.from_refined(refined), drake,
                                               dr.state_columns(model), dr.FREE, "perturbed"))
    assert _failing(rows) and all(q.startswith("free run ") and "order" not in q
                                  for q in _failing(rows))


# --------------------------------------------------------------------------- whole run
def test_run_writes_rows_and_page(tmp_path):
    scenario = small_scenario(dt=4e-3, quick_t_end=0.1)
    df = dc.run(tmp_path, [scenario], quick=True)
    assert set(df["section"]) == {"terms", "runs"}
    assert not _failing(df)
    back = read_rows(tmp_path, "drake")
    # Drake's own rows; gpme's observed-order row of the runs it made is gpme's check
    assert len(back) == (df["engine"] == "drake").sum()
    assert set(df["engine"]) == {"drake", "gpme"}
    page = (tmp_path / "drake.html").read_text()
    assert "gpme vs Drake" in page and dc.drake_version() in page


# --------------------------------------------------------------------------- drives
def _drive_values(model, tmp_path, times):
    """(times, nv) Drake's drive port of ``model`` evaluated at ``times`` (s), and the
    DrakeSystem (its velocity order)."""
    from pydrake.systems.framework import DiagramBuilder
    from crosscheck.drake.drives import drive_output
    from crosscheck.drake.model import for_model
    ds = for_model(model, tmp_path, model.name)
    builder = DiagramBuilder()
    builder.ExportOutput(drive_output(builder, model, ds), "drives")
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    out = []
    for t in times:
        context.SetTime(float(t))
        out.append(np.array(diagram.get_output_port(0).Eval(context)))
    return np.array(out), ds, diagram


@pytest.mark.parametrize("extra", [None, "constant"])
def test_drake_drive_sources_equal_the_models_drive_forces(tmp_path, extra):
    """The crane's quintic ramp (and a constant added on another joint) as Drake's own
    TrajectorySource / ConstantVectorSource: the model's t(t) in Drake's velocity order,
    before, during and after the ramp, to round-off of a degree-5 polynomial in t."""
    from gpme_core.model import Drive, Model
    from gpme_core.time_functions import Constant
    m = crane_scenario(1).model
    drives = m.drives + ((Drive(m.coordinate_names[-1], Constant(-3.5)),) if extra else ())
    model = Model(m.joints, m.links, m.frames, drives, m.gravity, m.flexible_links, m.name,
                  m.geometry, m.point_springs)
    times = np.array([-0.5, 0.0, 0.37, 1.9, 2.5, 4.999, 5.0, 7.3])
    values, ds, diagram = _drive_values(model, tmp_path, times)
    assert not any(type(s).__name__ == "PythonDrives" for s in diagram.GetSystems())
    expected = np.array([ds.to_drake(model.drive_forces(t)) for t in times])
    np.testing.assert_allclose(values, expected, rtol=0, atol=16 * np.finfo(float).eps)


def test_a_drive_drake_has_no_source_for_keeps_the_python_system(tmp_path):
    """A cosine drive (the small arm's) goes through the LeafSystem that calls the model's
    drive_forces: the same values, every evaluation in Python."""
    model = small_model()
    times = np.array([0.0, 0.4, 1.3])
    values, ds, diagram = _drive_values(model, tmp_path, times)
    assert any(type(s).__name__ == "PythonDrives" for s in diagram.GetSystems())
    expected = np.array([ds.to_drake(model.drive_forces(t)) for t in times])
    np.testing.assert_array_equal(values, expected)

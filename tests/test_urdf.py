"""URDF writer and reader (gpme_io/urdf_writer.py, urdf_reader.py, side_file.py, re-exported
by gpme_io/urdf.py) and the committed files in models/urdf/."""
import shutil
import subprocess
import textwrap

import numpy as np
import pinocchio as pin
import pytest

from crosscheck import generate_models
from gpme_io.urdf import (MUJOCO_BOUND, UNLIMITED, load_side_file, load_urdf, read_urdf,
                          side_file_path, write_urdf)
from gpme_examples.crane import CraneParameters, build_crane
from gpme_core.dynamics import gravity_forces, mass_matrix, velocity_product_terms
from gpme_core.errors import ModelError, ModelFileError
from gpme_core.model import REVOLUTE

COMMITTED = sorted(generate_models.URDF_DIR.glob("*.urdf"))
# Relative tolerance of dynamics terms after a round trip: the only change is the
# pseudo-inertia -> (m, c, I_C) conversion in ChainBuilder.build (one rounding of
# m c c^T against I_C), measured 0 to 1e-16; 1e-13 leaves room for other platforms.
ROUND_TRIP_REL = 1e-13


def _terms(model, rng):
    q = rng.uniform(-1.0, 1.0, model.n_coordinates)
    qd = rng.uniform(-1.0, 1.0, model.n_coordinates)
    return q, qd, (mass_matrix(model, q), gravity_forces(model, q),
                   velocity_product_terms(model, q, qd))


def _assert_same_dynamics(a, b, rng):
    q, qd, terms_a = _terms(a, rng)
    terms_b = (mass_matrix(b, q), gravity_forces(b, q), velocity_product_terms(b, q, qd))
    for name, x, y in zip(("M", "g", "h"), terms_a, terms_b):
        assert np.max(np.abs(x - y)) <= ROUND_TRIP_REL * np.max(np.abs(x)), name


@pytest.mark.parametrize("n_rfe", [0, 1, 3], ids=["rigid", "n1", "n3"])
def test_crane_round_trip_is_exact(tmp_path, n_rfe, rng):
    model = build_crane(n_rfe)
    path, side = write_urdf(model, tmp_path / f"{model.name}.urdf")
    assert side == tmp_path / f"{model.name}.gpme.json"
    back = read_urdf(path)
    assert back.name == model.name and back.coordinate_names == model.coordinate_names
    for a, b in zip(model.joints, back.joints):
        for field in a.__dict__:
            assert np.array_equal(np.asarray(getattr(a, field)), np.asarray(getattr(b, field))), \
                (a.name, field)
    assert [lk.name for lk in back.links] == [lk.name for lk in model.links]
    assert [lk.inertia is None for lk in back.links] == [lk.inertia is None for lk in model.links]
    assert np.array_equal(back.gravity, model.gravity)
    assert back.frames.keys() == model.frames.keys()
    assert back.frames["E"].link_index == model.frames["E"].link_index
    assert np.array_equal(back.frames["E"].transform, model.frames["E"].transform)
    assert [(d.joint, d.function) for d in back.drives] == [(d.joint, d.function)
                                                           for d in model.drives]
    assert back.flexible_links == model.flexible_links
    _assert_same_dynamics(model, back, rng)


def test_skewed_arm_round_trip(tmp_path, arm, rng):
    """Unaligned axes, rotated origins, springs with references, a frame off the origin."""
    path, _ = write_urdf(arm, tmp_path / "arm.urdf")
    back = read_urdf(path)
    assert np.array_equal(back.stiffness, arm.stiffness)
    assert np.array_equal(back.spring_reference, arm.spring_reference)
    assert np.array_equal(back.damping, arm.damping)
    # rpy text: one rounding of the rotation -> rpy -> rotation conversion
    assert np.max(np.abs(back.origins - arm.origins)) < 1e-15
    assert np.allclose(back.frames["E"].transform, arm.frames["E"].transform, rtol=0, atol=1e-15)
    _assert_same_dynamics(arm, back, rng)


def test_rigid_urdf_made_flexible_on_reading_equals_rfem_crane(rng):
    p = CraneParameters()
    made = read_urdf(generate_models.URDF_DIR / "crane_rigid.urdf",
                     flexible={"arm": (p.beam(), 3)})
    built = build_crane(3)
    assert made.coordinate_names == built.coordinate_names
    assert np.array_equal(made.stiffness, built.stiffness)
    assert np.array_equal(made.damping, built.damping)
    assert made.flexible_links[0].n_segments == 3
    _assert_same_dynamics(built, made, rng)


def test_committed_files_match_the_generator():
    files = generate_models.generate_urdf(generate_models.URDF_DIR)
    problems = generate_models.check_files(generate_models.URDF_DIR, files)
    assert not problems, ("models/urdf drifted from the generator; run "
                          "`python -m crosscheck.generate_models urdf`:\n" + "\n".join(problems))
    assert {p.name for p in COMMITTED} == {n for n in files if n.endswith(".urdf")}


def test_check_mode_reports_drift(tmp_path, capsys):
    assert generate_models.main(["urdf", "--out", str(tmp_path)]) == 0
    assert generate_models.main(["urdf", "--check", "--out", str(tmp_path)]) == 0
    victim = tmp_path / "crane_rigid.urdf"
    victim.write_text(victim.read_text().replace('value="5.0"', 'value="5.000001"'))
    assert generate_models.main(["urdf", "--check", "--out", str(tmp_path)]) == 1
    assert "crane_rigid.urdf: differs from the generator" in capsys.readouterr().err


@pytest.mark.parametrize("path", COMMITTED, ids=[p.stem for p in COMMITTED])
def test_check_urdf_accepts_committed_file(path):
    exe = shutil.which("check_urdf")
    if exe is None:
        pytest.skip("check_urdf not installed (Debian package liburdfdom-tools)")
    res = subprocess.run([exe, str(path)], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "Successfully Parsed XML" in res.stdout


@pytest.mark.parametrize("path", COMMITTED, ids=[p.stem for p in COMMITTED])
def test_committed_file_loads_in_pinocchio(path):
    model = read_urdf(path)
    pm = pin.buildModelFromUrdf(str(path))
    assert pm.nq == pm.nv == model.n_coordinates
    assert list(pm.names)[1:] == list(model.coordinate_names)
    assert np.array_equal(pm.damping, model.damping)
    masses = [pm.inertias[k + 1].mass for k in range(model.n_coordinates)]
    assert masses == [0.0 if lk.inertia is None else lk.inertia.mass for lk in model.links]
    assert pm.existFrame("E")


@pytest.mark.parametrize("path", COMMITTED, ids=[p.stem for p in COMMITTED])
def test_committed_file_loads_in_mujoco_urdf_importer(path):
    mujoco = pytest.importorskip("mujoco")
    model = read_urdf(path)
    mj = mujoco.MjModel.from_xml_path(str(path))
    assert mj.nq == mj.nv == model.n_coordinates
    assert [mj.joint(k).name for k in range(mj.njnt)] == list(model.coordinate_names)
    assert np.array_equal(mj.dof_damping, model.damping)
    masses = {mj.body(k).name: mj.body_mass[k] for k in range(mj.nbody)}
    for lk in model.links:      # massless links get MuJoCo's lower bound (MuJoCo only)
        want = MUJOCO_BOUND if lk.inertia is None else lk.inertia.mass
        assert masses[lk.name] == pytest.approx(want, rel=1e-12)
    assert "E" in masses, "fusestatic=false keeps the end-effector body"


# ------------------------------------------------------------------ foreign URDFs
ROBOT = """<?xml version="1.0"?>
<robot name="two_link">
  <link name="world"/>
  <joint name="to_base" type="fixed"><parent link="world"/><child link="base"/>
    <origin xyz="0 0 0.1"/></joint>
  <link name="base"><inertial><mass value="9"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="shoulder" type="{shoulder_type}"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.2" rpy="0.1 0 0"/><axis xyz="0 0 2"/>
    <limit lower="-2" upper="2" effort="10" velocity="3"/><dynamics damping="0.3"/></joint>
  <link name="upper"><inertial><origin xyz="0.1 0 0" rpy="0 0.2 0"/><mass value="2"/>
    <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <joint name="upper_to_motor" type="fixed"><parent link="upper"/><child link="motor"/>
    <origin xyz="0.3 0 0" rpy="0 0 0.5"/></joint>
  <link name="motor"><inertial><mass value="0.5"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <joint name="upper_to_camera" type="fixed"><parent link="upper"/><child link="camera"/>
    <origin xyz="0.05 0.02 0"/></joint>
  <link name="camera"/>
  <joint name="elbow" type="revolute"><parent link="motor"/><child link="fore"/>
    <origin xyz="0.05 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="3"/></joint>
  <link name="fore"><inertial><origin xyz="0.2 0 0"/><mass value="1"/>
    <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="tool" type="fixed"><parent link="fore"/><child link="tip"/>
    <origin xyz="0.4 0 0"/></joint>
  <link name="tip"/>
</robot>
"""


def _write(tmp_path, text, name="robot.urdf"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_foreign_urdf_matches_pinocchio_reading_of_it(tmp_path, rng):
    """Fixed joints merged (motor), frames kept (camera, tip), world-fixed base dropped;
    M, g and h agree with Pinocchio's own reading of the same file."""
    path = _write(tmp_path, ROBOT.format(shoulder_type="revolute"))
    model = read_urdf(path)
    assert model.coordinate_names == ("shoulder", "elbow")
    assert set(model.frames) == {"motor", "camera", "tip"}
    assert model.total_mass == pytest.approx(3.5, rel=1e-15)
    assert model.joints[0].limits == (-2.0, 2.0) and model.joints[0].damping == 0.3
    pm = pin.buildModelFromUrdf(str(path))
    data = pm.createData()
    pm.gravity = pin.Motion(model.gravity, np.zeros(3))
    for _ in range(5):
        q, qd = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
        g_pin = pin.computeGeneralizedGravity(pm, data, q)
        # round-off of the merged inertias: 1e-13 relative
        assert np.allclose(mass_matrix(model, q), pin.crba(pm, data, q), rtol=0, atol=1e-13)
        assert np.allclose(gravity_forces(model, q), g_pin, rtol=0, atol=1e-13)
        assert np.allclose(velocity_product_terms(model, q, qd),
                           g_pin - pin.rnea(pm, data, q, qd, np.zeros(2)), rtol=0, atol=1e-13)
        pin.framesForwardKinematics(pm, data, q)
        from gpme_core.kinematics import chain_kinematics
        kin = chain_kinematics(model, q)
        fr = model.frames["tip"]
        assert np.allclose(kin.T[fr.link_index] @ fr.transform,
                           data.oMf[pm.getFrameId("tip")].homogeneous, rtol=0, atol=1e-14)


def test_continuous_joint_is_an_unlimited_revolute(tmp_path):
    model = read_urdf(_write(tmp_path, ROBOT.format(shoulder_type="continuous")))
    assert model.joints[0].kind == REVOLUTE
    assert model.joints[0].limits == (-np.inf, np.inf)


def test_unbounded_limits_written_as_unlimited_read_back_as_inf(tmp_path):
    model = build_crane(0)
    path, _ = write_urdf(model, tmp_path / "c.urdf")
    assert f'lower="{-UNLIMITED!r}"' in path.read_text()
    assert read_urdf(path).joints[1].limits == (-np.inf, np.inf)


def test_make_a_foreign_link_flexible(tmp_path):
    p = CraneParameters()
    beam = p.beam()
    model = read_urdf(_write(tmp_path, ROBOT.format(shoulder_type="revolute")),
                      flexible={"upper": (beam, 2)})
    assert model.coordinate_names[:4] == ("shoulder", "psi_upper_1", "theta_upper_1", "phi_upper_1")
    assert model.coordinate_names[-1] == "elbow"
    # at zero deflection the tip frame is where the rigid file puts it, moved by L - 0.3 m?
    # no: things hanging on the link keep their rigid placement
    rigid = read_urdf(tmp_path / "robot.urdf")
    from gpme_core.kinematics import chain_kinematics
    q_r = np.array([0.3, -0.2])
    q_f = np.zeros(model.n_coordinates)
    q_f[0], q_f[-1] = q_r
    t_r = chain_kinematics(rigid, q_r).T
    t_f = chain_kinematics(model, q_f).T
    for name in ("tip", "camera", "motor"):
        a, b = rigid.frames[name], model.frames[name]
        assert np.allclose(t_r[a.link_index] @ a.transform, t_f[b.link_index] @ b.transform,
                           rtol=0, atol=1e-15), name
    # the link's own inertial is replaced by the beam; the motor stays
    assert model.total_mass == pytest.approx(3.5 - 2.0 + beam.mass, rel=1e-14)


# ------------------------------------------------------------------ errors
BAD = """<?xml version="1.0"?>
<robot name="bad">
  <link name="world"/>
  <joint name="free" type="floating"><parent link="world"/><child link="a"/></joint>
  <link name="a"><inertial><mass value="1"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="slide" type="screw"><parent link="a"/><child link="b"/></joint>
  <link name="b"/>
  <joint name="copy" type="revolute"><parent link="a"/><child link="c"/>
    <axis xyz="0 0 0"/><limit lower="1" upper="-1"/>
    <origin xyz="1 two 3"/></joint>
  <link name="c"><inertial><mass value="-1"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="lost" type="revolute"><parent link="nowhere"/><child link="d"/></joint>
  <link name="d"/>
</robot>
"""


def test_every_malformed_element_is_named_in_one_error(tmp_path):
    with pytest.raises(ModelFileError) as exc:
        read_urdf(_write(tmp_path, BAD))
    msg = str(exc.value)
    for expected in ("joint 'slide': unknown type 'screw'; URDF types: revolute, continuous, "
                     "prismatic, fixed, floating, planar",
                     "joint 'copy': <limit lower=1.0 upper=-1.0> must have lower <= upper",
                     "joint 'copy': <axis xyz> must not be zero",
                     "joint 'copy' <origin xyz>: expected 3 finite numbers, got '1 two 3'",
                     "link 'c' <inertial>: mass must be positive and finite, got -1.0 kg",
                     "joint 'lost': parent link 'nowhere' is not a <link> of the file",
                     "exactly one root link (a link that is no joint's child), found "
                     "['world', 'b', 'd']"):
        assert expected in msg
    assert len(exc.value.problems) == 7
    assert str(tmp_path / "robot.urdf") in exc.value.problems[0]


def _chain_with(extra):
    return ("""<?xml version="1.0"?><robot name="r"><link name="world"/>
      <joint name="j1" type="revolute"><parent link="world"/><child link="a"/>
        <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <link name="a"><inertial><mass value="1"/>
        <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>"""
            + extra + "</robot>")


def test_branches_of_moving_joints_need_a_chain_choice(tmp_path):
    extra = "".join(f"""<joint name="{j}" type="prismatic"><parent link="a"/><child link="{c}"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        <link name="{c}"><inertial><mass value="1"/>
        <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>"""
                    for j, c in (("left", "l"), ("right", "r")))
    path = _write(tmp_path, _chain_with(extra))
    with pytest.raises(ModelFileError, match=r"the moving joints below link 'world' lie on 2 "
                                             r"branches ending at links \['l', 'r'\]: choose "
                                             r"one with chain=\('world', <tip link>\)"):
        read_urdf(path)
    model = read_urdf(path, chain=("world", "r"))
    assert model.coordinate_names == ("j1", "right") and "l" in model.frames


def test_moving_link_without_inertial_is_accepted_and_noted_unless_declared(tmp_path):
    """A massless chain link is fine when M stays positive definite (here j2 moves b)."""
    extra = """<joint name="j2" type="revolute"><parent link="a"/><child link="hollow"/>
        <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        <link name="hollow"/>
        <joint name="j3" type="revolute"><parent link="hollow"/><child link="b"/>
        <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        <link name="b"><inertial><origin xyz="0.5 0 0"/><mass value="1"/>
        <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>"""
    path = _write(tmp_path, _chain_with(extra))
    res = load_urdf(path)
    assert res.model.links[1].inertia is None
    assert "chain links without mass (accepted: the mass matrix is checked positive " \
           "definite): hollow" in res.notes
    res = load_urdf(path, massless_links=["hollow"])
    assert not any("without mass" in n for n in res.notes)


def test_malformed_xml_and_side_file(tmp_path):
    with pytest.raises(ModelFileError, match="not well-formed XML"):
        read_urdf(_write(tmp_path, "<robot><link name='a'></robot>"))
    path, side = write_urdf(build_crane(0), tmp_path / "c.urdf")
    side.write_text(side.read_text().replace('"psi2"', '"psi9"').replace('"version": 1',
                                                                         '"version": 7'))
    with pytest.raises(ModelFileError) as exc:
        read_urdf(path)
    assert "expected format 'gpme-urdf-side-file' version 1, got" in str(exc.value)
    side.write_text(side.read_text().replace('"version": 7', '"version": 1'))
    with pytest.raises(ModelFileError, match=r"springs for joints \['psi9'\] that are not"):
        read_urdf(path)
    read_urdf(path, side_file=None)       # the URDF alone is still readable


def test_flexible_request_problems(tmp_path):
    path = generate_models.URDF_DIR / "crane_flexible_n1.urdf"
    beam = CraneParameters().beam()
    with pytest.raises(ModelFileError) as exc:
        read_urdf(path, flexible={"arm": (beam, 2), "E": (beam, 1), "slider": "beam"})
    msg = str(exc.value)
    assert "flexible link 'arm': already RFEM-discretised with 1 segments" in msg
    assert "flexible link 'E': not a link moved by a joint" in msg
    assert "flexible link 'slider': expected a FlexibleLink or (BeamProperties, " \
           "n_segments), got 'beam'" in msg
    assert len(exc.value.problems) == 3


def test_writer_rejects_name_clash_and_unstorable_drive(tmp_path):
    from gpme_core.model import ChainBuilder
    from gpme_core.inertia import cuboid
    b = ChainBuilder("clash")
    b.add_joint("q", REVOLUTE, (0, 0, 1), link="arm")
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_frame("arm", np.diag([1.0, 1.0, 1.0, 1.0]) + np.eye(4, k=3) * 0.1)
    # a frame off its link's origin is written as a link of its own name
    b.add_drive("q", lambda t: 1.0)
    model = b.build()
    with pytest.raises(ModelFileError) as exc:
        write_urdf(model, tmp_path / "x.urdf")
    assert "URDF link names would repeat: ['arm']" in str(exc.value)
    assert "drive on 'q'" in str(exc.value) and "include_drives=False" in str(exc.value)
    # the URDF's root link "world" cannot be a model link: the model refuses the name
    b = ChainBuilder("clash")
    b.add_joint("q", REVOLUTE, (0, 0, 1), link="world")
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    with pytest.raises(ModelError, match="'world': the name is reserved for the world"):
        b.build()


def test_side_file_is_beside_and_validated(tmp_path):
    path, side = write_urdf(build_crane(1), tmp_path / "crane.urdf")
    assert side_file_path(path) == side
    data = load_side_file(side)
    assert data["joints"]["z1"] == {"stiffness": 1e4, "spring_reference": 0.0}
    assert data["massless_links"] == ["arm_sde1_psi", "arm_sde1_theta"]


def test_cycle_detached_from_the_root_is_named(tmp_path):
    extra = """<link name="p"/><link name="r"/>
        <joint name="pr" type="fixed"><parent link="p"/><child link="r"/></joint>
        <joint name="rp" type="fixed"><parent link="r"/><child link="p"/></joint>"""
    with pytest.raises(ModelFileError, match=r"links \['p', 'r'\] are not connected to the "
                                             r"root link 'world'"):
        read_urdf(_write(tmp_path, _chain_with(extra)))

"""MJCF export: committed files load and match the generator, the export reproduces gpme's
terms, export errors list every problem, the auxiliary mechanism's geometry is right, and
the programmed MJCF alone (plus the drive torque) reproduces gpme's programmed motion."""
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest

from crosscheck.mujoco import generate_mjcf as gen
from crosscheck.mujoco import mechanism as mech
from crosscheck.mujoco import mjcf as mjcf_module
from crosscheck.mujoco.mjcf import _quat, mjcf_text
from crosscheck.mujoco.sim import chain_map, drive_callback, equality_violations
from crosscheck.mujoco.terms import sample_states, term_rows
from gpme_core import transforms as tf
from gpme_core.constraints import CoordinateProgramme, EllipseConstraint, JointProgramme
from gpme_examples.crane import CraneParameters, build_crane, crane_constraints, crane_system, \
    initial_state
from gpme_core.errors import ModelError
from gpme_core.inertia import cuboid
from gpme_core.integrate import simulate
from gpme_core.model import REVOLUTE, ChainBuilder
from gpme_core.time_functions import Constant, Cosine

FILES = sorted(gen.mjcf_documents())


@pytest.mark.parametrize("name", FILES)
def test_committed_file_loads_in_mujoco(name):
    m = mujoco.MjModel.from_xml_path(str(gen.DEFAULT_DIR / name))
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    assert m.nkey == 1


def test_committed_files_match_the_generator():
    assert gen.drift() == []


def test_drift_check_reports_an_edited_file(tmp_path):
    gen.generate_mjcf(tmp_path)
    path = tmp_path / "crane_rigid.xml"
    path.write_text(path.read_text().replace('stiffness="10000.0"', 'stiffness="10001.0"'))
    (tmp_path / "stray.xml").write_text("<mujoco/>")
    problems = gen.drift(tmp_path)
    assert len(problems) == 2
    assert "crane_rigid.xml: differs from the generator" in problems[0]
    assert "stray.xml: not produced by the generator" in problems[1]
    assert gen.main(["--check", "--out", str(tmp_path)]) == 1


def test_drift_check_reports_a_file_that_is_not_utf8(tmp_path, capsys):
    gen.generate_mjcf(tmp_path)
    path = tmp_path / "crane_rigid.xml"
    path.write_bytes(path.read_bytes().replace(b"crane_rigid", b"crane_\xff", 1))
    assert gen.drift(tmp_path) == [f"{path}: differs from the generator from line 1"]
    assert gen.main(["--check", "--out", str(tmp_path)]) == 1
    assert "crane_rigid.xml: differs" in capsys.readouterr().out


def test_generate_into_an_unusable_directory_is_one_error_line(tmp_path, capsys):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    assert gen.main(["--out", str(a_file / "sub")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: cannot write the MJCF files to {a_file / 'sub'}: ")
    assert "Traceback" not in err and err.count("\n") == 1


def test_quaternion_of_rotations(rng):
    # includes rotations by ~pi, where Shepperd's method must switch branches
    for angle in (0.0, 0.3, np.pi - 1e-9, np.pi):
        for axis in np.eye(3).tolist() + [rng.normal(size=3)]:
            axis = np.asarray(axis) / np.linalg.norm(axis)
            r = tf.rotation_about_axis(axis, angle)
            back = np.zeros(9)
            mujoco.mju_quat2Mat(back, _quat(r))
            # 1e-15: one rotation built and converted twice, eps-level entries
            assert np.abs(back.reshape(3, 3) - r).max() < 1e-15 * 10


def test_export_of_a_skewed_arm_matches_gpme_terms(arm):
    """Skewed axes, rotated origins, off-centre masses: every term at round-off."""
    mj = mujoco.MjModel.from_xml_string(mjcf_text(arm))
    rows = term_rows(arm, mj, sample_states(arm, 4, seed=7))
    bad = [(r["quantity"], r["abs_error"], r["tol_abs"]) for r in rows if not r["passed"]]
    assert not bad


def test_a_changed_stiffness_in_mujoco_only_is_reported():
    model = build_crane(1)
    stiffer = model.with_changes(joint_changes={"psi_arm_1": {"stiffness": model.stiffness[3] * 1.001}})
    mj = mujoco.MjModel.from_xml_string(mjcf_text(stiffer))
    rows = term_rows(model, mj, sample_states(model, 2, seed=3))
    failed = {r["quantity"] for r in rows if not r["passed"]}
    assert failed == {"passive -(f + d) vs qfrc_passive [N, N m]"}
    assert all(r["entry"] == "psi_arm_1" for r in rows if not r["passed"])


def test_export_lists_every_problem():
    b = ChainBuilder("bad")
    b.add_joint("a", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_joint("b", REVOLUTE, (0, 1, 0), origin=tf.translation(0.1, 0, 0))   # massless link
    b.add_joint("c", REVOLUTE, (1, 0, 0), origin=tf.translation(0.2, 0, 0))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_frame("E")
    model = b.build()
    specs = [EllipseConstraint(1.0, 2.0, frame="F"), JointProgramme("a", Constant(0.0))]
    with pytest.raises(ModelError) as err:
        mjcf_text(model, dt=-1.0, constraints=specs)
    msg = str(err.value)
    for part in ("dt must be positive", "need exactly one CoordinateProgramme",
                 "type JointProgramme has no MuJoCo mechanism", "no frame 'F'"):
        assert part in msg


def test_a_massless_link_gets_a_bounded_body_and_the_terms_still_match():
    """A massless link that cannot share a body (its next joint is offset) is exported with
    MASS_BOUND and INERTIA_BOUND; gpme's M, bias and passive forces still match MuJoCo's."""
    from crosscheck.mujoco.mjcf import MASS_BOUND
    b = ChainBuilder("massless_middle")
    b.add_joint("a", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_joint("b", REVOLUTE, (0, 1, 0), origin=tf.translation(0.1, 0, 0))   # massless link
    b.add_joint("c", REVOLUTE, (1, 0, 0), origin=tf.translation(0.2, 0, 0))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1), com=(0.05, 0.0, 0.0)))
    model = b.build()
    text = mjcf_text(model, dt=1e-3)
    assert f'mass="{MASS_BOUND!r}"' in text and "massless link" in text
    mj = mujoco.MjModel.from_xml_string(text)
    rows = term_rows(model, mj, sample_states(model, 3, 11))
    assert all(r["status"] == "pass" for r in rows), [r for r in rows if r["status"] != "pass"]


def test_height_programme_must_be_a_cosine_on_z():
    model = build_crane(0)
    specs = [EllipseConstraint(0.3, 0.6), CoordinateProgramme(Constant(1.0), axis=0)]
    with pytest.raises(ModelError, match="axis must be 2.*\n.*function must be a Cosine"):
        mjcf_text(model, constraints=specs)


def _programmed(name):
    m = mujoco.MjModel.from_xml_path(str(gen.DEFAULT_DIR / name))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    return m, d


def test_mechanism_geometry_at_the_keyframe():
    p = CraneParameters()
    m, d = _programmed("crane_rigid_programmed.xml")
    tendon = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, "aux_ellipse_string")
    eq = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_EQUALITY, "Phi_1")
    # the tendon equality holds length0 + polycoef[0] = 2 max(a, b); 1e-12 m: sums of 3
    # distances of order 1 m
    assert abs(m.tendon_length0[tendon] + m.eq_data[eq, 0] - 2 * max(p.ellipse_a, p.ellipse_b)) < 1e-12
    # keyframe on the manifold: every auxiliary constraint satisfied to the keyframe's
    # 12 significant digits (1e-11 m)
    viol = equality_violations(m, d)
    assert set(viol) == {"aux_scotch_yoke", "Phi_2", "Phi_1"}
    assert max(abs(v) for v in viol.values()) < 1e-11
    e = d.site_xpos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "E")]
    assert abs((e[0] / p.ellipse_a) ** 2 + (e[1] / p.ellipse_b) ** 2 - 1) < 1e-10
    assert abs(e[2] - (p.z0 + p.amplitude)) < 1e-11


def test_programmed_mjcf_alone_reproduces_gpme():
    """Keyframe + drive torque only, 0.3 s: MuJoCo follows gpme's programmed motion."""
    system = crane_system(0)
    model = system.model
    q0, qd0 = system.consistent_state(0.0, *initial_state(model))
    g = simulate(system, 0.3, q0, qd0, dt=1e-4, output_dt=0.3)
    m, d = _programmed("crane_rigid_programmed.xml")
    cmap = chain_map(m, model)
    mujoco.set_mjcb_control(drive_callback(model, m))
    try:
        mujoco.mj_step(m, d, nstep=3000)
    finally:
        mujoco.set_mjcb_control(None)
    q_mj = d.qpos[cmap.qpos]
    q_g = g[list(model.coordinate_names)].to_numpy()[-1]
    # 1e-7: MuJoCo's soft equality lags by Phi ~ tc^2 e (crosscheck.mujoco.cases), with
    # tc = 1e-4 s and e <= |Jdot q_dot| ~ v^2 / r <= (1 m/s)^2 / 0.1 m = 10 m/s^2 over
    # 0.3 s: 1e-7 m, and the arm's lever (~1 m) carries it to the coordinates at O(1)
    # (measured 1.2e-8 rad at 0.2 s); a wrong mechanism (a lagging height, a missing
    # ellipse) is off by > 1e-3
    assert np.abs(q_mj - q_g).max() < 1e-7
    # and the auxiliary crank still turns at 2 pi / T (1e-9 rad/s: armature 1e12 kg m^2)
    crank = m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, mech.CRANK)]
    assert abs(d.qvel[crank] - 2 * np.pi / CraneParameters().period) < 1e-9


def test_tendon_length_formula():
    prog = mech.read_programme(build_crane(0), crane_constraints())
    c = prog.focal_distance
    assert c == pytest.approx(np.sqrt(0.75 ** 2 - 0.375 ** 2), rel=1e-15)
    for t in np.linspace(0, 2 * np.pi, 7):
        p_e = np.array([0.375 * np.cos(t), 0.75 * np.sin(t), 1.2])
        assert mech.string_length_at(prog, p_e, 1.2) == pytest.approx(1.5, abs=1e-14)


# --- names and values written through ElementTree -----------------------------------------
# Every name a user can give reaches MuJoCo unchanged: markup characters (escaped by
# ElementTree), whitespace, any Unicode plane, text that would close a comment or a CDATA
# section.  Keys: model, links (2), joints (2), frame, constraints (2).
NAME_SETS = {
    "markup": dict(model='m&<"x\'>', links=('a<b&"c\'', "</body>"), joints=('j<&>"\'', "&amp;"),
                   frame='E"<>&\'', constraints=('Phi<1>', 'Phi&"2"')),
    "unicode": dict(model="кран", links=("звено λ", "関節リンク"), joints=("ψ₂", "z\u0301"),
                    frame="😀 tip", constraints=("Φ₁", "Φ₂")),
    "whitespace": dict(model=" m ", links=(" lead", "trail "), joints=("tab\tj", "new\nline\rcr"),
                       frame="  ", constraints=("a b", "\t")),
    "comment_and_cdata_breakers": dict(model="x-->y--", links=("<!-- l -->", "]]>"),
                                       joints=("--", "-"), frame="<![CDATA[E", constraints=(
                                           "-->", "--!>")),
}


def _named_model(names, drive=Constant(0.5)):
    """Two-joint arm with every name taken from ``names`` and a drive on its first joint."""
    b = ChainBuilder(names["model"])
    b.add_joint(names["joints"][0], REVOLUTE, (0, 0, 1), link=names["links"][0], stiffness=2.0)
    b.add_body(cuboid(1.0, (0.1, 0.2, 0.3), com=(0.1, 0.0, 0.0)))
    b.add_joint(names["joints"][1], REVOLUTE, (0, 1, 0), origin=tf.translation(0.2, 0, 0),
                link=names["links"][1], damping=0.1)
    b.add_body(cuboid(0.5, (0.3, 0.1, 0.1), com=(0.15, 0.0, 0.0)))
    b.add_frame(names["frame"], tf.translation(0.3, 0, 0))
    b.add_drive(names["joints"][0], drive)
    return b.build()


def _named_constraints(names):
    return [EllipseConstraint(0.3, 0.5, frame=names["frame"], name=names["constraints"][0]),
            CoordinateProgramme(Cosine(0.0, 0.1, 2.0), axis=2, frame=names["frame"],
                                name=names["constraints"][1])]


def _names(m, obj, ids):
    return [mujoco.mj_id2name(m, obj, i) for i in ids]


@pytest.mark.parametrize("names", NAME_SETS.values(), ids=NAME_SETS.keys())
def test_special_names_round_trip_through_elementtree_and_mujoco(names):
    model = _named_model(names)
    n = model.n_coordinates
    text = mjcf_text(model, 1e-3, _named_constraints(names), initial_state=(np.zeros(n), np.zeros(n)))
    root = ET.fromstring(text)                    # well-formed, and the attributes read back
    assert root.get("model") == names["model"]
    assert [j.get("name") for j in root.iter("joint")][:n] == list(names["joints"])
    m = mujoco.MjModel.from_xml_string(text)
    ob = mujoco.mjtObj
    assert m.names.split(b"\0")[0].decode() == names["model"]
    assert _names(m, ob.mjOBJ_JOINT, range(n)) == list(names["joints"])
    assert _names(m, ob.mjOBJ_BODY, range(1, n + 1)) == list(names["links"])
    assert names["frame"] in _names(m, ob.mjOBJ_SITE, range(m.nsite))
    assert _names(m, ob.mjOBJ_EQUALITY, range(m.neq))[1:] == list(names["constraints"][::-1])
    assert _names(m, ob.mjOBJ_ACTUATOR, [0]) == [f"drive_{names['joints'][0]}"]
    # and the names are usable: the term comparison finds every coordinate by name
    mj = mujoco.MjModel.from_xml_string(mjcf_text(model, 1e-3))
    rows = term_rows(model, mj, sample_states(model, 2, seed=5))
    assert all(r["status"] == "pass" for r in rows), [r for r in rows if r["status"] != "pass"]


class _DashedRepr:
    """A drive function whose repr would end an XML comment and holds a NUL."""

    def __call__(self, t):
        return 0.0

    def __repr__(self):
        return "f--\x00-->"


def test_comment_text_cannot_end_the_comment():
    names = dict(NAME_SETS["comment_and_cdata_breakers"])
    text = mjcf_text(_named_model(names, drive=_DashedRepr()), 1e-3)
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    root = ET.fromstring(text.split("\n", 1)[1], parser=parser)
    comments = [c.text for c in root.iter(ET.Comment)]
    assert " ctrl = f- -\\x00- -> (N or N m), set by the caller " in comments
    assert text.startswith("<!-- x- ->y- -: generated by ")
    mujoco.MjModel.from_xml_string(text)


@pytest.mark.parametrize("name", FILES)
def test_committed_file_is_well_formed_xml(name):
    root = ET.parse(gen.DEFAULT_DIR / name).getroot()
    assert root.tag == "mujoco" and root.find("worldbody") is not None


def test_extreme_floats_reach_mujoco_bit_exact():
    """repr-level text: the huge, the subnormal and the 17-digit values come back exact."""
    stiffness, damping, springref = 1.2345678901234567e300, 5e-324, -1.7976931348623157e308
    gravity = (2.2250738585072014e-308, -1e-300, -9.806650000000001)
    origin = (1e-300, 0.1 + 0.2, 123456789.12345679)
    b = ChainBuilder("extreme", gravity=gravity)
    b.add_joint("a", REVOLUTE, (0, 0, 1), origin=tf.translation(*origin), stiffness=stiffness,
                damping=damping, spring_reference=springref)
    b.add_body(cuboid(1.0 / 3.0, (0.1, 0.2, 0.3)))
    m = mujoco.MjModel.from_xml_string(mjcf_text(b.build(), 1e-3))
    assert m.jnt_stiffness[0] == stiffness and m.dof_damping[0] == damping
    assert m.qpos_spring[0] == springref
    assert tuple(m.opt.gravity) == gravity and tuple(m.body_pos[1]) == origin
    assert m.body_mass[1] == 1.0 / 3.0


def _model_with(joints=("a", "b"), links=(None, None), frame="E", drives=("a",)):
    b = ChainBuilder("names")
    b.add_joint(joints[0], REVOLUTE, (0, 0, 1), link=links[0])
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1), com=(0.05, 0.0, 0.0)))
    b.add_joint(joints[1], REVOLUTE, (0, 1, 0), origin=tf.translation(0.1, 0, 0), link=links[1])
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1), com=(0.05, 0.0, 0.0)))
    b.add_frame(frame)
    for j in drives:
        b.add_drive(j, Constant(1.0))
    return b.build()


def _specs(frame="E", names=("Phi_1", "Phi_2")):
    return [EllipseConstraint(0.3, 0.5, frame=frame, name=names[0]),
            CoordinateProgramme(Cosine(0.0, 0.1, 2.0), axis=2, frame=frame, name=names[1])]


# (model, constraints, words of the one message); the first group is refused by MuJoCo
# itself ("repeated name": test_mujoco_refuses_the_repeated_names_too), the second cannot be
# written in XML 1.0, the last would be read wrongly.
REPEATED = {
    # a link named "world" (MuJoCo's world body) never gets here: gpme_core.model refuses
    # the name for every engine (tests/test_tree.py)
    "two_drives_on_one_joint": (lambda: _model_with(drives=("a", "a")), None,
                                ["MuJoCo actuator name 'drive_a'", "the drive on joint 'a'",
                                 "give each joint one drive (sum the functions)"]),
    "link_named_like_the_mechanism": (lambda: _model_with(links=(None, "aux_follower")), _specs(),
                                      ["MuJoCo body name 'aux_follower'",
                                       "link 'aux_follower' and to the auxiliary mechanism"]),
    "frame_named_like_the_mechanism": (lambda: _model_with(frame="aux_puck"), _specs("aux_puck"),
                                       ["MuJoCo site name 'aux_puck'", "frame 'aux_puck'"]),
    "constraints_of_one_name": (lambda: _model_with(), _specs(names=("Phi", "Phi")),
                                ["MuJoCo equality name 'Phi'",
                                 "constraint 'Phi' and to constraint 'Phi'"]),
    "constraint_named_like_the_yoke": (lambda: _model_with(), _specs(names=("aux_scotch_yoke", "P")),
                                       ["MuJoCo equality name 'aux_scotch_yoke'"]),
}
UNWRITABLE = {
    "nul_in_joint_name": (lambda: _model_with(joints=("a\x00b", "b"), links=("l", None), drives=()),
                          None,
                          ["joint name 'a\\x00b'", "U+0000", "cannot be written in XML 1.0",
                           "printable characters"]),
    "lone_surrogate_frame": (lambda: _model_with(frame="E\ud800"), None,
                             ["frame name 'E\\ud800'", "U+D800"]),
    "noncharacter_in_constraint_name": (lambda: _model_with(), _specs(names=("P\uffff", "Q")),
                                        ["constraint name 'P\\uffff'", "U+FFFF"]),
    "empty_joint_name": (lambda: _model_with(joints=("", "b"), links=("l", None), drives=()),
                         None, ["joint name is empty", "must be a non-empty str"]),
    "link_name_not_a_str": (lambda: _model_with(links=(5, None)), None,
                            ["link name 5", "got type int"]),
    "reserved_joint_name": (lambda: _model_with(joints=("aux_crank", "b"), drives=()), None,
                            ["joint name 'aux_crank' is reserved for the auxiliary mechanism",
                             "rename the joint"]),
}


@pytest.mark.parametrize("build, constraints, words", [*REPEATED.values(), *UNWRITABLE.values()],
                         ids=[*REPEATED, *UNWRITABLE])
def test_a_name_mujoco_or_xml_refuses_is_one_clear_model_error(build, constraints, words):
    with pytest.raises(ModelError) as err:
        mjcf_text(build(), 1e-3, constraints)
    msg = str(err.value)
    for w in words:
        assert w in msg
    assert len(err.value.problems) == 1


@pytest.mark.parametrize("build, constraints", [v[:2] for v in REPEATED.values()], ids=list(REPEATED))
def test_mujoco_refuses_the_repeated_names_too(build, constraints, monkeypatch):
    """The rule is MuJoCo's: without the check, MuJoCo itself refuses the document."""
    monkeypatch.setattr(mjcf_module, "name_problems", lambda model, programme=None: [])
    text = mjcf_text(build(), 1e-3, constraints)
    with pytest.raises(ValueError, match="repeated name"):
        mujoco.MjModel.from_xml_string(text)


def test_every_name_problem_is_listed_at_once():
    model = _model_with(joints=("a\x01", "b"), links=("aux_follower", None), frame="aux_puck",
                        drives=("b", "b"))
    with pytest.raises(ModelError) as err:
        mjcf_text(model, -1.0, _specs("aux_puck", names=("Phi", "Phi")))
    msg = str(err.value)
    for w in ("dt must be positive", "U+0001", "body name 'aux_follower'",
              "actuator name 'drive_b'",
              "site name 'aux_puck'", "equality name 'Phi'"):
        assert w in msg
    assert len(err.value.problems) == 6


_NAME_CHARS = ["a", "Z", "0", " ", "\t", "\n", "\r", "<", ">", "&", '"', "'", "-", "/", ":",
               "\u00a0", "λ", "関", "\ufeff", "\ue000", "😀", "\U0010fffd",
               "\x00", "\x0b", "\x1f", "\ud800", "\ufffe"]     # the last five: not XML
_NOT_XML = set(_NAME_CHARS[-5:])


def test_every_name_the_writer_accepts_loads_in_mujoco_unchanged(rng):
    """Random names over markup, whitespace, every plane and XML's forbidden characters:
    a name is refused exactly when it holds a character XML cannot hold, and every name
    accepted comes back from MuJoCo unchanged."""
    refused = accepted = 0
    for _ in range(60):
        picks = [str(rng.choice(_NAME_CHARS)) for _ in range(int(rng.integers(1, 8)))]
        name = "".join(picks)
        model = _model_with(joints=(name, "b"), frame=name + "_E", drives=())
        problems = mjcf_module.name_problems(model)
        if set(name) & _NOT_XML:
            assert problems and "cannot be written in XML 1.0" in problems[0]
            refused += 1
            continue
        assert problems == []
        m = mujoco.MjModel.from_xml_string(mjcf_text(model, 1e-3))
        assert _names(m, mujoco.mjtObj.mjOBJ_JOINT, [0]) == [name]
        assert _names(m, mujoco.mjtObj.mjOBJ_BODY, [1]) == [name]
        assert _names(m, mujoco.mjtObj.mjOBJ_SITE, [0]) == [name + "_E"]
        accepted += 1
    assert refused > 5 and accepted > 5      # both branches exercised


class _NanAtZero:
    def __call__(self, t):
        return float("nan")


@pytest.mark.parametrize("state, drive, words", [
    ((np.array([0.0, np.nan]), np.zeros(2)), Constant(1.0),
     ["initial_state q must be finite", "[nan]", "['b']"]),
    ((np.zeros(3), np.zeros(2)), Constant(1.0), ["initial_state q must have shape (2,)", "(3,)"]),
    ((np.zeros(2), np.zeros(2)), _NanAtZero(), ["drive on 'a'", "must be finite, got nan"]),
    (np.zeros((3, 2)), Constant(1.0), ["initial_state must be a pair (q, q_dot)"]),
], ids=["nan_q", "wrong_shape", "drive_nan_at_t0", "not_a_pair"])
def test_keyframe_values_must_be_finite(state, drive, words):
    b = ChainBuilder("key")
    b.add_joint("a", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_joint("b", REVOLUTE, (0, 1, 0), origin=tf.translation(0.1, 0, 0))
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.1)))
    b.add_drive("a", drive)
    with pytest.raises(ModelError) as err:
        mjcf_text(b.build(), 1e-3, initial_state=state)
    for w in words:
        assert w in str(err.value)

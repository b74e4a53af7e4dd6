"""MJCF export: committed files load and match the generator, the export reproduces gpme's
terms, export errors list every problem, the auxiliary mechanism's geometry is right, and
the programmed MJCF alone (plus the drive torque) reproduces gpme's programmed motion."""
import mujoco
import numpy as np
import pytest

from crosscheck.mujoco import generate_mjcf as gen
from crosscheck.mujoco import mechanism as mech
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
from gpme_core.time_functions import Constant

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

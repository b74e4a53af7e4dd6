"""gpme_io.urdf_reader on the descriptions people have: ignored elements (named in the
notes), point masses, trees through a chosen chain with frozen joints, flexible links
whose beam is not along x, beam sections, one error for every problem, and real robots
from example-robot-data compared with Pinocchio reading the same file.

Reference quantities come from Pinocchio (buildModelFromUrdf + buildReducedModel, its own
reduction of the tree) or from chains assembled by hand in the test, never from the reader.
"""
import math
import sysconfig
import tempfile
from pathlib import Path

import numpy as np
import pytest

from gpme_core import transforms as tf
from gpme_core.dynamics import gravity_forces, mass_matrix, velocity_product_terms
from gpme_core.errors import ModelError, ModelFileError
from gpme_core.inertia import RigidBodyInertia
from gpme_core.kinematics import chain_kinematics
from gpme_core.model import PRISMATIC, REVOLUTE, ChainBuilder
from gpme_core.rfem import BeamProperties, BeamSection
from gpme_io.urdf import FlexibleLink, UrdfReadResult, load_urdf, read_urdf

pin = pytest.importorskip("pinocchio")

DATA = Path(__file__).parent / "data" / "urdf"
# example-robot-data installed as data (pip package example-robot-data, cmeel layout)
ROBOTS = (Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
          / "example-robot-data" / "robots")
# Relative tolerance of M, g, h against Pinocchio or a hand-built chain.  Both sides form
# the terms from O(n) products of rigid transforms and inertias, each rounded at
# eps = 2.2e-16 of the largest term; with n <= 13 coordinates and terms that cancel by up
# to a factor 100 (the conditioning of a sum of lever-arm products), the difference is at
# most ~ n * 100 * eps = 3e-13 of the scale.  1e-12 holds that, and any modelling
# difference (a lost mass, a wrong frame) shows at 1e-4 or more.
REL = 1e-12


def _pin_q(pm, names, values):
    """Pinocchio configuration with joint ``names`` at ``values`` (rad or m), the rest
    neutral; a continuous joint holds (cos q, sin q)."""
    q = pin.neutral(pm)
    for name, v in zip(names, values):
        jm = pm.joints[pm.getJointId(name)]
        if jm.nq == 2:
            q[jm.idx_q:jm.idx_q + 2] = (math.cos(v), math.sin(v))
        else:
            q[jm.idx_q] = v
    return q


def _pinocchio_reduced(path, res: UrdfReadResult):
    """Pinocchio's model of the original URDF with every joint gpme froze locked at the
    value gpme reports (Pinocchio's own reduction of the tree)."""
    full = pin.buildModelFromUrdf(str(path))
    locked = [n for n in res.frozen if full.existJointName(n)]
    if not locked:
        return full
    q_ref = _pin_q(full, locked, [res.frozen[n] for n in locked])
    return pin.buildReducedModel(full, [full.getJointId(n) for n in locked], q_ref)


def _worst_against_pinocchio(path, res, seed, states=4):
    """(worst |dM|/max|M|, |dg|/g_scale, |dh|/h_scale) over seeded random states."""
    model = res.model
    pm = _pinocchio_reduced(path, res)
    names = list(model.coordinate_names)
    assert pm.nv == len(names)
    pm.gravity = pin.Motion(model.gravity, np.zeros(3))
    data = pm.createData()
    v_idx = [pm.joints[pm.getJointId(n)].idx_v for n in names]
    rng = np.random.default_rng(seed)
    worst = np.zeros(3)
    for _ in range(states):
        q = rng.uniform(-1.0, 1.0, len(names))
        qd = rng.uniform(-1.0, 1.0, len(names))
        qp = _pin_q(pm, names, q)
        vp = np.zeros(pm.nv)
        vp[v_idx] = qd
        m_p = pin.crba(pm, data, qp)
        m_p = np.triu(m_p) + np.triu(m_p, 1).T          # crba fills the upper triangle
        m_p = m_p[np.ix_(v_idx, v_idx)]
        g_p = pin.computeGeneralizedGravity(pm, data, qp)[v_idx]
        h_p = g_p - pin.rnea(pm, data, qp, vp, np.zeros(pm.nv))[v_idx]
        # scales: max|M|; gravity torque bound |gravity| * sum m_i |c_i| (world frame);
        # h ~ M qd^2
        pin.forwardKinematics(pm, data, qp)
        g_scale = np.linalg.norm(model.gravity) * sum(
            pm.inertias[k].mass * np.linalg.norm(data.oMi[k].act(pm.inertias[k].lever))
            for k in range(1, pm.njoints))
        m_scale = np.abs(m_p).max()
        h_scale = m_scale * np.abs(qd).max() ** 2
        worst = np.maximum(worst, (
            np.abs(mass_matrix(model, q) - m_p).max() / m_scale,
            np.abs(gravity_forces(model, q) - g_p).max() / g_scale,
            np.abs(velocity_product_terms(model, q, qd) - h_p).max() / h_scale))
    return worst


# ------------------------------------------------------------------ ignored elements
def test_ignored_elements_are_named_once_and_the_file_loads():
    res = load_urdf(DATA / "extensions.urdf", side_file=None)
    model = res.model
    assert model.coordinate_names == ("j1", "j2") and res.chain == ("base", "fore")
    notes = "\n".join(res.notes)
    for expected in (
            "<dynamics friction> on 2 joints ignored (gpme has no Coulomb friction): j1, j2",
            "effort/velocity <limit> on 2 joints ignored (gpme has no actuator limits): j1, j2",
            "<safety_controller> on 1 joint ignored (controller settings, not dynamics): j1",
            "<calibration> on 1 joint ignored (encoder reference, not dynamics): j1",
            "<mimic> on 1 joint ignored (a fixed joint does not move): tool_joint",
            "<visual>/<collision> of 1 link fixed to the world left out (they do not move; "
            "the model has no world body): base",
            "<transmission>", "<gazebo>",
            "<limit lower == upper> on 1 joint read as no range (unlimited; URDF's default "
            "lower = upper = 0 when a <limit> gives only effort and velocity): j2"):
        assert expected in notes, expected
    # each ignored class once: one line per class
    assert len([n for n in res.notes if "friction" in n]) == 1
    assert model.joints[0].limits == (-2.0, 2.0) and model.joints[0].damping == 0.5
    assert model.joints[1].limits == (-np.inf, np.inf)
    assert set(res.frames) == {"tool"} and model.total_mass == 3.0
    # the moving link's <collision> is kept (issue 28), in its link frame, mass unchanged
    (shape,) = model.geometry
    assert (model.links[shape.link_index].name, shape.kind, shape.size, shape.role) == \
        ("upper", "cylinder", (0.02, 0.4), "collision")


def test_lower_above_upper_stays_an_error(tmp_path):
    text = (DATA / "extensions.urdf").read_text().replace(
        '<limit lower="-2" upper="2"', '<limit lower="0.5" upper="-0.5"')
    path = tmp_path / "r.urdf"
    path.write_text(text)
    with pytest.raises(ModelFileError, match=r"joint 'j1': <limit lower=0\.5 upper=-0\.5> must "
                                             r"have lower <= upper"):
        load_urdf(path)


# ------------------------------------------------------------------ point masses
def test_point_mass_off_its_axis_is_a_valid_link():
    """Zero inertia tensors (cart and bob): M = [[m_c + m_b, -m_b r sin], [., m_b r^2]]
    at spin = q, written by hand for a point mass m_b at radius r."""
    path = DATA / "point_mass.urdf"
    text = path.read_text().replace("{com_x}", "0.25")
    model = load_urdf(_copy(text), side_file=None).model
    q = np.array([0.1, 0.7])
    m_b, r = 0.5, 0.25
    expected = np.array([[5.5, -m_b * r * math.sin(0.7)], [-m_b * r * math.sin(0.7), m_b * r ** 2]])
    assert np.allclose(mass_matrix(model, q), expected, rtol=0, atol=REL * 5.5)


def test_point_mass_on_its_own_revolute_axis_makes_m_singular():
    text = (DATA / "point_mass.urdf").read_text().replace("{com_x}", "0")
    with pytest.raises(ModelFileError, match=r"the mass matrix at q = spring references is not "
                                             r"positive definite .* no mass or inertia resists a "
                                             r"motion of spin; coordinates moving no mass: "
                                             r"\['spin'\]"):
        load_urdf(_copy(text), side_file=None)


def test_inertia_checks_accept_psd_and_reject_the_unphysical():
    assert not RigidBodyInertia(1.0, (0, 0, 0), np.zeros((3, 3))).problems("p")
    assert not RigidBodyInertia(1.0, (0, 0, 0), np.diag([0.0, 1.0, 1.0])).problems("rod")
    assert not RigidBodyInertia(0.0, (0, 0, 0), np.zeros((3, 3))).problems("none")
    # the triangle inequality broken (0.1 + 0.1 < 0.3): accepted as Pinocchio accepts it,
    # said by non_physical with the excess I3 - I1 - I2 = 0.1 kg m^2
    cad = RigidBodyInertia(1.0, (0, 0, 0), np.diag([0.1, 0.1, 0.3]))
    assert not cad.problems("link 'x'")
    assert cad.triangle_excess() == pytest.approx(0.1, rel=1e-12)
    assert cad.non_physical("link 'x'") == [
        "link 'x': principal moments [0.1, 0.1, 0.3] kg m^2 break the triangle inequality "
        "I1 + I2 >= I3 of a physical body (I3 exceeds I1 + I2 by 0.1 kg m^2); accepted, as "
        "Pinocchio accepts it: the mass matrix is checked positive definite instead"]
    # equality (a thin disc, I3 = I1 + I2) and round-off above it are physical
    assert not RigidBodyInertia(1.0, (0, 0, 0), np.diag([0.1, 0.1, 0.2 + 1e-15])
                                ).non_physical("disc")
    bad = RigidBodyInertia(1.0, (0, 0, 0), np.diag([-0.1, 0.2, 0.2])).problems("link 'y'")
    assert "inertia tensor must be positive definite or semi-definite" in bad[0]
    assert "[-0.1, 0.2, 0.2]" in bad[0]
    assert "mass must be positive and finite, got -2.0 kg" in \
        RigidBodyInertia(-2.0).problems("z")[0]


# ------------------------------------------------------------------ trees
def _tree_by_hand(jb, jm):
    """tree.urdf through base -> c with jb, jm frozen, assembled by hand: the branch's
    poses composed here from the file's numbers, not by the reader."""
    b = ChainBuilder("tree")
    b.add_joint("j1", REVOLUTE, (0, 0, 1), origin=tf.translation(0, 0, 0.3) @ tf.rot_z(0.2),
                link="a", limits=(-3, 3))
    r = tf.rot_x(0.1)[:3, :3]
    b.add_body(RigidBodyInertia(3.0, (0.05, 0, 0.1),
                                r @ np.array([[0.02, 0.001, 0], [0.001, 0.025, 0], [0, 0, 0.01]])
                                @ r.T))
    x_side = tf.translation(0, -0.1, 0.1) @ tf.revolute_motion((1, 0, 0), jb)
    b.add_body(RigidBodyInertia(1.5, (0, -0.1, 0), np.diag([0.003, 0.002, 0.003])), origin=x_side)
    x_finger = x_side @ tf.translation(0, -0.2, 0) @ tf.revolute_motion((0, 0, 1), jm)
    b.add_body(RigidBodyInertia(0.2, (0.03, 0, 0), np.diag([0.0001, 0.0002, 0.0002])),
               origin=x_finger)
    b.add_joint("j2", REVOLUTE, (0, 0, 1),
                origin=tf.translation(0, 0.1, 0.2) @ tf.rot_x(math.pi / 2), link="b")
    b.add_body(RigidBodyInertia(2.0, (0.25, 0, 0), np.diag([0.002, 0.04, 0.04])))
    b.add_body(RigidBodyInertia(0.4, (0.01, 0, 0), np.diag([0.0003, 0.0002, 0.0002])),
               origin=tf.translation(0.3, 0.02, 0) @ tf.rot_y(0.3))
    b.add_joint("j3", PRISMATIC, (1, 0, 0), origin=tf.translation(0.5, 0, 0), link="c")
    b.add_body(RigidBodyInertia(0.7, (0.05, 0, 0), np.diag([0.0004, 0.001, 0.001])))
    return b.build()


def test_tree_through_a_chain_with_frozen_and_mimic_joints_equals_the_hand_built_chain():
    path = DATA / "tree.urdf"
    res = load_urdf(path, chain=("base", "c"), frozen={"jb": 0.4})
    assert res.chain_joints == ("j1", "j2", "j3") and res.chain == ("base", "c")
    assert dict(res.frozen) == {"jb": 0.4, "jm": 2 * 0.4 + 0.1}
    assert set(res.frames) == {"side", "finger", "sensor"}
    assert any("jm = 2.0 * jb + 0.1 = 0.9" in n for n in res.notes)
    hand = _tree_by_hand(0.4, 0.9)
    rng = np.random.default_rng(7)
    for _ in range(4):
        q = rng.uniform(-1, 1, 3) * (1, 1, 0.1)
        m_ref = mass_matrix(hand, q)
        assert np.abs(mass_matrix(res.model, q) - m_ref).max() <= REL * np.abs(m_ref).max()
        g_ref = gravity_forces(hand, q)
        assert np.abs(gravity_forces(res.model, q) - g_ref).max() <= REL * np.abs(g_ref).max()
    # and Pinocchio's own reduction of the same file agrees
    assert np.all(_worst_against_pinocchio(path, res, seed=8) <= REL)


def test_tree_needs_a_tip_when_moving_joints_branch():
    with pytest.raises(ModelFileError, match=r"the moving joints below link 'base' lie on 2 "
                                             r"branches ending at links \['finger', 'c'\]"):
        load_urdf(DATA / "tree.urdf")


def test_chain_choice_problems_are_listed_together():
    with pytest.raises(ModelFileError) as exc:
        load_urdf(DATA / "tree.urdf", chain=("a", "c"),
                  frozen={"j2": 0.1, "nope": 1.0, "sensor_joint": 0.0, "jb": 3.0})
    msg = str(exc.value)
    for expected in ("frozen joint 'j2' is on the chain (a gpme coordinate)",
                     "frozen joint 'nope': no such joint; moving joints off the chain: "
                     "['j1', 'jb', 'jm']",
                     "frozen joint 'sensor_joint' is a fixed joint",
                     "frozen joint 'jb' = 3.0 rad is outside its <limit> [-1.0, 1.0]",
                     "joint 'j1' (revolute) lies above the chain root and would move the whole "
                     "chain: freeze it with frozen={'j1': value}"):
        assert expected in msg, expected
    with pytest.raises(ModelFileError, match=r"chain tip 'side' is not below the chain root 'b'"):
        load_urdf(DATA / "tree.urdf", chain=("b", "side"))


def test_mimic_joint_on_the_chain_is_an_error():
    with pytest.raises(ModelFileError, match=r"joint 'jm' on the chain mimics 'jb': every gpme "
                                             r"coordinate is independent"):
        load_urdf(DATA / "tree.urdf", chain=("base", "finger"))


def test_root_below_the_urdf_root_keeps_the_world_frame():
    """chain a -> c with j1 frozen at 0.3: the world is still the URDF root frame, so the
    model equals the hand-built chain with j1 made rigid at 0.3 (gravity along world z)."""
    res = load_urdf(DATA / "tree.urdf", chain=("a", "c"), frozen={"j1": 0.3, "jb": 0.4})
    assert res.chain_joints == ("j2", "j3")
    hand = _tree_by_hand(0.4, 0.9)
    q = np.array([0.3, -0.4, 0.05])
    idx = [1, 2]
    m_ref = mass_matrix(hand, q)[np.ix_(idx, idx)]
    assert np.abs(mass_matrix(res.model, q[idx]) - m_ref).max() <= REL * np.abs(m_ref).max()
    g_ref = gravity_forces(hand, q)[idx]
    assert np.abs(gravity_forces(res.model, q[idx]) - g_ref).max() <= REL * np.abs(g_ref).max()


# ------------------------------------------------------------------ flexible links
E, G, RHO = 70e9, 26e9, 2700.0
SECTION = BeamSection.rectangle(0.04, 0.02)      # I_y != I_z: the section frame matters


def _column_by_hand(n):
    """beam_along_z.urdf with the column as an RFEM beam along link z, built without
    add_beam: beam frame B = (x_B, y_B, z_B) = (z, y, -x) of the link; every element is
    placed in link axes, its inertia diag(J, I_y, I_z) rho l (+ m l^2/12 across) rotated
    by hand."""
    length = 0.8
    r = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])   # columns: B in link
    a, iy, iz, j = (SECTION.area, SECTION.second_moment_y, SECTION.second_moment_z,
                    SECTION.second_moment_y + SECTION.second_moment_z)

    def piece(l):
        m = RHO * a * l
        i_b = np.diag([RHO * j * l, RHO * iy * l + m * l ** 2 / 12, RHO * iz * l + m * l ** 2 / 12])
        return RigidBodyInertia(m, (0, 0, l / 2), r @ i_b @ r.T)

    b = ChainBuilder("beam_along_z")
    b.add_joint("yaw", REVOLUTE, (0, 0, 1), link="column", limits=(-3, 3))
    dl = length / max(n, 1)
    if n == 0:
        b.add_body(piece(length))
        to_tip = tf.translation(0, 0, -length)       # beam tip seen from the link frame
    else:
        b.add_body(piece(dl / 2))
        axes = {"psi": (-1.0, 0.0, 0.0), "theta": (0.0, 1.0, 0.0), "phi": (0.0, 0.0, 1.0)}
        stiff = {"psi": E * iz / dl, "theta": E * iy / dl, "phi": G * SECTION.torsion_constant / dl}
        for k in range(1, n + 1):
            for rot in ("psi", "theta", "phi"):
                b.add_joint(f"{rot}_column_{k}", REVOLUTE, axes[rot],
                            origin=tf.translation(0, 0, dl / 2 if k == 1 else dl)
                            if rot == "psi" else None, stiffness=stiff[rot])
            b.add_body(piece(dl if k < n else dl / 2))
        to_tip = tf.translation(0, 0, -(length - dl / 2))   # rfe n sits at L - dl/2
    b.add_body(RigidBodyInertia(0.3, (0, 0, 0), np.diag([0.001, 0.001, 0.002])),
               origin=to_tip @ tf.translation(0.05, 0, 0.8))
    b.add_joint("pitch", REVOLUTE, (0, 1, 0),
                origin=to_tip @ tf.translation(0, 0, 0.8) @ tf.rot_z(0.3), link="arm")
    b.add_body(RigidBodyInertia(1.2, (0.3, 0, 0), np.diag([0.001, 0.04, 0.04])))
    return b.build()


@pytest.mark.parametrize("n", [0, 1, 3], ids=["n0", "n1", "n3"])
def test_flexible_link_with_beam_along_z_equals_the_hand_built_chain(n):
    spec = FlexibleLink(SECTION, E, G, RHO, n)
    res = load_urdf(DATA / "beam_along_z.urdf", flexible={"column": spec})
    hand = _column_by_hand(n)
    model = res.model
    assert model.coordinate_names == hand.coordinate_names
    assert np.array_equal(model.stiffness, hand.stiffness) or \
        np.allclose(model.stiffness, hand.stiffness, rtol=1e-15, atol=0)
    beam_mass = RHO * SECTION.area * 0.8
    assert any(f"link column: URDF inertial 6 kg replaced by the RFEM beam {beam_mass:.6g} kg"
               in note for note in res.notes)
    rng = np.random.default_rng(11 + n)
    for _ in range(3):
        q = rng.uniform(-0.5, 0.5, model.n_coordinates)
        m_ref, g_ref = mass_matrix(hand, q), gravity_forces(hand, q)
        assert np.abs(mass_matrix(model, q) - m_ref).max() <= REL * np.abs(m_ref).max()
        assert np.abs(gravity_forces(model, q) - g_ref).max() <= REL * np.abs(g_ref).max()
    # zero deflection: the arm joint and the plate frame are where the rigid file has them
    rigid = load_urdf(DATA / "beam_along_z.urdf").model
    q_r = np.array([0.4, -0.6])
    q_f = np.zeros(model.n_coordinates)
    q_f[0], q_f[-1] = q_r
    t_r, t_f = chain_kinematics(rigid, q_r).T, chain_kinematics(model, q_f).T
    assert np.allclose(t_r[-1], t_f[-1], rtol=0, atol=1e-15)
    fr_r, fr_f = rigid.frames["plate"], model.frames["plate"]
    assert np.allclose(t_r[fr_r.link_index] @ fr_r.transform,
                       t_f[fr_f.link_index] @ fr_f.transform, rtol=0, atol=1e-15)


def test_flexible_spec_problems_are_listed_together():
    with pytest.raises(ModelFileError) as exc:
        load_urdf(DATA / "beam_along_z.urdf", flexible={
            "arm": FlexibleLink(SECTION, E, G, RHO, 2),                      # tip: no axis
            "column": FlexibleLink(SECTION, -E, G, RHO, 1.5, axis=(0, 0, 2)),
            "plate": FlexibleLink(SECTION, E, G, RHO, 1)})
    msg = str(exc.value)
    for expected in ("flexible link 'arm': it is the chain tip (no next chain joint): give "
                     "axis= (unit, link frame) and length= (m)",
                     "flexible link 'column': n_segments must be an integer from 0 to 1000, got 1.5",
                     "flexible link 'column': axis must be a unit vector in the link frame, "
                     "got [0.0, 0.0, 2.0]",
                     "flexible link 'column': youngs_modulus must be positive and finite (Pa), "
                     "got -70000000000.0",
                     "flexible link 'plate': not a link moved by a joint of the chain"):
        assert expected in msg, expected


def test_add_beam_frame_rejects_a_non_rotation():
    b = ChainBuilder()
    b.add_joint("q", REVOLUTE, (0, 0, 1))
    beam = BeamProperties.from_section(1.0, SECTION, E, G, RHO)
    with pytest.raises(ModelError, match=r"beam 'b': beam frame rotation is not a proper rotation"):
        b.add_beam("b", beam, 1, frame=np.diag([1.0, 1.0, -1.0, 1.0]))


# ------------------------------------------------------------------ sections
def _rectangle_torsion_series(a, b, terms=2000):
    """Saint-Venant's J of an a x b rectangle (a >= b, full sides), the exact series
    (Timoshenko and Goodier, Theory of Elasticity, 3rd ed., sec. 109)."""
    n = np.arange(1, 2 * terms, 2)
    return a * b ** 3 / 3 * (1 - 192 / math.pi ** 5 * (b / a)
                             * np.sum(np.tanh(n * math.pi * a / (2 * b)) / n ** 5))


def test_sections_against_closed_forms_and_the_series():
    c = BeamSection.solid_circle(0.02)
    assert c.area == pytest.approx(math.pi * 1e-4, rel=1e-15)
    assert c.second_moment_y == c.second_moment_z == pytest.approx(math.pi * 0.02 ** 4 / 64,
                                                                   rel=1e-15)
    assert c.torsion_constant == pytest.approx(math.pi * 0.02 ** 4 / 32, rel=1e-15)
    t = BeamSection.tube(0.04, 0.003)                       # D = 40 mm, d = 34 mm
    assert t.area == pytest.approx(math.pi / 4 * (0.04 ** 2 - 0.034 ** 2), rel=1e-14)
    assert t.second_moment_z == pytest.approx(math.pi / 64 * (0.04 ** 4 - 0.034 ** 4), rel=1e-14)
    assert t.torsion_constant == pytest.approx(math.pi / 32 * (0.04 ** 4 - 0.034 ** 4), rel=1e-14)
    r = BeamSection.rectangle(0.06, 0.02)
    assert (r.second_moment_y, r.second_moment_z) == pytest.approx(
        (0.06 * 0.02 ** 3 / 12, 0.02 * 0.06 ** 3 / 12), rel=1e-15)
    # Roark's formula is within 0.5 % of the series for every aspect ratio (worst 0.49 % near
    # a/b = 1.14, found by scanning the series); width and height are interchangeable
    for ratio in (1.0, 1.14, 1.5, 2.0, 3.0, 5.0, 10.0, 50.0):
        b = 0.01
        exact = _rectangle_torsion_series(ratio * b, b)
        for sec in (BeamSection.rectangle(ratio * b, b), BeamSection.rectangle(b, ratio * b)):
            assert abs(sec.torsion_constant - exact) <= 0.005 * exact, ratio
    beam = BeamProperties.from_section(2.0, t, 210e9, 81e9, 7850.0, bending_viscosity=1e6)
    assert beam.mass == pytest.approx(7850.0 * t.area * 2.0, rel=1e-15)
    assert BeamProperties.solid_circular(2.0, 0.02, 210e9, 81e9, 7850.0) == \
        BeamProperties.from_section(2.0, c, 210e9, 81e9, 7850.0)


def test_section_inputs_are_validated():
    with pytest.raises(ModelError, match=r"tube: wall_thickness 0\.03 m must be smaller than the "
                                         r"outer radius 0\.02 m"):
        BeamSection.tube(0.04, 0.03)
    with pytest.raises(ModelError) as exc:
        BeamSection.rectangle(-0.01, float("nan"))
    assert "width_y must be positive and finite (m), got -0.01" in str(exc.value)
    assert "height_z must be positive and finite (m), got nan" in str(exc.value)
    with pytest.raises(ModelError, match=r"solid_circle: diameter must be positive"):
        BeamSection.solid_circle(0.0)


# ------------------------------------------------------------------ one error for all
def test_every_stage_reports_into_one_error(tmp_path):
    """A bad side file, a negative inertia on a chain link, an unknown frozen joint and a
    chain link whose motion nothing resists (spin on a point mass on its axis)."""
    text = (DATA / "point_mass.urdf").read_text().replace("{com_x}", "0").replace(
        '<mass value="5"/>', '<mass value="-5"/>')
    path = _copy(text, tmp_path)
    side = path.with_name(path.stem + ".gpme.json")
    side.write_text('{"format": "other", "version": 1}')
    with pytest.raises(ModelFileError) as exc:
        load_urdf(path, frozen={"ghost": 1.0})
    msg = str(exc.value)
    for expected in ("expected format 'gpme-urdf-side-file' version 1, got 'other'",
                     "link 'cart' <inertial>: mass must be positive and finite, got -5.0 kg",
                     "frozen joint 'ghost': no such joint",
                     "no mass or inertia resists a motion of",
                     "(found with the invalid <inertial> elements above left out)"):
        assert expected in msg, expected


def _copy(text, directory=None):
    import tempfile
    d = Path(directory or tempfile.mkdtemp())
    path = d / "robot.urdf"
    path.write_text(text)
    return path


# ------------------------------------------------------------------ real robots
# (file under example-robot-data/robots, chain, frozen): serial arms and trees with a chain
REAL = [
    ("ur_description/urdf/ur5_robot.urdf", None, None),
    ("panda_description/urdf/panda.urdf", ("panda_link0", "panda_hand"), {"panda_finger_joint1": 0.02}),
    ("kinova_description/robots/kinova.urdf", None, None),
    ("xarm_description/urdf/xarm7.urdf", None, None),
    ("z1_description/urdf/z1.urdf", None, None),
    ("double_pendulum_description/urdf/double_pendulum_continuous.urdf", None, None),
    ("talos_data/robots/talos_reduced.urdf", ("torso_2_link", "arm_left_7_link"),
     {"torso_1_joint": 0.1, "torso_2_joint": -0.2}),
    ("tiago_description/robots/tiago.urdf", ("torso_lift_link", "arm_7_link"),
     {"torso_lift_joint": 0.1}),
    ("pr2_description/urdf/pr2.urdf", ("torso_lift_link", "r_wrist_roll_link"),
     {"torso_lift_joint": 0.1}),
    ("baxter_description/urdf/baxter.urdf", ("base", "left_gripper"), None),
    ("human_description/robots/human.urdf", ("middle_pelvis", "right_hand"), None),
]


# descriptions whose moving links' inertias break the triangle inequality (CAD round-off):
# accepted as Pinocchio accepts them (issue 28), each with its note and warning naming the
# links, and their terms must then agree with Pinocchio's as any other's
NON_PHYSICAL = [
    ("hyq_description/robots/hyq_no_sensors.urdf", ("base_link", "lf_foot"), None,
     ["lf_foot"]),
    ("allegro_hand_description/urdf/allegro_right_hand.urdf", ("palm_link", "link_3.0"), None,
     ["link_3.0"]),
    ("allegro_hand_description/urdf/allegro_left_hand.urdf", ("palm_link", "link_7.0"), None,
     ["link_7.0"]),
    ("romeo_description/urdf/romeo_small.urdf", ("base_link", "r_wrist"), None,
     ["RShoulderYawLink"]),
    ("pr2_description/urdf/pr2.urdf", ("base_footprint", "head_tilt_link"), None,
     ["sensor_mount_link"]),
]


@pytest.mark.parametrize("rel, chain, frozen, links", NON_PHYSICAL,
                         ids=[Path(r[0]).stem + "-" + r[1][1] for r in NON_PHYSICAL])
def test_real_robot_with_non_physical_inertias_is_read_as_pinocchio_reads_it(rel, chain,
                                                                             frozen, links):
    from gpme_core.errors import InertiaWarning
    path = ROBOTS / rel
    if not path.exists():
        pytest.skip(f"example-robot-data not installed ({path} missing)")
    with pytest.warns(InertiaWarning, match="break the triangle inequality"):
        res = load_urdf(path, side_file=None, chain=chain, frozen=frozen)
    note = [n for n in res.notes if n.startswith("non-physical inertias of moving links")]
    assert note and all(f"link {link!r}" in note[0] for link in links), res.notes
    worst = _worst_against_pinocchio(path, res, seed=sum(map(ord, rel)) % 1000)
    assert np.all(worst <= REL), dict(zip("Mgh", worst))


def test_a_negative_principal_moment_is_still_refused():
    """romeo_laas_small's 'body' has a negative principal moment (-0.0213 kg m^2): not a
    body at all, refused with the moments (Pinocchio takes it silently)."""
    path = ROBOTS / "romeo_description/urdf/romeo_laas_small.urdf"
    if not path.exists():
        pytest.skip(f"example-robot-data not installed ({path} missing)")
    with pytest.raises(ModelFileError, match=r"(?s)link 'body' <inertial>: inertia tensor "
                                             r"must be positive definite or semi-definite"
                                             r".*\[-0\.0213"):
        load_urdf(path, side_file=None)


@pytest.mark.parametrize("rel, chain, frozen", REAL, ids=[Path(r[0]).stem for r in REAL])
def test_real_robot_matches_pinocchio_reading_the_same_file(rel, chain, frozen):
    path = ROBOTS / rel
    if not path.exists():
        pytest.skip(f"example-robot-data not installed ({path} missing)")
    res = load_urdf(path, side_file=None, chain=chain, frozen=frozen)
    worst = _worst_against_pinocchio(path, res, seed=sum(map(ord, rel)) % 1000)
    assert np.all(worst <= REL), dict(zip("Mgh", worst))


def test_a_link_frame_round_trips_through_the_urdf_writer():
    """A frame that is a chain link's own frame (a model file's constraint on a moving link)
    is written as that URDF link, not as a second link of the same name, and comes back with
    with_link_frames."""
    from gpme_core.model import REVOLUTE, ChainBuilder
    from gpme_core.inertia import cuboid
    from gpme_io.urdf_reader import read_urdf, with_link_frames
    from gpme_io.urdf_writer import link_own_frame, urdf_documents
    b = ChainBuilder("two")
    b.add_joint("j1", REVOLUTE, (0, 0, 1), link="l1")
    b.add_body(cuboid(1.0, (0.1, 0.1, 0.3), com=(0, 0, 0.15)))
    b.add_frame("l1")                                   # the link's own frame
    b.add_joint("j2", REVOLUTE, (0, 1, 0), link="l2")
    b.add_body(cuboid(1.0, (0.3, 0.1, 0.1), com=(0.15, 0, 0)))
    model = b.build()
    assert link_own_frame(model, "l1")
    text, _ = urdf_documents(model)
    assert text.count('<link name="l1"') == 1
    path = Path(tempfile.mkdtemp()) / "two.urdf"
    path.write_text(text)
    back = with_link_frames(read_urdf(path, side_file=None), ["l1"])
    assert back.frame("l1").link_index == 0
    with pytest.raises(ModelError, match="no links named"):
        with_link_frames(back, ["nowhere"])


def test_expression_drive_round_trips_and_a_bad_expression_is_refused(tmp_path):
    """A drive written as a SymPy expression (a model file's `type = "expression"`) is
    stored as its text and read back without eval; code in that text is refused."""
    import json

    from gpme_core.inertia import cuboid
    from gpme_core.model import REVOLUTE, ChainBuilder
    from gpme_core.time_functions import SympyTimeFunction
    from gpme_io.urdf_reader import read_urdf
    from gpme_io.urdf_writer import write_urdf
    b = ChainBuilder("driven")
    b.add_joint("j1", REVOLUTE, (0, 0, 1), link="l1")
    b.add_body(cuboid(1.0, (0.3, 0.1, 0.1), com=(0.15, 0, 0)))
    b.add_drive("j1", SympyTimeFunction("0.3*sin(4*t)"))
    path, side = write_urdf(b.build(), tmp_path / "driven.urdf")
    back = read_urdf(path)
    assert back.drive_forces(0.2) == pytest.approx([0.3 * math.sin(0.8)], rel=1e-15)
    data = json.loads(side.read_text())
    data["drives"][0]["parameters"]["expr"] = "__import__('os').system('true')"
    side.write_text(json.dumps(data))
    with pytest.raises(ModelFileError, match="drive record on 'j1'"):
        read_urdf(path)

"""Reading a URDF as a whole tree (every moving joint a coordinate, ``whole_tree=True`` or
the side file's ``"tree": true``): the written tree reads back exactly, a flexible link
carrying two branches puts both on its beam's tip, and the terms of that flexible tree
equal Pinocchio's on the URDF gpme writes for it."""
import numpy as np
import pinocchio as pin
import pytest

from conftest import spatial_tree
from crosscheck.pinocchio.model import from_urdf
from gpme_core import dynamics as dy
from gpme_core.errors import ModelFileError
from gpme_core.kinematics import link_transforms
from gpme_core.rfem import BeamSection
from gpme_io.urdf import write_urdf
from gpme_io.urdf_reader import FlexibleLink, load_urdf, parse_urdf

E, G, RHO = 70e9, 26e9, 2700.0
SECTION = BeamSection.rectangle(0.04, 0.02)

# An arm on a turntable whose flexible link "arm" carries two fingers at its tip: two
# branches below one beam, so the beam's axis and length must be given (no single next
# joint to point at).  Joint origins in m, rpy in rad.
FORK = """<robot name="fork">
  <link name="base"/>
  <link name="turntable"><inertial><mass value="3"/><origin xyz="0 0 0.1"/>
    <inertia ixx="0.02" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="arm"><inertial><mass value="2"/><origin xyz="0.4 0 0"/>
    <inertia ixx="0.001" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_a"><inertial><mass value="0.3"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.0001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_b"><inertial><mass value="0.2"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.0001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip_a"/>
  <joint name="yaw" type="revolute"><parent link="base"/><child link="turntable"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="pitch" type="revolute"><parent link="turntable"/><child link="arm"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="open_a" type="revolute"><parent link="arm"/><child link="finger_a"/>
    <origin xyz="0.8 0.05 0" rpy="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="open_b" type="prismatic"><parent link="arm"/><child link="finger_b"/>
    <origin xyz="0.8 -0.05 0"/><axis xyz="0 1 0"/>
    <limit lower="-0.1" upper="0.1" effort="1" velocity="1"/></joint>
  <joint name="tip_a_fixed" type="fixed"><parent link="finger_a"/><child link="tip_a"/>
    <origin xyz="0.2 0 0"/></joint>
</robot>
"""


def test_a_written_tree_reads_back_exactly(tmp_path, rng):
    tree = spatial_tree()
    urdf, _ = write_urdf(tree, tmp_path / "tree.urdf")
    res = load_urdf(urdf)                    # the side file says "tree": true
    model = res.model
    assert model.coordinate_names == tree.coordinate_names
    np.testing.assert_array_equal(model.parents, tree.parents)
    q, q_dot = rng.uniform(-1, 1, 7), rng.uniform(-1, 1, 7)
    a, b = dy.dynamics_terms(tree, 0.0, q, q_dot), dy.dynamics_terms(model, 0.0, q, q_dot)
    for name in ("M", "h", "g", "f", "d"):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=0, atol=1e-13,
                                   err_msg=name)


def test_a_chain_choice_on_a_tree_still_asks_for_the_branch():
    with pytest.raises(ModelFileError, match="lie on 2 branches"):
        parse_urdf(FORK)
    rigid = parse_urdf(FORK, whole_tree=True)
    assert rigid.coordinate_names == ("yaw", "pitch", "open_a", "open_b")
    assert rigid.parents.tolist() == [-1, 0, 1, 1]
    assert "tip_a" in rigid.frames


def test_a_flexible_link_carrying_two_branches(tmp_path, rng):
    """At zero deflection every link and frame sits where the rigid read puts it; the
    fingers hang on the beam's last segment; the written URDF's terms equal Pinocchio's."""
    rigid = parse_urdf(FORK, whole_tree=True)
    with pytest.raises(ModelFileError, match="arm"):           # no single next joint
        parse_urdf(FORK, whole_tree=True, flexible={"arm": FlexibleLink(SECTION, E, G, RHO, 3)})
    spec = FlexibleLink(SECTION, E, G, RHO, 3, axis=(1, 0, 0), length=0.8)
    model = parse_urdf(FORK, whole_tree=True, flexible={"arm": spec})
    names = model.coordinate_names
    assert len(names) == 4 + 9
    tip_segment = model.parents[names.index("open_a")]
    assert model.parents[names.index("open_b")] == tip_segment
    assert names[tip_segment].endswith("_3")              # the beam's last segment
    q_rigid = rng.uniform(-1, 1, 4) * np.array([1, 1, 1, 0.05])
    q = np.zeros(len(names))
    for k, c in enumerate(rigid.coordinate_names):
        q[names.index(c)] = q_rigid[k]
    t_rigid, t_flex = link_transforms(rigid, q_rigid), link_transforms(model, q)
    for c in ("open_a", "open_b"):
        np.testing.assert_allclose(t_flex[names.index(c)],
                                   t_rigid[rigid.coordinate_names.index(c)], atol=1e-14)
    for f in rigid.frames:
        fr, fr_flex = rigid.frame(f), model.frame(f)
        np.testing.assert_allclose(t_flex[fr_flex.link_index] @ fr_flex.transform,
                                   t_rigid[fr.link_index] @ fr.transform, atol=1e-14)
    urdf, _ = write_urdf(model, tmp_path / "fork_flexible.urdf")
    ps = from_urdf(urdf, names, [lk.name for lk in model.links], list(model.frames))
    pm = ps.model
    data = pm.createData()
    for _ in range(3):
        q, q_dot = rng.uniform(-0.5, 0.5, len(names)), rng.uniform(-1, 1, len(names))
        terms = dy.dynamics_terms(model, 0.0, q, q_dot)
        m_pin = pin.crba(pm, data, ps.q_pin(q))
        m_pin = (np.triu(m_pin) + np.triu(m_pin, 1).T)[np.ix_(ps.v_index, ps.v_index)]
        g_pin = ps.to_gpme(pin.computeGeneralizedGravity(pm, data, ps.q_pin(q)))
        h_pin = -(ps.to_gpme(pin.rnea(pm, data, ps.q_pin(q), ps.to_pin(q_dot),
                                      np.zeros(pm.nv))) - g_pin)
        # round-off relative to the largest entry (tests/test_tree.py: 1.3e-15 measured)
        for ours, theirs in ((terms.M, m_pin), (terms.h, h_pin), (terms.g, g_pin)):
            np.testing.assert_allclose(ours, theirs, rtol=0,
                                       atol=1e-12 * max(1.0, np.abs(theirs).max()))
    reread = load_urdf(urdf).model                   # side file: tree and RFEM records
    assert reread.coordinate_names == names
    np.testing.assert_array_equal(reread.parents, model.parents)

"""Kinematic trees (every branch moving): the trace-form terms against Pinocchio's CRBA and
RNEA on the same tree (built joint by joint and read from the URDF gpme writes), the
structure of M (no inertial coupling between branches), runs of a tree (compiled loop
against the Python path, energy balance), and the model's checks of a tree's parents.

The Lagrange, finite-difference and compiled-against-numpy checks of the terms run on the
tree of conftest.spatial_tree inside tests/test_dynamics.py, test_kinematics.py and
test_fast.py.
"""
import numpy as np
import pinocchio as pin
import pytest

from conftest import spatial_arm, spatial_tree
from crosscheck.pinocchio.model import from_gpme, from_urdf
from gpme_core import dynamics as dy
from gpme_core import transforms as tf
from gpme_core.errors import ModelError
from gpme_core.gpme import ProgrammedMotion
from gpme_core.inertia import cuboid
from gpme_core.integrate import simulate
from gpme_core.model import REVOLUTE, WORLD, ChainBuilder
from gpme_io.urdf import write_urdf

# Pinocchio and gpme sum the same physics in different orders (spatial algebra against
# 4x4 traces): the difference is round-off, a few eps times the largest term times the
# number of bodies (7 here); measured 1.3e-15 relative to the largest entry on this tree
# (20 states, both Pinocchio sides), so 1e-12 leaves a margin of ~750 for other states.
TERM_RTOL = 1e-12


def _pinocchio_terms(ps, q, q_dot):
    """(M, h, g) from Pinocchio in gpme's convention: M q_ddot = h + Q with the gravity
    force -g in Q (h = -(C q_dot), g = dV/dq), gpme coordinate order."""
    pm = ps.model
    data = pm.createData()
    q_p, v_p = ps.q_pin(q), ps.to_pin(q_dot)
    m = pin.crba(pm, data, q_p)
    m = np.triu(m) + np.triu(m, 1).T
    m = m[np.ix_(ps.v_index, ps.v_index)]
    g = ps.to_gpme(pin.computeGeneralizedGravity(pm, data, q_p))
    h = -(ps.to_gpme(pin.rnea(pm, data, q_p, v_p, np.zeros(pm.nv))) - g)
    return m, h, g


@pytest.fixture(scope="module")
def pinocchio_sides(tmp_path_factory):
    tree = spatial_tree()
    urdf, _ = write_urdf(tree, tmp_path_factory.mktemp("tree") / "spatial_tree.urdf")
    read = from_urdf(urdf, tree.coordinate_names, [lk.name for lk in tree.links],
                     list(tree.frames))
    return tree, {"built joint by joint": from_gpme(tree), "read from URDF": read}


@pytest.mark.parametrize("side", ["built joint by joint", "read from URDF"])
def test_tree_terms_equal_pinocchio(side, pinocchio_sides, rng):
    tree, sides = pinocchio_sides
    ps = sides[side]
    for _ in range(5):
        q = rng.uniform(-1.5, 1.5, tree.n_coordinates)
        q_dot = rng.uniform(-3, 3, tree.n_coordinates)
        terms = dy.dynamics_terms(tree, 0.0, q, q_dot)
        m_pin, h_pin, g_pin = _pinocchio_terms(ps, q, q_dot)
        for name, ours, theirs in (("M", terms.M, m_pin), ("h", terms.h, h_pin),
                                   ("g", terms.g, g_pin)):
            np.testing.assert_allclose(ours, theirs, rtol=0,
                                       atol=TERM_RTOL * max(1.0, np.abs(theirs).max()),
                                       err_msg=f"{name} against Pinocchio ({side})")


def test_urdf_of_a_tree_names_each_joints_parent(pinocchio_sides):
    tree, sides = pinocchio_sides
    pm = sides["read from URDF"].model
    for k, name in enumerate(tree.coordinate_names):
        parent = int(tree.parents[k])
        expected = "universe" if parent < 0 else tree.coordinate_names[parent]
        assert pm.names[pm.parents[pm.getJointId(name)]] == expected


def test_branches_do_not_couple_in_the_mass_matrix(tree, rng):
    """m_ij = 0 exactly when neither joint moves the other's link (sibling branches, or
    the two roots), and not 0 along a path (the masses are off the joint axes)."""
    q = rng.uniform(-1, 1, tree.n_coordinates)
    m = dy.mass_matrix(tree, q)
    related = tree.moves | tree.moves.T
    assert not m[~related].any()
    assert np.all(np.abs(m[related]) > 1e-6)
    names = tree.coordinate_names
    assert not related[names.index("q1"), names.index("q3")]     # sibling branches
    assert not related[names.index("q0"), names.index("q5")]     # two roots


def test_a_chain_written_with_parent_names_is_the_same_model(arm, rng):
    """Naming every parent explicitly (the link before, WORLD for the first) builds the
    same model as the implicit chain: identical transforms and terms."""
    b = ChainBuilder("explicit")
    for k, (joint, link) in enumerate(zip(arm.joints, arm.links)):
        parent = WORLD if k == 0 else arm.links[k - 1].name
        b.add_joint(joint.name, joint.kind, joint.axis, joint.origin, joint.stiffness,
                    joint.spring_reference, joint.damping, link.name, joint.limits, parent)
        b.add_body(link.inertia)
    explicit = b.build()
    assert explicit.is_chain and arm.is_chain
    q, q_dot = rng.uniform(-1, 1, arm.n_coordinates), rng.uniform(-1, 1, arm.n_coordinates)
    a, e = dy.dynamics_terms(arm, 0.0, q, q_dot), dy.dynamics_terms(explicit, 0.0, q, q_dot)
    for name in ("M", "h", "g"):
        np.testing.assert_array_equal(getattr(a, name), getattr(e, name))


def _free_tree():
    """spatial_tree without springs, dampers or limits (energy is conserved)."""
    tree = spatial_tree()
    changes = {j.name: {"stiffness": 0.0, "damping": 0.0} for j in tree.joints}
    return tree.with_changes(joint_changes=changes)


def _energy_swing(tree, run):
    """J, max - min of kinetic plus potential energy over a run's samples."""
    names = list(tree.coordinate_names)
    energy = [dy.kinetic_energy(tree, row[names].to_numpy(),
                                row[[f"{c}_dot" for c in names]].to_numpy())
              + dy.potential_energy(tree, row[names].to_numpy())
              for _, row in run.iterrows()]
    return max(energy) - min(energy)


def test_free_tree_run_conserves_energy_and_compiled_equals_python():
    """A free, undamped tree swinging under gravity for 0.5 s (3.1 J kinetic energy at the
    start): RK4's energy error must fall with the step at its order 4 (measured ratio 15.9
    from dt = 2e-3 to 1e-3 s, 1.0e-9 J at 1e-3 s).  A wrong coupling term makes the model
    non-conservative, and its drift does not fall with the step; the gate asks for order
    above 3 (ratio > 8) and a drift below 1e-6 of the kinetic energy.  The compiled loop
    equals the Python one to round-off."""
    tree = _free_tree()
    system = ProgrammedMotion(tree)
    n = tree.n_coordinates
    q0 = np.linspace(-0.6, 0.7, n)
    qd0 = np.linspace(2.0, -3.0, n)
    runs = {c: simulate(system, 0.5, q0, qd0, dt=1e-3, output_dt=0.05, compiled=c)
            for c in (True, False)}
    names = list(tree.coordinate_names)
    np.testing.assert_allclose(runs[True][names].to_numpy(), runs[False][names].to_numpy(),
                               rtol=0, atol=1e-10)
    coarse = simulate(system, 0.5, q0, qd0, dt=2e-3, output_dt=0.05)
    fine_swing, coarse_swing = _energy_swing(tree, runs[True]), _energy_swing(tree, coarse)
    kinetic0 = dy.kinetic_energy(tree, q0, qd0)
    assert fine_swing < 1e-6 * kinetic0, f"energy drifts by {fine_swing:.3e} J"
    assert coarse_swing / fine_swing > 8.0, (
        f"energy error {coarse_swing:.3e} J at dt = 2e-3 s, {fine_swing:.3e} J at 1e-3 s: "
        "not converging at RK4's order")


def test_parent_listed_after_the_joint_is_refused():
    b = ChainBuilder("bad_order")
    b.add_joint("a", REVOLUTE, (0, 0, 1))
    b.add_body(cuboid(1.0, (0.1, 0.2, 0.3), com=(0.1, 0, 0)))
    b.add_joint("b", REVOLUTE, (0, 0, 1), parent="c")
    b.add_body(cuboid(1.0, (0.1, 0.2, 0.3), com=(0.1, 0, 0)))
    b.add_joint("c", REVOLUTE, (0, 0, 1), parent=WORLD)
    b.add_body(cuboid(1.0, (0.1, 0.2, 0.3), com=(0.1, 0, 0)))
    with pytest.raises(ModelError, match=r"joint 'b': parent link 'c' is listed after it"):
        b.build()


def test_unknown_parent_and_a_link_called_world_are_refused():
    b = ChainBuilder("bad_names")
    b.add_joint("a", REVOLUTE, (0, 0, 1), link=WORLD)
    b.add_body(cuboid(1.0, (0.1, 0.2, 0.3), com=(0.1, 0, 0)))
    b.add_joint("b", REVOLUTE, (0, 0, 1), parent="nowhere")
    b.add_body(cuboid(1.0, (0.1, 0.2, 0.3), com=(0.1, 0, 0)))
    with pytest.raises(ModelError) as info:
        b.build()
    text = str(info.value)
    assert "parent link 'nowhere' is not a link of the model" in text
    assert "the name is reserved for the world" in text


def test_branch_origin_is_in_the_parent_link_frame(tree):
    """q3's frame at q = 0 is q0's link frame composed with q3's origin (not q2's)."""
    from gpme_core.kinematics import link_transforms
    t = link_transforms(tree, np.zeros(tree.n_coordinates))
    k0, k3 = tree.index("q0"), tree.index("q3")
    np.testing.assert_allclose(t[k3], t[k0] @ tree.joints[k3].origin, atol=1e-15)
    np.testing.assert_allclose(t[tree.index("q5")], tree.joints[tree.index("q5")].origin,
                               atol=1e-15)
    assert spatial_arm().is_chain and not tree.is_chain
    assert tf.translation(0, 0, 0).shape == (4, 4)

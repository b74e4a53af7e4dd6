"""Spring-dampers between points (gpme_core.point_springs): the generalized forces are the
gradients of their energy and Rayleigh function, and bad input is refused by name."""
import numpy as np
import pytest

from conftest import spatial_tree
from gpme_core import dynamics as dy
from gpme_core.errors import ConstraintError, ModelError
from gpme_core.kinematics import chain_kinematics
from gpme_core.model import Model, validate_model
from gpme_core.point_springs import PointSpring, point_spring_energy, spring_state

pytestmark = pytest.mark.both_computation_paths

H = 1e-6      # central differences: truncation ~h^2, round-off ~eps/h: ~1e-9 relative


def _with_springs(*springs):
    tree = spatial_tree()
    model = Model(tree.joints, tree.links, tree.frames, tree.drives, tree.gravity,
                  tree.flexible_links, tree.name, tree.geometry, springs)
    validate_model(model)
    return model


SPRINGS = (PointSpring("between", "E", "F", 300.0, 0.05, 2.0),
           PointSpring("to_world", "F", (0.3, -0.2, 0.1), 120.0, 0.4, 0.5))


def test_elastic_force_is_the_gradient_of_the_spring_energy(rng):
    model = _with_springs(*SPRINGS)
    for _ in range(3):
        q = rng.uniform(-1, 1, model.n_coordinates)
        f = dy.dynamics_terms(model, 0.0, q, np.zeros_like(q)).f - model.stiffness * (
            q - model.spring_reference)
        grad = np.empty_like(q)
        for i in range(q.size):
            e = np.zeros_like(q)
            e[i] = H
            grad[i] = (point_spring_energy(model, chain_kinematics(model, q + e))
                       - point_spring_energy(model, chain_kinematics(model, q - e))) / (2 * H)
        np.testing.assert_allclose(f, grad, rtol=0, atol=1e-7 * max(1.0, np.abs(grad).max()))


def test_damping_force_is_the_gradient_of_the_rayleigh_function(rng):
    model = _with_springs(*SPRINGS)
    q, q_dot = rng.uniform(-1, 1, model.n_coordinates), rng.uniform(-1, 1, model.n_coordinates)
    kin = chain_kinematics(model, q)

    def rayleigh(v):
        return sum(0.5 * s.damping * spring_state(model, s, kin, v)[1] ** 2 for s in SPRINGS)

    d = dy.dynamics_terms(model, 0.0, q, q_dot).d - model.damping * q_dot
    grad = np.array([(rayleigh(q_dot + H * e) - rayleigh(q_dot - H * e)) / (2 * H)
                     for e in np.eye(q.size)])
    np.testing.assert_allclose(d, grad, rtol=0, atol=1e-7 * max(1.0, np.abs(grad).max()))


def test_a_spring_is_in_the_potential_energy():
    model = _with_springs(*SPRINGS)
    q = np.zeros(model.n_coordinates)
    bare = _with_springs()
    extra = dy.spring_potential_energy(model, q) - dy.spring_potential_energy(bare, q)
    assert extra == pytest.approx(point_spring_energy(model, chain_kinematics(model, q)))
    assert extra > 0


def test_bad_springs_are_refused_by_name():
    with pytest.raises(ModelError) as info:
        _with_springs(PointSpring("s", "E", "G", -1.0, 0.1),
                      PointSpring("s", "E", (0.0, float("nan"), 0.0), 1.0, -0.1, 0.0))
    text = str(info.value)
    for words in ("point spring 's': stiffness must be a finite number >= 0",
                  "no frame named 'G'", "anchor must be a frame name or a finite world point",
                  "free_length must be", "point spring names must be unique"):
        assert words in text, words


def test_points_that_meet_are_a_clear_error():
    tree = spatial_tree()
    q = np.zeros(tree.n_coordinates)
    fr = tree.frame("E")
    p = (chain_kinematics(tree, q).T[fr.link_index] @ fr.transform[:, 3])[:3]
    model = _with_springs(PointSpring("at_E", "E", tuple(p), 10.0, 0.1))
    with pytest.raises(ConstraintError, match="point spring 'at_E': its points meet"):
        dy.dynamics_terms(model, 0.0, q, q)


def test_pinocchio_side_computes_the_same_spring_forces(rng, tmp_path):
    """crosscheck.pinocchio's PinocchioSystem.point_spring_forces (its frame placements,
    velocities and Jacobians) equals gpme's -(f + d) of the point springs, built joint by
    joint and read from the URDF and side file gpme writes (round-off of sums of a few
    products: 1e-12 of the largest)."""
    from crosscheck.pinocchio.model import from_gpme, from_urdf
    from gpme_io.urdf import write_urdf
    model = _with_springs(*SPRINGS)
    bare = _with_springs()
    urdf, _ = write_urdf(model, tmp_path / "sprung.urdf")
    from gpme_io.urdf_reader import load_urdf
    assert load_urdf(urdf).model.point_springs == model.point_springs   # via the side file
    sides = (from_gpme(model), from_urdf(urdf, model.coordinate_names,
                                         [lk.name for lk in model.links], list(model.frames)))
    for _ in range(3):
        q, q_dot = rng.uniform(-1, 1, model.n_coordinates), rng.uniform(-1, 1, model.n_coordinates)
        a, b = dy.dynamics_terms(model, 0.0, q, q_dot), dy.dynamics_terms(bare, 0.0, q, q_dot)
        ours = -((a.f - b.f) + (a.d - b.d))
        for ps in sides:
            theirs = ps.point_spring_forces(q, q_dot)
            np.testing.assert_allclose(ours, theirs, rtol=0,
                                       atol=1e-12 * max(1.0, np.abs(theirs).max()))


def test_mujoco_tendons_give_the_same_spring_forces(rng):
    """The MJCF's spatial tendons (stiffness, damping, springlength between the frames'
    sites) give in MuJoCo's qfrc_passive the same forces as gpme's point springs (the
    difference of the model with and without them; measured 1.1e-13 of ~500 N)."""
    import mujoco
    from crosscheck.mujoco.mjcf import mjcf_text
    from crosscheck.mujoco.sim import chain_map, set_state
    model, bare = _with_springs(*SPRINGS), _with_springs()
    engines = [mujoco.MjModel.from_xml_string(mjcf_text(m, 1e-3)) for m in (model, bare)]
    for _ in range(3):
        q, q_dot = rng.uniform(-1, 1, model.n_coordinates), rng.uniform(-1, 1, model.n_coordinates)
        passive = []
        for mj in engines:
            data = mujoco.MjData(mj)
            cmap = chain_map(mj, model)
            set_state(mj, data, cmap, q, q_dot)
            mujoco.mj_forward(mj, data)
            passive.append(data.qfrc_passive[cmap.dof].copy())
        a, b = dy.dynamics_terms(model, 0.0, q, q_dot), dy.dynamics_terms(bare, 0.0, q, q_dot)
        ours = -((a.f - b.f) + (a.d - b.d))
        np.testing.assert_allclose(passive[0] - passive[1], ours, rtol=0,
                                   atol=1e-12 * max(1.0, np.abs(ours).max()))


def test_drake_linear_spring_dampers_give_the_same_forces(rng, tmp_path):
    """Drake's LinearSpringDamper elements, added from the side file's records to the plant
    its parser makes of the written URDF, give the same spring and damper forces as gpme's
    point springs (with the joint springs and dampers in both)."""
    from crosscheck.drake.check import drake_terms
    from crosscheck.drake.model import for_model
    model = _with_springs(*SPRINGS)
    ds = for_model(model, tmp_path)
    context = ds.plant.CreateDefaultContext()
    for _ in range(3):
        q, q_dot = rng.uniform(-1, 1, model.n_coordinates), rng.uniform(-1, 1, model.n_coordinates)
        terms = dy.dynamics_terms(model, 0.0, q, q_dot)
        d = drake_terms(ds, context, 0.0, q, q_dot, np.zeros(model.n_coordinates))
        for ours, theirs in ((-terms.f, d["springs"]), (-terms.d, d["dampers"])):
            np.testing.assert_allclose(ours, theirs, rtol=0,
                                       atol=1e-12 * max(1.0, np.abs(theirs).max()))


def test_exudyn_spring_dampers_give_the_same_forces(rng):
    """Exudyn's ObjectConnectorSpringDamper between MarkerKinematicTreeRigid points (and a
    ground point) in its kinematic tree: its right-hand side f (M q_ddot = f) equals gpme's
    h + Q with the point springs, to round-off."""
    from crosscheck.exudyn.model import mass_and_forces
    model = _with_springs(*SPRINGS)
    for _ in range(3):
        q, q_dot = rng.uniform(-1, 1, model.n_coordinates), rng.uniform(-1, 1, model.n_coordinates)
        terms = dy.dynamics_terms(model, 0.0, q, q_dot)
        _, f_exu = mass_and_forces(model, 0.0, q, q_dot, "lagrange")
        ours = terms.h + terms.Q
        np.testing.assert_allclose(f_exu, ours, rtol=0,
                                   atol=1e-11 * max(1.0, np.abs(ours).max()))


def test_the_stability_estimate_sees_the_point_springs(rng):
    """gpme_core.stability linearises the point springs too: their line stiffness is the
    Hessian of their energy (finite differences) where the springs sit at their free length,
    and a stiff spring shortens the suggested RK4 step."""
    from gpme_core.gpme import ProgrammedMotion
    from gpme_core.point_springs import point_spring_matrices
    from gpme_core.stability import rk4_step
    q = rng.uniform(-1, 1, 7)
    probe = _with_springs(*SPRINGS)
    kin = chain_kinematics(probe, q)
    relaxed = [PointSpring(s.name, s.frame, s.anchor, s.stiffness,
                           spring_state(probe, s, kin, np.zeros(7))[0]) for s in SPRINGS]
    model = _with_springs(*relaxed)
    k_mat, _ = point_spring_matrices(model, chain_kinematics(model, q))
    h = 1e-4

    def energy(x):
        return point_spring_energy(model, chain_kinematics(model, x))
    hess = np.empty((q.size, q.size))
    for i in range(q.size):
        for j in range(q.size):
            ei, ej = np.eye(q.size)[i] * h, np.eye(q.size)[j] * h
            hess[i, j] = (energy(q + ei + ej) - energy(q + ei - ej) - energy(q - ei + ej)
                          + energy(q - ei - ej)) / (4 * h * h)
    # second differences: truncation ~h^2, round-off ~eps E / h^2 ~ 1e-8 of the entries
    np.testing.assert_allclose(k_mat, hess, rtol=0, atol=1e-5 * np.abs(hess).max())
    stiff = _with_springs(PointSpring("stiff", "E", "F", 3e6, 0.05))
    q0 = np.zeros(model.n_coordinates)
    assert rk4_step(ProgrammedMotion(stiff), q0) < 0.2 * rk4_step(ProgrammedMotion(_with_springs()), q0)

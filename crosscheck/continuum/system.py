"""The continuum model in Exudyn: rigid bodies, generic joints, geometrically exact beams.

Built from a :class:`~crosscheck.continuum.layout.ContinuumLayout` (model data only):

* each rigid part a NodeRigidBodyEP + ObjectRigidBody whose node frame is the gpme link
  frame, placed at the start by forward kinematics written here (link k:
  T_k = T_parent origin_k motion_k(q_k), every sde angle 0, i.e. the beams straight);
  inertia given about the node, [J_xx, J_yy, J_zz, J_yz, J_xz, J_xy];
* each kept joint an ObjectJointGeneric between a marker on the parent (at the joint
  origin) and the child's node frame, both turned by R_a (R_a e_z = the joint axis) so the
  joint's free axis is the generic joint's local z: rotation z free for a revolute,
  translation z free for a prismatic joint; a joint programme q_k = f(t) constrains that
  axis too, with offset f(t) and its rate as the joint's offset user functions;
* joint springs and dampers: ObjectConnectorTorsionalSpringDamper (revolute, offset the
  spring reference) or ObjectConnectorRigidBodySpringDamper with only the local z
  translation entries (prismatic); drives: a body-fixed torque (force) tau(t) a on the
  child and -tau(t) a on the parent (collinear, at the joint origin, for a force);
* each beam N ObjectBeamGeometricallyExact elements on N + 1 NodeRigidBodyEP nodes along
  the beam frame's x axis, clamped to the carrying body at B and to the tip body at the
  tip frame by fully constrained generic joints;
* gravity: LoadMassProportional on every body and beam element;
* a point constraint phi(p, t) = 0 on a model frame: a massless NodePoint held at the
  frame's origin by an ObjectJointSpherical, and phi with its gradient (SymPy, from
  crosscheck.constraint_reference) as an ObjectConnectorCoordinateVector on that point's
  coordinates, so the constraint sees the frame's world position and nothing else.

Sign of the multipliers: Exudyn's AE coordinates lambda_exu enter as M q_ddot + C_q^T
lambda_exu = f; gpme's lambda = -lambda_exu for the same Phi rows (as in
crosscheck.exudyn.runs).  A joint programme's multiplier is the generic joint's AE
coordinate along its free axis (a torque in N m or a force in N), the constraint's load on
the child, which is gpme's lambda itself (crosscheck.continuum.runs).
"""
from dataclasses import dataclass, field
from typing import Mapping, Optional

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (LoadForceVector, LoadMassProportional, LoadTorqueVector,
                                  MarkerBodyMass, MarkerBodyRigid,
                                  MarkerNodeCoordinates, MarkerNodePosition, MarkerNodeRigid,
                                  NodePoint, NodePointGround, NodeRigidBodyEP,
                                  ObjectBeamGeometricallyExact,
                                  ObjectConnectorCoordinateVector,
                                  ObjectConnectorRigidBodySpringDamper,
                                  ObjectConnectorTorsionalSpringDamper, ObjectGround,
                                  ObjectJointGeneric, ObjectJointSpherical, ObjectRigidBody)
from exudyn.rigidBodyUtilities import (AngularVelocity2EulerParameters_t,
                                       RotationMatrix2EulerParameters)

from gpme_core import pair_constraints as pc
from gpme_core.errors import ModelError

from ..constraint_reference import ReferenceJointProgramme, reference_constraints
from .layout import ContinuumLayout
from .section import continuum_section

REVOLUTE_FREE = [1, 1, 1, 1, 1, 0]       # generic joint: rotation about local z free
PRISMATIC_FREE = [1, 1, 0, 1, 1, 1]      # translation along local z free
ALL_FIXED = [1, 1, 1, 1, 1, 1]


def axis_to_z(axis) -> np.ndarray:
    """(3, 3) rotation R with R e_z = unit ``axis`` (the shortest one; a half turn about x
    for axis = -e_z)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    z = np.array([0.0, 0.0, 1.0])
    w = np.cross(z, a)
    s, c = np.linalg.norm(w), float(z @ a)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    k = w / s
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * kx + (1.0 - c) * kx @ kx


def _motion(kind, axis, q) -> np.ndarray:
    t = np.eye(4)
    a = np.asarray(axis, dtype=float)
    if kind == "revolute":
        kx = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        t[:3, :3] = np.eye(3) + np.sin(q) * kx + (1.0 - np.cos(q)) * kx @ kx
    else:
        t[:3, 3] = a * q
    return t


def link_states(model, q, q_dot) -> tuple:
    """(poses (n, 4, 4), origin velocities (n, 3) m/s, angular velocities (n, 3) rad/s), all
    in the world frame, of the model's links at q, q_dot (forward kinematics written here:
    T_k = T_parent origin_k motion_k(q_k); v_k = v_p + w_p x (p_k - p_p) + a_k q_dot_k
    for a prismatic joint; w_k = w_p + a_k q_dot_k for a revolute one, a_k the world axis)."""
    n = model.n_coordinates
    poses, vel, omega = np.empty((n, 4, 4)), np.zeros((n, 3)), np.zeros((n, 3))
    for k, joint in enumerate(model.joints):
        p = int(model.parents[k])
        t_p = np.eye(4) if p < 0 else poses[p]
        v_p, w_p = (np.zeros(3), np.zeros(3)) if p < 0 else (vel[p], omega[p])
        poses[k] = t_p @ np.asarray(joint.origin, dtype=float) @ _motion(joint.kind, joint.axis,
                                                                       q[k])
        a_world = poses[k][:3, :3] @ np.asarray(joint.axis, dtype=float)
        vel[k] = v_p + np.cross(w_p, poses[k][:3, 3] - t_p[:3, 3])
        omega[k] = w_p.copy()
        if joint.kind == "revolute":
            omega[k] += a_world * q_dot[k]
        else:
            vel[k] += a_world * q_dot[k]
    return poses, vel, omega


@dataclass
class ContinuumSystem:
    """The Exudyn items of a continuum model (mbs before or after Assemble).

    body_nodes {link: node}; beam_nodes {beam name: [node, ...] root to tip};
    joint_frames {joint index: (parent link or -1, (4, 4) joint frame in the parent,
    child link, (3, 3) R_a)} for measuring joint coordinates; constraint_objects
    [(object index, [names])]; joint_programmes {constraint name: (object index, axis
    index of the offset)}; notes: what was built, one line each.
    """

    mbs: object
    layout: ContinuumLayout
    elements: Mapping[str, int]
    body_nodes: dict = field(default_factory=dict)
    bodies: dict = field(default_factory=dict)
    beam_nodes: dict = field(default_factory=dict)
    joint_frames: dict = field(default_factory=dict)
    constraint_objects: list = field(default_factory=list)
    joint_programmes: dict = field(default_factory=dict)
    constraint_names: tuple = ()
    notes: list = field(default_factory=list)
    euler_bernoulli: bool = False


def _ep_node(mbs, pose, v, w) -> int:
    ep = np.asarray(RotationMatrix2EulerParameters(pose[:3, :3]), dtype=float)
    ep_t = np.asarray(AngularVelocity2EulerParameters_t(w, ep), dtype=float)
    return mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[*pose[:3, 3], *ep],
                                       initialVelocities=[*v, *ep_t]))


def _inertia6(part) -> list:
    """[J_xx, J_yy, J_zz, J_yz, J_xz, J_xy] about the link origin (kg m^2)."""
    c = part.com
    j = part.inertia + part.mass * (float(c @ c) * np.eye(3) - np.outer(c, c))
    return [j[0, 0], j[1, 1], j[2, 2], j[1, 2], j[0, 2], j[0, 1]]


def _split_constraints(specs, model, layout):
    """({joint index: ReferenceJointProgramme}, {frame: [ReferencePointConstraint]}, names)."""
    joint_refs, point_refs = {}, {}
    for spec in specs:
        if isinstance(spec, pc.PairConstraint):
            raise ModelError(f"constraint {spec.name!r}: two-frame constraints are not realised by "
                             "the continuum model yet")
    refs = reference_constraints(specs, model.coordinate_names)
    for ref in refs:
        if isinstance(ref, ReferenceJointProgramme):
            if ref.index not in layout.joints:
                raise ModelError(f"constraint {ref.name!r} programmes {ref.coordinate!r}, a "
                                 "coordinate of a flexible link, which has no continuum "
                                 "counterpart")
            joint_refs[ref.index] = ref
        else:
            point_refs.setdefault(ref.frame, []).append(ref)
    return joint_refs, point_refs, tuple(r.name for r in refs)


def build_system(model, layout: ContinuumLayout, q0, q_dot0, specs=(), elements=8,
                 gravity: Optional[np.ndarray] = None,
                 euler_bernoulli: bool = False) -> ContinuumSystem:
    """Add the continuum model of gpme ``model`` to a new Exudyn MainSystem.

    q0, q_dot0 (n,): the start (rad, m; rad/s, m/s), the sde entries ignored (the beams
    start straight and moving rigidly with their carrying body); specs: the scenario's
    constraint specs (joint programmes and point constraints); elements: beam elements per
    beam (int, or {beam name: int}); gravity (3,) m/s^2, default the model's.
    Returns a :class:`ContinuumSystem` whose mbs is not yet assembled.
    """
    if model.point_springs:
        raise ModelError("point springs are not realised by the continuum model yet")
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    mbs.variables["systemContainer"] = sc            # keep the container alive with mbs
    q = np.array(q0, dtype=float)
    q_dot = np.array(q_dot0, dtype=float)
    for b in layout.beams:
        q[list(b.sde_joints)] = 0.0
        q_dot[list(b.sde_joints)] = 0.0
    per_beam = {b.name: int(elements[b.name] if isinstance(elements, Mapping) else elements)
                for b in layout.beams}
    out = ContinuumSystem(mbs, layout, per_beam)
    out.euler_bernoulli = bool(euler_bernoulli)
    poses, vel, omega = link_states(model, q, q_dot)
    g = np.asarray(model.gravity if gravity is None else gravity, dtype=float)
    ground = mbs.AddObject(ObjectGround())
    for k, part in layout.bodies.items():
        node = _ep_node(mbs, poses[k], vel[k], omega[k])
        out.body_nodes[k] = node
        out.bodies[k] = mbs.AddObject(ObjectRigidBody(nodeNumber=node, mass=part.mass,
                                                      inertia=_inertia6(part),
                                                      centerOfMass=part.com.tolist()))
        if part.mass > 0.0 and np.any(g):
            mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(
                MarkerBodyMass(bodyNumber=out.bodies[k])), loadVector=g.tolist()))

    def rigid_marker(link, local):
        if link < 0:
            return mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=list(local)))
        return mbs.AddMarker(MarkerBodyRigid(bodyNumber=out.bodies[link],
                                             localPosition=list(local)))

    for beam in layout.beams:
        _add_beam(mbs, out, beam, poses, vel, omega, g, rigid_marker)
    joint_refs, point_refs, out.constraint_names = _split_constraints(specs, model, layout)
    for k in layout.joints:
        _add_joint(mbs, out, model, k, rigid_marker, joint_refs.get(k))
    for frame, refs in point_refs.items():
        _add_point_constraints(mbs, out, model, layout, frame, refs, poses, rigid_marker)
    out.notes.append(f"{len(layout.bodies)} rigid bodies (NodeRigidBodyEP), {len(layout.joints)} "
                     "generic joints, " + ", ".join(f"beam {nm}: {ne} geometrically exact elements"
                                                    for nm, ne in per_beam.items()))
    return out


def exudyn_section(cs, damping: bool = True):
    """Exudyn's BeamSection of a crosscheck.continuum.section.ContinuumSection: its diagonal
    stiffness, damping (unless ``damping`` is False) and rotary inertia, and its mass per
    length (units and strain order in crosscheck.continuum.section)."""
    section = exu.BeamSection()
    section.stiffnessMatrix = np.diag(cs.stiffness)
    if damping:
        section.dampingMatrix = np.diag(cs.damping)
    section.massPerLength = cs.mass_per_length
    section.inertia = np.diag(cs.rotary_inertia)
    return section


def _add_beam(mbs, out, beam, poses, vel, omega, g, rigid_marker):
    n_el = out.elements[beam.name]
    if n_el < 1:
        raise ModelError(f"beam {beam.name!r}: at least one element, got {n_el}")
    cs = continuum_section(beam.beam, out.euler_bernoulli)
    section = exudyn_section(cs)
    c = beam.carrying_link
    root = poses[c] @ beam.root_frame
    length = beam.beam.length
    nodes = []
    for i in range(n_el + 1):
        pose = root.copy()
        pose[:3, 3] = root[:3, 3] + root[:3, 0] * length * i / n_el
        v = vel[c] + np.cross(omega[c], pose[:3, 3] - poses[c][:3, 3])
        nodes.append(_ep_node(mbs, pose, v, omega[c]))
    elements = [mbs.AddObject(ObjectBeamGeometricallyExact(
        nodeNumbers=[nodes[i], nodes[i + 1]], length=length / n_el, sectionData=section))
        for i in range(n_el)]
    if any(cs.damping):
        _add_material_damping(mbs, nodes, cs, length / n_el)
    if np.any(g):
        for e in elements:
            mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(
                MarkerBodyMass(bodyNumber=e)), loadVector=g.tolist()))
    mbs.AddObject(ObjectJointGeneric(
        markerNumbers=[rigid_marker(c, beam.root_frame[:3, 3]),
                       mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[0]))],
        constrainedAxes=ALL_FIXED, rotationMarker0=beam.root_frame[:3, :3].tolist()))
    mbs.AddObject(ObjectJointGeneric(
        markerNumbers=[mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[-1])),
                       rigid_marker(beam.tip_link, beam.tip_frame[:3, 3])],
        constrainedAxes=ALL_FIXED, rotationMarker1=beam.tip_frame[:3, :3].tolist()))
    out.beam_nodes[beam.name] = nodes
    out.notes.append(f"beam {beam.name}: L = {length:g} m, {n_el} elements, EA = "
                     f"{cs.stiffness[0]:.4g} N, kGA = {cs.stiffness[1]:.4g} N (k = "
                     f"{cs.shear_coefficient:.4f}, {cs.shape} section), GJ = {cs.stiffness[3]:.4g}, "
                     f"EI_y = {cs.stiffness[4]:.4g}, EI_z = {cs.stiffness[5]:.4g} N m^2, rho A = "
                     f"{cs.mass_per_length:.4g} kg/m")


def _add_material_damping(mbs, nodes, cs, element_length):
    """Kelvin-Voigt damping of a beam as one damper per element between its two nodes.

    Exudyn 1.13's ObjectBeamGeometricallyExact ignores its section's damping matrix
    (measured: a cantilever's free vibration does not decay with any damping matrix,
    tests/test_continuum.py), so the section damping is put on the element's relative
    motion instead: an ObjectConnectorRigidBodySpringDamper between node i and node i + 1
    (no stiffness) with damping eta_E A / l_e on the relative velocity along the element's
    x axis and eta_G J / l_e, eta_E I_y / l_e, eta_E I_z / l_e on the relative angular
    velocity about x, y, z of node i's frame: the element's mean strain rates times its
    section damping, integrated over its length l_e.  The shear damping is left out (the
    relative lateral velocity also holds the bending rotation); as the mesh is refined this
    is the continuum's Kelvin-Voigt damping, the same law RFEM discretises at its sdes.
    """
    d = np.zeros((6, 6))
    d[0, 0] = cs.damping[0] / element_length
    d[3, 3], d[4, 4], d[5, 5] = (v / element_length for v in cs.damping[3:])
    zero = np.zeros((6, 6)).tolist()
    for a, b in zip(nodes[:-1], nodes[1:]):
        mbs.AddObject(ObjectConnectorRigidBodySpringDamper(
            markerNumbers=[mbs.AddMarker(MarkerNodeRigid(nodeNumber=a)),
                           mbs.AddMarker(MarkerNodeRigid(nodeNumber=b))],
            stiffness=zero, damping=d.tolist()))


def _add_joint(mbs, out, model, k, rigid_marker, programme):
    joint = model.joints[k]
    parent = int(model.parents[k])
    origin = np.asarray(joint.origin, dtype=float)
    r_a = axis_to_z(joint.axis)
    revolute = joint.kind == "revolute"
    m0 = rigid_marker(parent, origin[:3, 3])
    m1 = rigid_marker(k, (0.0, 0.0, 0.0))
    rot0, rot1 = (origin[:3, :3] @ r_a).tolist(), r_a.tolist()
    free = 5 if revolute else 2
    kwargs = {}
    if programme is not None:
        def offset(mbs_, t, item, off, f=programme._f, i=free):
            v = [0.0] * 6
            v[i] = float(f(t)[0])
            return v

        def offset_t(mbs_, t, item, off, f=programme._f, i=free):
            v = [0.0] * 6
            v[i] = float(f(t)[1])
            return v
        kwargs = dict(offsetUserFunction=offset, offsetUserFunction_t=offset_t)
    obj = mbs.AddObject(ObjectJointGeneric(
        markerNumbers=[m0, m1], constrainedAxes=ALL_FIXED if programme else
        (REVOLUTE_FREE if revolute else PRISMATIC_FREE), rotationMarker0=rot0,
        rotationMarker1=rot1, **kwargs))
    out.joint_frames[k] = (parent, origin, k, r_a, obj)
    if programme is not None:
        out.joint_programmes[programme.name] = (obj, free)
    if joint.stiffness != 0.0 or joint.damping != 0.0:
        if revolute:
            mbs.AddObject(ObjectConnectorTorsionalSpringDamper(
                markerNumbers=[m0, m1], stiffness=float(joint.stiffness),
                damping=float(joint.damping), offset=float(joint.spring_reference),
                rotationMarker0=rot0, rotationMarker1=rot1))
        else:
            k6, d6, off = np.zeros((6, 6)), np.zeros((6, 6)), [0.0] * 6
            k6[2, 2], d6[2, 2], off[2] = joint.stiffness, joint.damping, joint.spring_reference
            mbs.AddObject(ObjectConnectorRigidBodySpringDamper(
                markerNumbers=[m0, m1], stiffness=k6.tolist(), damping=d6.tolist(),
                offset=off, rotationMarker0=rot0, rotationMarker1=rot1))
    for drive in model.drives:
        if model.index(drive.joint) != k:
            continue
        a_child = np.asarray(joint.axis, dtype=float)
        a_parent = origin[:3, :3] @ a_child
        load = LoadTorqueVector if revolute else LoadForceVector
        for marker, axis, sign in ((m1, a_child, 1.0), (m0, a_parent, -1.0)):
            if marker is m0 and parent < 0:
                continue
            mbs.AddLoad(load(markerNumber=marker, bodyFixed=True, loadVector=[0.0, 0.0, 0.0],
                             loadVectorUserFunction=lambda mbs_, t, lv, f=drive.function,
                             a=axis, s=sign: (s * float(f(t)) * a).tolist()))


def _add_point_constraints(mbs, out, model, layout, frame, refs, poses, rigid_marker):
    fr = model.frame(frame)
    link = int(fr.link_index)
    if link not in layout.bodies:
        raise ModelError(f"constraint frame {frame!r} lies inside a flexible link; the continuum "
                         "model constrains frames of rigid parts (a beam's root or tip body)")
    local = np.asarray(fr.transform, dtype=float)[:3, 3]
    p0 = poses[link] @ np.append(local, 1.0)
    point = mbs.AddNode(NodePoint(referenceCoordinates=p0[:3].tolist()))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[rigid_marker(link, local),
                                                      mbs.AddMarker(MarkerNodePosition(
                                                          nodeNumber=point))]))
    ground = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=mbs.AddNode(
        NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))))
    m = len(refs)
    eye = np.eye(3)
    zero = np.zeros(3)

    def rows(t, q, q_t):            # Exudyn hands over reference + displacement: p itself
        p = np.asarray(q)[:3]
        v = np.asarray(q_t)[:3]
        vals = [r.evaluate(t, p, v, eye, zero) for r in refs]
        return vals

    def constraint(mbs_, t, item, q, q_t, velocity_level):
        return [(r[1] if velocity_level else r[0]) for r in rows(t, q, q_t)]

    def jacobian(mbs_, t, item, q, q_t, velocity_level):
        return np.array([r[2] for r in rows(t, q, q_t)])

    obj = mbs.AddObject(ObjectConnectorCoordinateVector(
        markerNumbers=[mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=point)), ground],
        scalingMarker0=np.zeros((m, 3)), scalingMarker1=np.zeros((m, 3)),
        constraintUserFunction=constraint, jacobianUserFunction=jacobian))
    out.constraint_objects.append((obj, [r.name for r in refs]))

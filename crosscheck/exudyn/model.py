"""A gpme model as Exudyn builds it: one ObjectKinematicTree, springs, dampers and drives.

Only model DATA is taken from the gpme Model (joint origins and axes, link mass, centre of
mass and inertia about it in the link frame, stiffness, spring reference, damping, gravity,
the drives' time functions); the kinematics and dynamics are Exudyn's.

Exudyn's kinematic tree (ObjectKinematicTree, minimal coordinates in one NodeGenericODE2)
places joint frame i as ``J_i = J_parent @ [R_i o_i; 0 1] @ motion_i(q_i)``, with the
motion a rotation about / translation along a *coordinate* axis of J_i (JointType
RevoluteX/Y/Z, PrismaticX/Y/Z), and takes the link's mass, COM and inertia about the COM
in J_i.  gpme's link frame is ``L_k = L_parent @ origin_k @ motion_k(q_k)`` about the unit
axis a_k of the joint frame.  Where a_k is a coordinate axis, J_k = L_k.  Otherwise a
constant rotation R_a with R_a e_c = a_k (e_c the coordinate axis closest to a_k) makes
it one: motion about a_k = R_a motion_c(q) R_a^T, hence

    J_k = J_parent @ (X_parent @ origin_k @ R_a) @ motion_c(q_k),   L_k = J_k @ X_k,
    X_k = R_a^T (as a 4x4 rotation; L coordinates -> J coordinates: r_J = X_k r_L),

so the tree's joint transform is X_parent origin_k R_a, the link's COM is R_a^T c and its
inertia R_a^T I_C R_a, and the children of link k see X_k in front of their origins
(X = identity for aligned joints).  The coordinates q are the same in both engines.

Springs and dampers are Exudyn's own connectors: one ObjectConnectorCoordinateSpringDamper
per joint with stiffness or damping, between a ground coordinate (marker 0) and the tree
coordinate q_k (marker 1), offset = q_ref.  Exudyn's scalar spring-damper acts on the
relative coordinate q_k - 0 with f = K (q_k - offset) + D q_dot_k and applies -f to
marker 1, i.e. the generalized force on q_k is -K_k (q_k - q_ref_k) - D_k q_dot_k, gpme's
"lagrange" damping (tests/test_exudyn.py checks the sign and the offset on one joint).
Drives are LoadCoordinate loads on q_k with a load user function returning the drive's
force (N) or torque (N m) at Exudyn's time.  Gravity is the tree's own ``gravity``.
"""
import time
from dataclasses import dataclass
from typing import Mapping

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (LoadCoordinate, MarkerBodyPosition, MarkerKinematicTreeRigid,
                                  MarkerNodeCoordinate, MarkerNodeCoordinates, NodeGenericODE2,
                                  NodePointGround, ObjectConnectorCoordinateSpringDamper,
                                  ObjectConnectorSpringDamper, ObjectGround,
                                  ObjectKinematicTree)
from numpy.typing import NDArray

from gpme_core.errors import ModelError

_TYPES = {("revolute", 0): exu.JointType.RevoluteX, ("revolute", 1): exu.JointType.RevoluteY,
          ("revolute", 2): exu.JointType.RevoluteZ, ("prismatic", 0): exu.JointType.PrismaticX,
          ("prismatic", 1): exu.JointType.PrismaticY, ("prismatic", 2): exu.JointType.PrismaticZ}
AXIS_TOL = 1e-12          # |a - e_c| below which an axis counts as the coordinate axis e_c
DAMPING_FORMS = ("lagrange",)


def axis_rotation(axis) -> tuple:
    """(c, R_a): the coordinate axis index c (0 x, 1 y, 2 z) closest to the unit ``axis``
    (3,) and the rotation (3, 3) R_a with R_a e_c = axis (the identity when axis = e_c;
    the shortest rotation otherwise, by pi about another coordinate axis for axis = -e_c)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    c = int(np.argmax(np.abs(a)))
    e = np.zeros(3)
    e[c] = 1.0
    if np.abs(a - e).max() <= AXIS_TOL:
        return c, np.eye(3)
    w = np.cross(e, a)
    s, cos = np.linalg.norm(w), float(e @ a)
    if s < 1e-12:                                  # a = -e_c: half turn about e_(c+1)
        k = np.zeros(3)
        k[(c + 1) % 3] = 1.0
        return c, 2.0 * np.outer(k, k) - np.eye(3)
    k = w / s
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return c, np.eye(3) + s * kx + (1.0 - cos) * kx @ kx      # Rodrigues


@dataclass(frozen=True)
class TreeLayout:
    """The ObjectKinematicTree data of a gpme chain (pure numbers, no Exudyn objects).

    joint_types     : (n,) exu.JointType per joint
    axis_index      : (n,) coordinate axis (0, 1, 2) of each Exudyn joint
    axis_rotations  : (n, 3, 3) R_a of each joint (identity where the axis is aligned)
    joint_rotations : (n, 3, 3) rotation of J_parent -> J_k at q = 0
    joint_offsets   : (n, 3) m, origin of J_k in J_parent
    link_masses     : (n,) kg;  link_coms : (n, 3) m in J_k
    link_inertias   : (n, 3, 3) kg m^2 about the COM, J_k axes
    unaligned       : names of the joints whose axis was rotated onto a coordinate axis
    """

    joint_types: tuple
    axis_index: NDArray[np.int64]
    axis_rotations: NDArray[np.float64]
    joint_rotations: NDArray[np.float64]
    joint_offsets: NDArray[np.float64]
    link_masses: NDArray[np.float64]
    link_coms: NDArray[np.float64]
    link_inertias: NDArray[np.float64]
    unaligned: tuple


def tree_layout(model) -> TreeLayout:
    """:class:`TreeLayout` of the gpme ``model`` (a chain or a tree: the parent of joint k
    is ``model.parents[k]``, -1 the world, as Exudyn's linkParents)."""
    types, idx, rots, jr, jo, masses, coms, inertias, unaligned = [], [], [], [], [], [], [], [], []
    for k, (joint, link) in enumerate(zip(model.joints, model.links)):
        parent = int(model.parents[k])
        # X_parent: the parent link frame in the parent's joint frame (R_a^T of its axis)
        x_parent = np.eye(3) if parent < 0 else rots[parent].T
        c, r_a = axis_rotation(joint.axis)
        if joint.kind not in ("revolute", "prismatic"):
            raise ModelError(f"joint {joint.name!r}: kind {joint.kind!r}; Exudyn's tree takes "
                             "revolute or prismatic joints")
        if not np.allclose(r_a, np.eye(3), rtol=0, atol=0):
            unaligned.append(joint.name)
        origin = np.asarray(joint.origin, dtype=float)
        types.append(_TYPES[(joint.kind, c)])
        idx.append(c)
        rots.append(r_a)
        jr.append(x_parent @ origin[:3, :3] @ r_a)
        jo.append(x_parent @ origin[:3, 3])
        if link.inertia is None:
            masses.append(0.0)
            coms.append(np.zeros(3))
            inertias.append(np.zeros((3, 3)))
        else:
            masses.append(float(link.inertia.mass))
            coms.append(r_a.T @ link.inertia.com_array)
            inertias.append(r_a.T @ link.inertia.inertia_array @ r_a)
    arr = lambda v: np.array(v, dtype=float)
    return TreeLayout(tuple(types), np.array(idx, dtype=int), arr(rots), arr(jr), arr(jo),
                      arr(masses), arr(coms), arr(inertias), tuple(unaligned))


@dataclass(frozen=True)
class ExudynTree:
    """The items of a gpme model added to an Exudyn MainSystem.

    mbs            : exudyn MainSystem (mutable; items are added before Assemble)
    node           : NodeGenericODE2 index of the n tree coordinates (gpme order)
    tree           : ObjectKinematicTree index
    node_marker    : MarkerNodeCoordinates of the tree node (all n coordinates)
    ground_marker  : MarkerNodeCoordinates of a ground point node (3 coordinates, all 0)
    n              : coordinates
    coordinate_names : gpme's, same order
    springs        : {coordinate: ObjectConnectorCoordinateSpringDamper index}
    drives         : {coordinate: LoadCoordinate index}
    layout         : TreeLayout
    notes          : what the Exudyn side takes from where, one line each
    """

    mbs: object
    node: int
    tree: int
    node_marker: int
    ground_marker: int
    n: int
    coordinate_names: tuple
    springs: Mapping[str, int]
    drives: Mapping[str, int]
    layout: TreeLayout
    notes: tuple


def add_tree(mbs, model, q0, q_dot0, damping_form: str = "lagrange") -> ExudynTree:
    """Add the gpme ``model`` to the Exudyn MainSystem ``mbs``, starting at q0, q_dot0 (n,)
    (rad, m; rad/s, m/s).

    damping_form: the gpme system's (ProgrammedMotion.damping_form); only "lagrange" (the
    damper force -D q_dot once, what Lagrange's equations give) has an Exudyn counterpart:
    "paper-eq7" (the damper force twice, the paper's misprint kept for demonstration)
    raises ModelError.
    """
    if damping_form not in DAMPING_FORMS:
        raise ModelError(f"damping_form {damping_form!r}: Exudyn's spring-dampers realise "
                         f"only {DAMPING_FORMS} (-D q_dot once); 'paper-eq7' doubles the damper "
                         "force, which no Exudyn connector does")
    n = model.n_coordinates
    q0, q_dot0 = (np.asarray(x, dtype=float) for x in (q0, q_dot0))
    if q0.shape != (n,) or q_dot0.shape != (n,):
        raise ModelError(f"q0 and q_dot0 must have shape ({n},), got {q0.shape}, {q_dot0.shape}")
    lay = tree_layout(model)
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n,
                                       initialCoordinates=q0.tolist(),
                                       initialCoordinates_t=q_dot0.tolist(),
                                       numberOfODE2Coordinates=n))
    tree = mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=list(lay.joint_types),
        linkParents=[int(p) for p in model.parents],
        jointTransformations=exu.Matrix3DList(list(lay.joint_rotations)),
        jointOffsets=exu.Vector3DList(list(lay.joint_offsets)),
        linkInertiasCOM=exu.Matrix3DList(list(lay.link_inertias)),
        linkCOMs=exu.Vector3DList(list(lay.link_coms)), linkMasses=lay.link_masses.tolist(),
        baseOffset=[0.0, 0.0, 0.0], gravity=np.asarray(model.gravity, float).tolist()))
    node_marker = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=node))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    ground_marker = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=ground))
    ground_coordinate = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    springs, drives, coordinate_markers = {}, {}, {}

    def coordinate_marker(k):
        if k not in coordinate_markers:
            coordinate_markers[k] = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node,
                                                                       coordinate=k))
        return coordinate_markers[k]

    for k, joint in enumerate(model.joints):
        if joint.stiffness == 0.0 and joint.damping == 0.0:
            continue
        springs[joint.name] = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
            markerNumbers=[ground_coordinate, coordinate_marker(k)],
            stiffness=float(joint.stiffness), damping=float(joint.damping),
            offset=float(joint.spring_reference)))
    for drive in model.drives:
        k = model.index(drive.joint)
        function = drive.function
        drives[drive.joint] = mbs.AddLoad(LoadCoordinate(
            markerNumber=coordinate_marker(k), load=0.0,
            loadUserFunction=lambda mbs_, t, load, f=function: float(f(t))))
    for spring in model.point_springs:
        springs[spring.name] = mbs.AddObject(ObjectConnectorSpringDamper(
            markerNumbers=[_point_marker(mbs, model, tree, lay, spring.frame),
                           _point_marker(mbs, model, tree, lay, spring.anchor)],
            referenceLength=float(spring.free_length), stiffness=float(spring.stiffness),
            damping=float(spring.damping)))
    notes = [f"ObjectKinematicTree with {n} joints from the gpme model's joint origins, axes "
             "and link inertias (data only)"]
    if model.point_springs:
        notes.append(f"{len(model.point_springs)} ObjectConnectorSpringDamper (point springs) "
                     "between MarkerKinematicTreeRigid points of the tree and ground points")
    if lay.unaligned:
        notes.append("joint axes rotated onto a coordinate axis (inertia, COM and the "
                     "children's transforms carried along): " + ", ".join(lay.unaligned))
    notes.append(f"{len(springs)} ObjectConnectorCoordinateSpringDamper (springs, dampers), "
                 f"{len(drives)} LoadCoordinate drive(s) with load user functions, gravity "
                 f"{np.asarray(model.gravity, float).tolist()} m/s^2 as the tree's own")
    return ExudynTree(mbs, node, tree, node_marker, ground_marker, n,
                      tuple(model.coordinate_names), springs, drives, lay, tuple(notes))


def _point_marker(mbs, model, tree, lay, end):
    """Exudyn marker of one end of a point spring: the origin of a gpme frame on the tree
    (its link's MarkerKinematicTreeRigid; the gpme link frame is Exudyn's joint frame
    turned by the axis rotation R_a, so the point is R_a^T r there), or a world point
    (a MarkerBodyPosition on an ObjectGround)."""
    if isinstance(end, str):
        fr = model.frame(end)
        local = lay.axis_rotations[fr.link_index].T @ fr.transform[:3, 3]
        return mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=tree,
                                                      linkNumber=int(fr.link_index),
                                                      localPosition=local.tolist()))
    ground = mbs.AddObject(ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
    return mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground,
                                            localPosition=[float(v) for v in end]))


def quiet_settings(end_time: float = 1.0, steps: int = 1):
    """exu.SimulationSettings that print nothing and write no files (solution, sensors,
    solver information)."""
    s = exu.SimulationSettings()
    s.timeIntegration.verboseMode = 0
    s.timeIntegration.verboseModeFile = 0
    s.solution.file.write = False
    s.show.statistics = False
    s.show.computationTime = False
    s.show.globalTimers = False
    s.timeIntegration.endTime = float(end_time)
    s.timeIntegration.numberOfSteps = int(steps)
    return s


def solve_implicit(mbs, settings) -> tuple:
    """Run Exudyn's implicit (generalized-alpha) solver on the assembled ``mbs``: (ok,
    message, wall time s, solver).  Exudyn's own errors and those raised inside user
    functions become ok = False with their message, for the caller's SimulationError."""
    sim = exu.MainSolverImplicitSecondOrder()
    start = time.perf_counter()
    try:
        ok = sim.SolveSystem(mbs, settings)
        message = "" if ok else sim.GetErrorString()
    except Exception as exc:           # Exudyn's own errors and those of the user functions
        ok, message = False, f"{type(exc).__name__}: {exc}"
    return ok, message, time.perf_counter() - start, sim


def mass_and_forces(model, t: float, q, q_dot, damping_form: str = "lagrange"):
    """(M (n, n), f (n,)) of Exudyn's system at (t, q, q_dot): M the system mass matrix
    (kg, kg m, kg m^2), f the ODE2 right-hand side M q_ddot = f (gravity, velocity products,
    springs, dampers, drives; N, N m), both from Exudyn's own implicit solver
    (ComputeMassMatrix, ComputeODE2RHS) on a system built for this state alone."""
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    add_tree(mbs, model, q, q_dot, damping_form)
    mbs.Assemble()
    settings = quiet_settings()
    settings.timeIntegration.startTime = float(t)
    settings.timeIntegration.endTime = float(t) + 1.0
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, settings)
    solver.ComputeMassMatrix(mbs)
    m = np.array(solver.GetSystemMassMatrix(), dtype=float)
    solver.ComputeODE2RHS(mbs)
    f = np.array(solver.GetSystemResidual(), dtype=float)[:model.n_coordinates]
    solver.FinalizeSolver(mbs, settings)
    return m, f

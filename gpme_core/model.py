"""Kinematic-tree model description: joints, links, frames, springs, dampers, drives.

A model is a kinematic tree of joints k = 0 .. n-1, each with one coordinate q_k and
one parent link p(k) < k (-1 = the world); a serial chain is the tree with p(k) = k - 1.
The frame of joint k after its motion is the frame of link k:

    T^(k)(q) = T^(p(k))(q) @ origin_k @ motion_k(q_k),      T^(-1) = identity (world),

where origin_k (4, 4) is constant (parent link frame -> joint frame at q_k = 0) and
motion_k is a rotation about (revolute) or a translation along (prismatic) the unit
``axis`` of the joint frame.  Link k carries the mass properties attached to it,
expressed in its own frame (held as the pseudo-inertia H^(k)); links may be massless
(intermediate frames of an RFEM spring-damping element).  Joint i moves link l when i is
l or one of its ancestors (``Model.moves[i, l]``); every sum of the trace-form terms runs
over these pairs only, so a branch does not move its sibling branches.  Closed loops are
a tree plus two-frame constraints (gpme_core.pair_constraints).

A model is built once by :class:`ChainBuilder`, validated once (every problem in one
:class:`ModelError`), and immutable.  The state (t, q, q_dot) is passed in and out as
arrays ordered as ``model.coordinate_names``.
"""
import warnings
from dataclasses import dataclass
from types import MappingProxyType
from typing import Callable, Optional

import numpy as np

from . import transforms as tf
from .dynamics import mass_matrix
from .errors import InertiaWarning, ModelError
from .geometry import Shape
from .inertia import RigidBodyInertia, transform_pseudo_inertia, inertia_from_pseudo
from .point_springs import PointSpring, check_point_springs
from .joint_kinds import JOINT_KINDS, PRISMATIC, REVOLUTE  # noqa: F401 (users import them here)
from .rfem import discretise_beam

STANDARD_GRAVITY = (0.0, 0.0, -9.81)
# Joint.parent naming the world as a joint's parent (the root of a branch); no link may
# be called so
WORLD = "world"
# |axis| - 1 accepted for a joint axis (a unit vector written in 9 significant digits)
AXIS_UNIT_TOL = 1e-9
# Shortest joint axis a reader normalises (gpme_io.urdf_reader): an axis this short is a
# zero vector plus round-off more likely than a direction, and normalising it multiplies
# its round-off by 1/|axis| (1e6 here: 1e-16 relative becomes 1e-10 in the direction).
MIN_AXIS_LENGTH = 1e-6


def axis_problem(axis) -> Optional[str]:
    """None for a unit 3-vector (|axis| = 1 within AXIS_UNIT_TOL), else what is wrong: the
    shape, a value that is not finite, or its length (degenerate below MIN_AXIS_LENGTH)."""
    a = np.asarray(axis, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        return f"axis must be a unit 3-vector, got {np.ravel(a).tolist()} (finite numbers)"
    length = float(np.linalg.norm(a))
    if length < MIN_AXIS_LENGTH:
        return (f"axis must be a unit 3-vector, got {a.tolist()}, which is degenerate: its "
                f"length {length:.3g} is below {MIN_AXIS_LENGTH:g} (no direction: "
                "normalising it would multiply its round-off by 1/|axis|); e.g. [0, 0, 1]")
    if abs(length - 1.0) > AXIS_UNIT_TOL:
        return (f"axis must be a unit 3-vector, got {a.tolist()} of length {length:.6g} "
                f"(1 within {AXIS_UNIT_TOL:g}); divide it by its length")
    return None


def frozen_array(values, dtype=float):
    """A read-only copy of ``values`` as a numpy array (the caller's array stays writable)."""
    arr = np.array(values, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class Joint:
    """One single-coordinate joint.

    name            : coordinate name (unique)
    kind            : "revolute" (q in rad) or "prismatic" (q in m)
    axis            : (3,) unit vector in the joint frame
    origin          : (4, 4) parent link frame -> joint frame at q = 0
    stiffness       : N m/rad or N/m, >= 0; spring generalized force -stiffness (q - q_ref)
    spring_reference: rad or m, q_ref
    damping         : N m s/rad or N s/m, >= 0; damper generalized force -damping q_dot
    link            : name of the link this joint moves
    limits          : (lower, upper) range of q in rad or m (the stroke of a slider, the
                      travel of a hinge); a programmed motion that needs q outside it
                      cannot be met and stops with a ConstraintError
    parent          : name of the link the joint is mounted on (``origin`` is given in its
                      frame), WORLD for the world, or None for the link of the joint
                      listed just before it (the world for the first: a serial chain)
    """

    name: str
    kind: str
    axis: tuple
    origin: np.ndarray
    stiffness: float = 0.0
    spring_reference: float = 0.0
    damping: float = 0.0
    link: str = ""
    limits: tuple = (-np.inf, np.inf)
    parent: Optional[str] = None

    def __post_init__(self):
        # a read-only copy: the caller's array can change afterwards without moving the joint
        object.__setattr__(self, "origin", frozen_array(self.origin))
        object.__setattr__(self, "axis", tuple(float(a) for a in np.ravel(self.axis)))
        object.__setattr__(self, "limits", tuple(float(v) for v in np.ravel(self.limits)))


@dataclass(frozen=True)
class Link:
    """Mass properties carried by the frame of one joint (None inertia = massless)."""

    name: str
    inertia: Optional[RigidBodyInertia]


@dataclass(frozen=True)
class Frame:
    """A named frame fixed on link ``link_index``; ``transform`` (4, 4) in the link frame."""

    name: str
    link_index: int
    transform: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "transform", frozen_array(self.transform))


@dataclass(frozen=True)
class Drive:
    """A force (N) or torque (N m) on coordinate ``joint`` given as a function of time (s)."""

    joint: str
    function: Callable[[float], float]


class Model:
    """Immutable, validated serial-chain model.  Build it with :class:`ChainBuilder`.

    Immutable means: every array attribute is a read-only copy (writing into it raises
    ValueError), ``frames`` is a read-only mapping (types.MappingProxyType), the sequences
    are tuples of frozen dataclasses, and assigning or deleting an attribute raises
    AttributeError.  Use :meth:`with_changes` (or a new builder) for a changed model.

    Array attributes (n coordinates): origins (n, 4, 4); axes (n, 3); is_revolute (n,)
    bool; generators (n, 4, 4); pseudo_inertias (n, 4, 4) kg, kg m, kg m^2 in each link
    frame; gravity (3,) m/s^2 and gamma (4,) = (gravity, 0); stiffness, spring_reference,
    damping, lower_limits, upper_limits (n,) in the coordinates' SI units; parents (n,)
    int, the index of each joint's parent link (-1 the world, always < the joint's own);
    moves (n, n) bool, moves[i, l] when joint i moves link l (i is l or an ancestor of it).
    """

    def __init__(self, joints, links, frames, drives, gravity, flexible_links, name,
                 geometry=(), point_springs=()):
        put = self._init_attr
        put("name", name)
        # gpme_core.point_springs.PointSpring: spring-dampers between points
        put("point_springs", tuple(point_springs))
        # gpme_core.geometry.Shape records: what the links look like (never dynamics)
        put("geometry", tuple(geometry))
        put("joints", tuple(joints))
        put("links", tuple(links))
        put("frames", MappingProxyType(dict(frames)))
        put("drives", tuple(drives))
        gravity = np.array(gravity, dtype=float)
        put("gravity", frozen_array(gravity))
        # (4,) homogeneous gravity (g_x, g_y, g_z, 0) used by the trace-form gravity terms
        put("gamma", frozen_array(np.append(gravity, 0.0) if gravity.shape == (3,)
                                  else np.zeros(4)))
        put("flexible_links", tuple(flexible_links))
        n = len(self.joints)
        put("n_coordinates", n)
        put("coordinate_names", tuple(j.name for j in self.joints))
        put("_index", MappingProxyType({nm: k for k, nm in enumerate(self.coordinate_names)}))
        put("origins", frozen_array([j.origin for j in self.joints]))
        put("axes", frozen_array([j.axis for j in self.joints]))
        put("is_revolute", frozen_array([j.kind == REVOLUTE for j in self.joints], dtype=bool))
        put("generators", frozen_array([
            tf.revolute_generator(a) if rev else tf.prismatic_generator(a)
            for a, rev in zip(self.axes, self.is_revolute)]))
        put("pseudo_inertias", frozen_array([
            lk.inertia.pseudo_inertia() if lk.inertia is not None else np.zeros((4, 4))
            for lk in self.links]))
        put("stiffness", frozen_array([j.stiffness for j in self.joints]))
        put("spring_reference", frozen_array([j.spring_reference for j in self.joints]))
        put("damping", frozen_array([j.damping for j in self.joints]))
        put("lower_limits", frozen_array([j.limits[0] for j in self.joints]))
        put("upper_limits", frozen_array([j.limits[1] for j in self.joints]))
        parents, parent_problems = _parent_indices(self.joints, self.links)
        put("parents", frozen_array(parents, dtype=np.int64))
        put("_parent_problems", tuple(parent_problems))
        put("moves", frozen_array(_moves(parents), dtype=bool))
        put("_drive_indices", frozen_array([self._index.get(d.joint, -1) for d in self.drives],
                                           dtype=int))
        put("_frozen", True)

    def _init_attr(self, attr, value):
        object.__setattr__(self, attr, value)

    def __setattr__(self, attr, value):
        raise AttributeError(f"Model is immutable: cannot set {attr!r}; build a changed model "
                             "with Model.with_changes or a ChainBuilder")

    def __delattr__(self, attr):
        raise AttributeError(f"Model is immutable: cannot delete {attr!r}")

    def __reduce__(self):
        # the read-only mapping does not pickle; rebuilt from the parts (e.g. for workers)
        return (Model, (self.joints, self.links, dict(self.frames), self.drives,
                        tuple(self.gravity), self.flexible_links, self.name, self.geometry,
                        self.point_springs))

    # ------------------------------------------------------------------ lookup
    @property
    def is_chain(self):
        """True when every joint is mounted on the link before it (a serial chain)."""
        return bool(np.array_equal(self.parents, np.arange(self.n_coordinates) - 1))

    def ancestors(self, link):
        """Indices of the joints that move link ``link`` (its path from the world), in
        increasing order, ``link`` itself last."""
        return np.flatnonzero(self.moves[:, link])

    def index(self, name):
        """Index of the coordinate called ``name``."""
        try:
            return self._index[name]
        except KeyError:
            raise ModelError(f"no coordinate named {name!r}; the model has "
                             f"{list(self.coordinate_names)}") from None

    def frame(self, name):
        """The :class:`Frame` called ``name``."""
        try:
            return self.frames[name]
        except KeyError:
            raise ModelError(f"no frame named {name!r}; the model has {sorted(self.frames)}") from None

    @property
    def flexible_coordinates(self):
        """Names of the RFEM coordinates (psi, theta, phi of every sde), in model order."""
        idx = sorted(k for f in self.flexible_links for k in f.joint_indices)
        return tuple(self.coordinate_names[k] for k in idx)

    def non_physical_inertias(self):
        """One line per link whose (lumped) inertia breaks the triangle inequality of a
        physical body (gpme_core.inertia.RigidBodyInertia.non_physical): accepted, as
        Pinocchio accepts it, and said in the reports; [] for a physical model."""
        return [line for lk in self.links if lk.inertia is not None
                for line in lk.inertia.non_physical(f"link {lk.name!r}")]

    @property
    def total_mass(self):
        """kg."""
        return float(self.pseudo_inertias[:, 3, 3].sum())

    def drive_forces(self, t):
        """(n,) N or N m: the drive generalized forces t(t) at time t (s)."""
        out = np.zeros(self.n_coordinates)
        for k, d in zip(self._drive_indices, self.drives):
            out[k] += d.function(t)
        return out

    def limit_violations(self, q):
        """'name = value unit outside its range [lower, upper]' for every coordinate of q
        outside its limits, joined by commas ('' when all are inside)."""
        bad = (q < self.lower_limits) | (q > self.upper_limits)
        return ", ".join(
            f"{self.coordinate_names[k]} = {q[k]:.6g} {'rad' if self.is_revolute[k] else 'm'} "
            f"outside its range [{self.lower_limits[k]:g}, {self.upper_limits[k]:g}]"
            for k in np.flatnonzero(bad))

    def stiffness_matrix(self):
        """(n, n) K of V = 1/2 (q - q_ref)^T K (q - q_ref)."""
        return np.diag(self.stiffness)

    def damping_matrix(self):
        """(n, n) D of the Rayleigh function R = 1/2 q_dot^T D q_dot."""
        return np.diag(self.damping)

    def with_changes(self, joint_changes=None, link_inertias=None, name=None):
        """A new validated model with some joint fields or link inertias replaced.

        joint_changes : {joint name: {field: value}}; link_inertias : {link name: inertia}.
        Used by tests and by the crosschecks to perturb one engine only.
        """
        joint_changes = joint_changes or {}
        link_inertias = link_inertias or {}
        joints = [Joint(**{**j.__dict__, **joint_changes.get(j.name, {})}) for j in self.joints]
        links = [Link(lk.name, link_inertias.get(lk.name, lk.inertia)) for lk in self.links]
        model = Model(joints, links, self.frames, self.drives, self.gravity,
                      self.flexible_links, name or self.name, self.geometry,
                      self.point_springs)
        validate_model(model)
        return model

    def __repr__(self):
        return (f"Model({self.name!r}, {self.n_coordinates} coordinates, "
                f"{len(self.frames)} frames, mass {self.total_mass:.6g} kg)")


def _parent_indices(joints, links):
    """((n,) parent link index per joint, -1 the world; [problems]) from Joint.parent: a
    named parent must be a link listed before the joint (parents first, so that one pass
    in index order meets every parent before its children)."""
    index = {lk.name: k for k, lk in enumerate(links)}
    parents, problems = [], []
    for k, j in enumerate(joints):
        if j.parent is None:
            parents.append(k - 1)
        elif j.parent == WORLD:
            parents.append(-1)
        elif index.get(j.parent, k) < k:
            parents.append(index[j.parent])
        else:
            where = ("is listed after it" if j.parent in index else
                     "is not a link of the model")
            problems.append(f"joint {j.name!r}: parent link {j.parent!r} {where}; a joint's "
                            f"parent must be {WORLD!r} or a link listed before the joint "
                            f"(links before it: {[lk.name for lk in links[:k]]})")
            parents.append(-1)
    return parents, problems


def _moves(parents):
    """(n, n) bool, [i, l] when joint i is link l or one of its ancestors."""
    n = len(parents)
    out = np.zeros((n, n), dtype=bool)
    for l in range(n):
        out[l, l] = True
        if parents[l] >= 0:
            out[:, l] |= out[:, parents[l]]
    return out


def _rigid_transform_problems(label, t):
    t = np.asarray(t, dtype=float)
    if t.shape != (4, 4):
        return [f"{label}: expected a (4, 4) transform, got shape {t.shape}"]
    if not np.all(np.isfinite(t)):
        return [f"{label}: transform has non-finite entries"]
    out = []
    r = t[:3, :3]
    if not np.allclose(r.T @ r, np.eye(3), atol=1e-9) or np.linalg.det(r) < 0:
        out.append(f"{label}: rotation part is not a proper rotation (R^T R != I or det < 0)")
    if not np.allclose(t[3], (0, 0, 0, 1)):
        out.append(f"{label}: last row must be (0, 0, 0, 1), got {t[3].tolist()}")
    return out


def validate_model(model):
    """Raise one ModelError listing every problem of ``model``."""
    problems = []
    if model.n_coordinates == 0:
        problems.append("the model has no joints; add at least one")
    problems += model._parent_problems
    seen = set()
    for j in model.joints:
        lbl = f"joint {j.name!r}"
        if j.name in seen:
            problems.append(f"{lbl}: duplicate coordinate name")
        seen.add(j.name)
        if j.kind not in JOINT_KINDS:
            problems.append(f"{lbl}: kind must be one of {JOINT_KINDS}, got {j.kind!r}")
        problem = axis_problem(j.axis)
        if problem:
            problems.append(f"{lbl}: {problem}")
        problems += _rigid_transform_problems(f"{lbl} origin", j.origin)
        for fld, unit in (("stiffness", "N/m or N m/rad"), ("damping", "N s/m or N m s/rad")):
            v = getattr(j, fld)
            if not np.isfinite(v) or v < 0:
                problems.append(f"{lbl}: {fld} must be finite and >= 0 ({unit}), got {v!r}")
        lim = np.asarray(j.limits, dtype=float)
        if lim.shape != (2,) or np.isnan(lim).any() or not lim[0] < lim[1]:
            problems.append(f"{lbl}: limits must be (lower, upper) with lower < upper, "
                            f"got {j.limits!r}")
        if not np.isfinite(j.spring_reference):
            problems.append(f"{lbl}: spring_reference must be finite, got {j.spring_reference!r}")
    link_names = set()
    for lk in model.links:
        if lk.name in link_names:
            problems.append(f"link {lk.name!r}: duplicate link name")
        if lk.name == WORLD:
            problems.append(f"link {WORLD!r}: the name is reserved for the world (the parent "
                            "of a branch's first joint); rename the link")
        link_names.add(lk.name)
        if lk.inertia is not None:
            problems += lk.inertia.problems(f"link {lk.name!r}")
    for k, shape in enumerate(model.geometry):
        if not 0 <= shape.link_index < model.n_coordinates:
            problems.append(f"shape {k}: link index {shape.link_index} out of range")
        else:
            problems += shape.problems(f"shape {k} on link "
                                       f"{model.links[shape.link_index].name!r}")
    for name, fr in model.frames.items():
        if not 0 <= fr.link_index < model.n_coordinates:
            problems.append(f"frame {name!r}: link index {fr.link_index} out of range")
        problems += _rigid_transform_problems(f"frame {name!r}", fr.transform)
    g = np.asarray(model.gravity)
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        problems.append(f"gravity must be a finite (3,) vector in m/s^2, got {g.tolist()}")
    problems += check_point_springs(model.point_springs, model.frames)
    for d in model.drives:
        if d.joint not in seen:
            problems.append(f"drive on {d.joint!r}: no such coordinate; have {sorted(seen)}")
        if not callable(d.function):
            problems.append(f"drive on {d.joint!r}: function must be callable t -> force")
    if not problems:
        problems += _mass_matrix_problems(model)
    if problems:
        raise ModelError(problems)


def _mass_matrix_problems(model):
    q = model.spring_reference.copy()
    m = mass_matrix(model, q)
    eig, vec = np.linalg.eigh(m)
    # Round-off in M is a few eps * max|M|; an eigenvalue below 1e-12 * the largest one
    # (cond(M) > 1e12) leaves no correct digit in an acceleration of 4 significant ones.
    tol = 1e-12 * max(eig.max(), 1e-300)
    if eig.min() > tol:
        return []
    names = model.coordinate_names
    modes = []
    for k in np.flatnonzero(eig <= tol):
        v = vec[:, k] / vec[np.argmax(np.abs(vec[:, k])), k]    # largest component = 1
        big = np.flatnonzero(np.abs(v) > 1e-6)
        modes.append(names[big[0]] if len(big) == 1 else
                     " ".join(f"{v[i]:+.3g} {names[i]}" for i in big))
    zero = [names[k] for k in range(model.n_coordinates) if m[k, k] <= 1e-300]
    hint = f"; coordinates moving no mass: {zero}" if zero else ""
    return [f"the mass matrix at q = spring references is not positive definite (smallest "
            f"eigenvalue "
            f"{eig.min():.3e}, largest {eig.max():.3e}): no mass or inertia resists a motion "
            f"of {'; of '.join(modes)}{hint}; give the links moved by these coordinates mass "
            "or rotational inertia about their joint axes (a point mass on a revolute axis "
            "has none)"]


class ChainBuilder:
    """Assemble a serial chain or a tree joint by joint, then :meth:`build` an immutable
    Model.

    Each :meth:`add_joint` creates a new link (the joint's moving frame), mounted on the
    newest link unless ``parent`` names another (a branch); the bodies, beams and frames
    added afterwards attach to the newest link until the next joint.
    """

    def __init__(self, name="model", gravity=STANDARD_GRAVITY):
        self.name = name
        self.gravity = gravity
        self._joints = []
        self._link_names = []
        self._link_h = []          # pseudo-inertia accumulated in the link frame
        self._link_parts = []      # the RigidBodyInertia objects attached to each link
        self._frames = {}
        self._drives = []
        self._flex = []
        self._pending_origin = np.eye(4)   # offset of the next joint (e.g. a beam tip)
        self._link_pending = {}            # {link: its offset, kept when it stops being newest}
        self._shapes = []                  # gpme_core.geometry.Shape of the links
        self._point_springs = []           # gpme_core.point_springs.PointSpring

    @property
    def n_joints(self):
        return len(self._joints)

    @property
    def current_link(self):
        """Name of the newest link (what bodies, frames and an unparented joint attach to;
        after :meth:`add_beam`, the beam's last segment), None before the first joint."""
        return self._link_names[-1] if self._link_names else None

    def add_joint(self, name, kind, axis, origin=None, stiffness=0.0, spring_reference=0.0,
                  damping=0.0, link=None, limits=(-np.inf, np.inf), parent=None):
        """Add a joint (and its link).

        parent : None to mount it on the current (newest) link, as in a serial chain; or
                 the name of an earlier link, or WORLD, to start a branch there.
        origin : (4, 4) joint frame at q = 0 in the parent link frame, after the parent's
                 attachment offset (a beam's tip, when the parent is a beam's last
                 segment: :meth:`current_link` after :meth:`add_beam` names it)."""
        origin = np.eye(4) if origin is None else np.asarray(origin, dtype=float)
        if self._link_names:       # the newest link keeps its attachment point for branches
            self._link_pending[self._link_names[-1]] = self._pending_origin
        on_current = parent is None or (self._link_names and parent == self._link_names[-1])
        pending = self._pending_origin if on_current else \
            self._link_pending.get(parent, np.eye(4))
        if origin.shape == (4, 4):
            origin = pending @ origin
        self._pending_origin = np.eye(4)
        axis = tuple(float(a) for a in np.ravel(axis))
        self._joints.append(Joint(name, kind, axis, origin, float(stiffness),
                                  float(spring_reference), float(damping), link or name,
                                  tuple(float(v) for v in limits), parent))
        self._link_names.append(link or name)
        self._link_h.append(None)
        self._link_parts.append([])
        return len(self._joints) - 1

    def add_body(self, inertia, origin=None):
        """Attach a rigid body to the current link; origin (4, 4) body frame in link frame."""
        if not self._joints:
            raise ModelError("add a joint before attaching a body: bodies fixed to the world "
                             "do not move and have no effect on the dynamics")
        label = f"body on link {self._link_names[-1]!r}"
        problems = inertia.problems(label)
        if problems:
            raise ModelError(problems)
        for line in inertia.non_physical(label):
            warnings.warn(line, InertiaWarning, stacklevel=2)
        x = self._pending_origin if origin is None else self._pending_origin @ np.asarray(origin, float)
        h = transform_pseudo_inertia(x, inertia.pseudo_inertia())
        self._link_parts[-1].append(inertia if np.array_equal(x, np.eye(4)) else None)
        prev = self._link_h[-1]
        self._link_h[-1] = h if prev is None else prev + h

    def add_shape(self, kind, size, origin=None, role="both", mesh=None, rgba=None):
        """Attach a shape (gpme_core.geometry: what the link looks like, never mass) to the
        current link; ``origin`` (4, 4) its frame in the link frame (after a pending beam
        tip offset, as for a body)."""
        if not self._joints:
            raise ModelError("add a joint before attaching a shape")
        x = self._pending_origin if origin is None else \
            self._pending_origin @ np.asarray(origin, float)
        shape = Shape(len(self._joints) - 1, kind, size, x, role, mesh, rgba)
        problems = shape.problems(f"shape on link {self._link_names[-1]!r}")
        if problems:
            raise ModelError(problems)
        self._shapes.append(shape)

    def add_frame(self, name, transform=None):
        """Name a frame fixed on the current link (e.g. the end-effector)."""
        if not self._joints:
            raise ModelError(f"frame {name!r}: add a joint first")
        t = np.eye(4) if transform is None else np.asarray(transform, dtype=float)
        self._frames[name] = Frame(name, len(self._joints) - 1, self._pending_origin @ t)

    def add_drive(self, joint, function):
        """A force/torque t(t) on coordinate ``joint``."""
        self._drives.append(Drive(joint, function))

    def add_point_spring(self, name, frame, anchor, stiffness, free_length, damping=0.0):
        """A spring-damper from the origin of ``frame`` to ``anchor`` (a world point (3,) m
        or another frame's name): stiffness N/m, free_length m, damping N s/m
        (gpme_core.point_springs)."""
        anchor = anchor if isinstance(anchor, str) else tuple(float(v) for v in anchor)
        self._point_springs.append(PointSpring(name, frame, anchor, float(stiffness),
                                               float(free_length), float(damping)))

    def add_beam(self, name, beam, n_segments, frame=None):
        """Attach an RFEM-discretised beam to the current link (see gpme_core.rfem).

        frame : (4, 4) beam frame B in the current link frame: the beam starts at B's
                origin and lies along B's +x, its section axes are B's y and z; None =
                identity (the beam along +x of the link frame).  What is added next
                attaches at the beam tip, B @ translation(L) at zero deflection.
        """
        discretise_beam(self, name, beam, n_segments, frame=frame)

    def pending_origin(self):
        """(4, 4) current link frame -> where the next joint, body or frame attaches (a copy;
        the identity except after a beam: its tip, gpme_core.rfem.discretise_beam)."""
        return self._pending_origin.copy()

    def set_pending_origin(self, t):
        """Attach the next joint, body or frame at t (4, 4), given in the current link frame
        (gpme_core.rfem.discretise_beam moves it to the beam tip)."""
        self._pending_origin = np.asarray(t, dtype=float)

    def record_flexible_link(self, info):
        """Record a gpme_core.rfem.FlexibleLinkInfo (done by add_beam; public for model
        readers that rebuild an RFEM link from a file)."""
        self._flex.append(info)

    def build(self):
        """Validate and return the immutable :class:`Model`."""
        links = []
        for name, h, parts in zip(self._link_names, self._link_h, self._link_parts):
            if h is None or not np.any(h):
                links.append(Link(name, None))
            elif len(parts) == 1 and parts[0] is not None:
                links.append(Link(name, parts[0]))     # keep the user's numbers bit-exact
            else:
                m, c, i_c = inertia_from_pseudo(h)
                links.append(Link(name, RigidBodyInertia(m, c, i_c)))
        model = Model(self._joints, links, self._frames, self._drives, self.gravity,
                      self._flex, self.name, self._shapes, self._point_springs)
        validate_model(model)
        return model

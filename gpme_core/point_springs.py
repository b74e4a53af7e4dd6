"""Spring-dampers between a point of the model and a fixed point or another point of the
model (a gas spring, a tension spring, a cable held taut): force elements that act along
the line between their two points.

A :class:`PointSpring` joins the origin p_a of model frame ``frame`` to ``anchor``: a
fixed world point (3,) m, or the origin p_b of another model frame.  With d = p_a - p_b,
L = |d| and e = d / L, its force on p_a (world frame, N) is

    F = -(stiffness (L - free_length) + damping L_dot) e,      L_dot = e . (v_a - v_b),

and -F on p_b.  Its generalized force is J_a^T F - J_b^T F (J the points' Jacobians,
gpme_core.kinematics), in gpme's convention split as the elastic part into f (f = dV/dq,
V = 1/2 stiffness (L - free_length)^2) and the damping part into d (d = dR/dq_dot,
R = 1/2 damping L_dot^2): M q_ddot = h - (g + d + f) + t.

The direction e is undefined where the two points meet: evaluating there raises a
ConstraintError naming the spring (a spring of free length > 0 between points that can
meet is a model error; a zero free length needs them apart).
"""
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .errors import ConstraintError, ModelError
from .kinematics import point_kinematics

# shortest distance (m) between a spring's points at which its direction is defined
MIN_LENGTH = 1e-12


@dataclass(frozen=True)
class PointSpring:
    """A spring-damper from the origin of frame ``frame`` to ``anchor`` (a world point (3,)
    m, or the name of another frame).

    stiffness    : N/m, >= 0;  free_length : m, >= 0;  damping : N s/m, >= 0
    """

    name: str
    frame: str
    anchor: object
    stiffness: float
    free_length: float
    damping: float = 0.0

    def problems(self, frames) -> list:
        """Every problem of the spring on a model with frame names ``frames``."""
        out = []
        label = f"point spring {self.name!r}"
        for fld, unit in (("stiffness", "N/m"), ("free_length", "m"), ("damping", "N s/m")):
            v = getattr(self, fld)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                out.append(f"{label}: {fld} must be a finite number >= 0 ({unit}), got {v!r}")
        names = [self.frame] + ([self.anchor] if isinstance(self.anchor, str) else [])
        for f in names:
            if f not in frames:
                out.append(f"{label}: no frame named {f!r}; the model has {sorted(frames)}")
        if not isinstance(self.anchor, str):
            a = np.asarray(self.anchor, dtype=float)
            if a.shape != (3,) or not np.all(np.isfinite(a)):
                out.append(f"{label}: anchor must be a frame name or a finite world point "
                           f"(3,) m, got {self.anchor!r}")
        if self.anchor == self.frame:
            out.append(f"{label}: joins frame {self.frame!r} to itself")
        return out


def _point(model, kin, q_dot, frame):
    fr = model.frame(frame)
    return point_kinematics(model, kin, q_dot, fr.link_index, fr.transform[:3, 3])


def spring_state(model, spring, kin, q_dot) -> tuple:
    """(L m, L_dot m/s, e (3,), J (3, n) = J_a - J_b) of one spring at kin, q_dot."""
    a = _point(model, kin, q_dot, spring.frame)
    if isinstance(spring.anchor, str):
        b = _point(model, kin, q_dot, spring.anchor)
        p_b, v_b, j_b = b.position, b.velocity, b.jacobian
    else:
        p_b, v_b, j_b = np.asarray(spring.anchor, float), np.zeros(3), 0.0
    d = a.position - p_b
    length = float(np.linalg.norm(d))
    if not length > MIN_LENGTH:
        raise ConstraintError(
            f"point spring {spring.name!r}: its points meet (frame {spring.frame!r} at "
            f"{np.round(a.position, 9).tolist()} m, distance {length:.3g} m), where the "
            "direction of its force is undefined; a spring needs its two points apart")
    e = d / length
    return length, float(e @ (a.velocity - v_b)), e, a.jacobian - j_b


def point_spring_forces(model, kin, q_dot) -> tuple:
    """((n,) f, (n,) d): the generalized elastic forces dV/dq and damping forces dR/dq_dot
    of the model's point springs (N or N m), zero without any."""
    n = model.n_coordinates
    f, d = np.zeros(n), np.zeros(n)
    if not model.point_springs:
        return f, d
    for s in model.point_springs:
        length, rate, e, jac = spring_state(model, s, kin, q_dot)
        f += s.stiffness * (length - s.free_length) * (e @ jac)
        d += s.damping * rate * (e @ jac)
    return f, d


def point_spring_energy(model, kin) -> float:
    """J, sum of 1/2 stiffness (L - free_length)^2 over the point springs."""
    zero = np.zeros(model.n_coordinates)
    return sum(0.5 * s.stiffness * (spring_state(model, s, kin, zero)[0] - s.free_length) ** 2
               for s in model.point_springs)


def point_spring_matrices(model, kin) -> tuple:
    """((n, n) K, (n, n) D): the point springs' line stiffness and damping at kin, the sums
    of stiffness g g^T and damping g g^T with g = e^T (J_a - J_b) the spring line's row:
    the Hessian of their energy where each spring is at its free length (the tension's
    geometric terms, proportional to L - L0, left out).  What gpme_core.stability
    linearises them with, as it does the joint springs."""
    n = model.n_coordinates
    k_mat, d_mat = np.zeros((n, n)), np.zeros((n, n))
    zero = np.zeros(n)
    for s in model.point_springs:
        _, _, e, jac = spring_state(model, s, kin, zero)
        g = e @ jac
        k_mat += s.stiffness * np.outer(g, g)
        d_mat += s.damping * np.outer(g, g)
    return k_mat, d_mat


def check_point_springs(springs, frames) -> list:
    """Problems of a model's point springs (names unique, each valid)."""
    out = [p for s in springs for p in s.problems(frames)]
    names = [s.name for s in springs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        out.append(f"point spring names must be unique, repeated: {dup}")
    return out


def as_spring(spring) -> Optional[PointSpring]:
    """``spring`` if it is a PointSpring, else ModelError."""
    if not isinstance(spring, PointSpring):
        raise ModelError(f"a point spring must be a gpme_core.point_springs.PointSpring, "
                         f"got {type(spring).__name__}")
    return spring

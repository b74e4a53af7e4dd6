"""Forward kinematics in homogeneous transforms and the partial derivatives T_i, T_ij.

For link l (the frame of joint l) the world transform is T^(l)(q) (4, 4).  Because
joint i moves every link l it carries (i = l or an ancestor of l in the kinematic tree,
``model.moves[i, l]``; in a serial chain every l >= i) the same way,

    T_i^(l)  = dT^(l)/dq_i        = S_i T^(l)            (i moves l, else 0),
    T_ij^(l) = d2T^(l)/dq_i dq_j  = S_min(i,j) S_max(i,j) T^(l)  (i and j move l, else 0),

with S_i = T^(i) Q_i (T^(i))^-1 (4, 4) the world-frame twist matrix of joint i and Q_i
its generator (dM_i/dq_i = M_i Q_i).  Two joints that both move l lie on l's path from
the world, where the lower index is the ancestor.  This is the structure that keeps the
cost of the trace-form terms at O(n^2) instead of O(n^4).  The functions
``transform_derivative`` and ``transform_second_derivative`` give single T_i^(l),
T_ij^(l) for tests and reports.

Tree recursions (p(l) the parent link, -1 the world with V, B = 0 there):
V_l = V_p(l) + S_l q_dot_l,  B_l = B_p(l) + (2 V_p(l) + S_l q_dot_l) S_l q_dot_l.
"""
from dataclasses import dataclass

import numpy as np

from . import fast

_E4 = np.eye(4)


def joint_motions(model, q):
    """(n, 4, 4) motion transforms M_k(q_k) of every joint."""
    q = np.asarray(q, dtype=float)
    n = model.n_coordinates
    gens = model.generators
    out = np.broadcast_to(_E4, (n, 4, 4)).copy()
    rev = model.is_revolute
    if rev.any():
        k = gens[rev, :3, :3]
        s = np.sin(q[rev])[:, None, None]
        c = np.cos(q[rev])[:, None, None]
        out[rev, :3, :3] += s * k + (1.0 - c) * (k @ k)
    pri = ~rev
    if pri.any():
        out[pri, :3, 3] = gens[pri, :3, 3] * q[pri][:, None]
    return out


def link_transforms(model, q):
    """(n, 4, 4) world transforms T^(l) of every link l at coordinates q (n,)."""
    local = model.origins @ joint_motions(model, q)
    out = np.empty_like(local)
    for k, parent in enumerate(model.parents):
        out[k] = local[k] if parent < 0 else out[parent] @ local[k]
    return out


def rigid_inverse(t):
    """Batched inverse of rigid transforms (..., 4, 4)."""
    r_t = np.swapaxes(t[..., :3, :3], -1, -2)
    out = np.zeros_like(t)
    out[..., :3, :3] = r_t
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", r_t, t[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def joint_twists(model, transforms):
    """(n, 4, 4) world twist matrices S_i = T^(i) Q_i T^(i)^-1."""
    return transforms @ model.generators @ rigid_inverse(transforms)


@dataclass(frozen=True)
class ChainKinematics:
    """Link transforms T (n, 4, 4) and joint twist matrices S (n, 4, 4) at one q;
    moves (n, n) bool is the model's ``moves`` (None: a serial chain)."""

    q: np.ndarray
    T: np.ndarray
    S: np.ndarray
    moves: np.ndarray = None

    def _moves(self, i, link):
        return i <= link if self.moves is None else bool(self.moves[i, link])

    def T_first(self, link, i):
        """T_i^(link) (4, 4)."""
        if not self._moves(i, link):
            return np.zeros((4, 4))
        return self.S[i] @ self.T[link]

    def T_second(self, link, i, j):
        """T_ij^(link) (4, 4)."""
        if not (self._moves(i, link) and self._moves(j, link)):
            return np.zeros((4, 4))
        a, b = min(i, j), max(i, j)
        return self.S[a] @ self.S[b] @ self.T[link]


def chain_kinematics(model, q):
    """:class:`ChainKinematics` at coordinates q (n,)."""
    q = np.asarray(q, dtype=float)
    t = link_transforms(model, q)
    return ChainKinematics(q, t, joint_twists(model, t), model.moves)


def transform_derivative(model, q, link, i):
    """T_i^(link) = dT^(link)/dq_i (4, 4)."""
    return chain_kinematics(model, q).T_first(link, i)


def transform_second_derivative(model, q, link, i, j):
    """T_ij^(link) = d2 T^(link)/dq_i dq_j (4, 4)."""
    return chain_kinematics(model, q).T_second(link, i, j)


def twist_velocities(S, q_dot, parents=None):
    """(n, 4, 4) V_l = sum_{i moves l} S_i q_dot_i: T_dot^(l) = V_l T^(l).

    parents : (n,) parent link indices (-1 the world), None for a serial chain."""
    w = S * np.asarray(q_dot, dtype=float)[:, None, None]
    if parents is None:
        return np.cumsum(w, axis=0)
    out = np.empty_like(w)
    for l, p in enumerate(parents):
        out[l] = w[l] if p < 0 else out[p] + w[l]
    return out


def velocity_product_accelerations(S, q_dot, parents=None):
    """(n, 4, 4) B_l with sum_{i,j move l} T_ij^(l) q_dot_i q_dot_j = B_l T^(l).

    B_l = sum_{i,j move l} S_min(i,j) S_max(i,j) q_dot_i q_dot_j, by the recursion
    B_l = B_p(l) + (2 V_p(l) + S_l q_dot_l) S_l q_dot_l (module docstring; p(l) = l - 1
    in a serial chain, parents=None).
    """
    q_dot = np.asarray(q_dot, dtype=float)
    w = S * q_dot[:, None, None]                     # S_l q_dot_l
    if parents is None:
        v_before = np.cumsum(w, axis=0) - w          # V_{l-1}
        inc = (2.0 * v_before + w) @ w
        return np.cumsum(inc, axis=0)
    v = twist_velocities(S, q_dot, parents)
    out = np.empty_like(w)
    for l, p in enumerate(parents):
        v_before = v[p] if p >= 0 else 0.0 * w[l]
        inc = (2.0 * v_before + w[l]) @ w[l]
        out[l] = inc if p < 0 else out[p] + inc
    return out


@dataclass(frozen=True)
class PointKinematics:
    """World position (3,) m, Jacobian (3, n) and drift (3,) m/s^2 of a body-fixed point.

    p_ddot = jacobian @ q_ddot + drift;  jacobian[:, i] = J T_i r,  drift = J (sum T_ij
    q_dot_i q_dot_j) r (the paper's C and d).
    """

    position: np.ndarray
    velocity: np.ndarray
    jacobian: np.ndarray
    drift: np.ndarray


def point_kinematics(model, kin, q_dot, link, r_local):
    """Kinematics of the point r_local (3,) m (in the frame of ``link``) at kin, q_dot."""
    return vector_kinematics(model, kin, q_dot, link, r_local, 1.0)


def vector_kinematics(model, kin, q_dot, link, r_local, w):
    """:class:`PointKinematics` of the homogeneous vector (r_local, w) fixed on ``link``:
    w = 1, a point (r_local in m, as :func:`point_kinematics`); w = 0, a direction
    (r_local a vector of the link frame, turned with the link and not translated: its
    'position' is the world vector, its Jacobian columns S_i (u, 0) = omega_i x u)."""
    if fast.ENABLED:
        pos, vel, jac, drift = fast.run(fast.point, kin.T, kin.S, model.moves,
                                        fast.state_array(q_dot), link,
                                        fast.state_array(r_local), float(w))
        return PointKinematics(pos, vel, jac, drift)
    r = np.append(np.asarray(r_local, dtype=float), float(w))
    r_world = kin.T[link] @ r
    jac = np.zeros((3, model.n_coordinates))
    path = model.ancestors(link)                     # a serial chain from the world
    jac[:, path] = (kin.S[path] @ r_world)[:, :3].T
    b = velocity_product_accelerations(kin.S[path], np.asarray(q_dot)[path])[-1]
    drift = (b @ r_world)[:3]
    return PointKinematics(r_world[:3], jac @ q_dot, jac, drift)


def frame_point(model, frame_name):
    """(link index, (3,) position in the link frame) of the origin of a named frame."""
    fr = model.frame(frame_name)
    return fr.link_index, fr.transform[:3, 3].copy()

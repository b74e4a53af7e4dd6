"""Forward kinematics in homogeneous transforms and the partial derivatives T_i, T_ij.

For link l (the frame of joint l) the world transform is T^(l)(q) (4, 4).  Because
joint i moves every link l >= i the same way,

    T_i^(l)  = dT^(l)/dq_i        = S_i T^(l)            (i <= l, else 0),
    T_ij^(l) = d2T^(l)/dq_i dq_j  = S_min(i,j) S_max(i,j) T^(l)  (i, j <= l, else 0),

with S_i = T^(i) Q_i (T^(i))^-1 (4, 4) the world-frame twist matrix of joint i and Q_i
its generator (dM_i/dq_i = M_i Q_i).  This is the chain structure that keeps the cost of
the trace-form terms at O(n^2) instead of O(n^4).  The functions ``transform_derivative``
and ``transform_second_derivative`` give single T_i^(l), T_ij^(l) for tests and reports.
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
    acc = _E4
    for k in range(model.n_coordinates):
        acc = acc @ local[k]
        out[k] = acc
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
    """Link transforms T (n, 4, 4) and joint twist matrices S (n, 4, 4) at one q."""

    q: np.ndarray
    T: np.ndarray
    S: np.ndarray

    def T_first(self, link, i):
        """T_i^(link) (4, 4)."""
        if i > link:
            return np.zeros((4, 4))
        return self.S[i] @ self.T[link]

    def T_second(self, link, i, j):
        """T_ij^(link) (4, 4)."""
        if max(i, j) > link:
            return np.zeros((4, 4))
        a, b = min(i, j), max(i, j)
        return self.S[a] @ self.S[b] @ self.T[link]


def chain_kinematics(model, q):
    """:class:`ChainKinematics` at coordinates q (n,)."""
    q = np.asarray(q, dtype=float)
    t = link_transforms(model, q)
    return ChainKinematics(q, t, joint_twists(model, t))


def transform_derivative(model, q, link, i):
    """T_i^(link) = dT^(link)/dq_i (4, 4)."""
    return chain_kinematics(model, q).T_first(link, i)


def transform_second_derivative(model, q, link, i, j):
    """T_ij^(link) = d2 T^(link)/dq_i dq_j (4, 4)."""
    return chain_kinematics(model, q).T_second(link, i, j)


def twist_velocities(S, q_dot):
    """(n, 4, 4) V_l = sum_{i<=l} S_i q_dot_i: T_dot^(l) = V_l T^(l)."""
    return np.cumsum(S * np.asarray(q_dot)[:, None, None], axis=0)


def velocity_product_accelerations(S, q_dot):
    """(n, 4, 4) B_l with sum_{i,j<=l} T_ij^(l) q_dot_i q_dot_j = B_l T^(l).

    B_l = sum_{i,j<=l} S_min(i,j) S_max(i,j) q_dot_i q_dot_j, by the recursion
    B_l = B_{l-1} + (2 V_{l-1} + S_l q_dot_l) S_l q_dot_l.
    """
    q_dot = np.asarray(q_dot, dtype=float)
    w = S * q_dot[:, None, None]                     # S_l q_dot_l
    v_before = np.cumsum(w, axis=0) - w              # V_{l-1}
    inc = (2.0 * v_before + w) @ w
    return np.cumsum(inc, axis=0)


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
    if fast.ENABLED:
        pos, vel, jac, drift = fast.run(fast.point, kin.T, kin.S, np.asarray(q_dot, dtype=float),
                                        link, np.asarray(r_local, dtype=float))
        return PointKinematics(pos, vel, jac, drift)
    r = np.append(np.asarray(r_local, dtype=float), 1.0)
    r_world = kin.T[link] @ r
    jac = np.zeros((3, model.n_coordinates))
    jac[:, :link + 1] = (kin.S[:link + 1] @ r_world)[:, :3].T
    b = velocity_product_accelerations(kin.S[:link + 1], np.asarray(q_dot)[:link + 1])[-1]
    drift = (b @ r_world)[:3]
    return PointKinematics(r_world[:3], jac @ q_dot, jac, drift)


def frame_point(model, frame_name):
    """(link index, (3,) position in the link frame) of the origin of a named frame."""
    fr = model.frame(frame_name)
    return fr.link_index, fr.transform[:3, 3].copy()

"""Trace-form dynamics terms of an unconstrained kinematic tree (a serial chain or not).

Equation of motion (Lagrange's equations of the second kind), paper's sign convention:

    M(q) q_ddot = h(q, q_dot) + Q,    Q = -(g + d + f) + t,

    m_ij = sum_l tr(T_i^(l) H^(l) T_j^(l)T)
    h_i  = -sum_l sum_j sum_k tr(T_i^(l) H^(l) T_jk^(l)T) q_dot_j q_dot_k  (velocity products)
    g_i  = dE_p,g / dq_i,  E_p,g = -sum_l gamma^T T^(l) H^(l) e_4,  gamma = (gravity, 0)
    f    = K (q - q_ref)   (springs),  d = D q_dot  (dampers: d = dR/dq_dot),
           plus the point springs' elastic and damping forces (gpme_core.point_springs),
    t    = drive forces.

All sums over l run over the links that both i and j move only (tree structure,
gpme_core.kinematics; in a serial chain l >= max(i, j)); with the composite world
pseudo-inertias of the subtrees, Hc_k = sum_{l in subtree(k)} T^(l) H^(l) T^(l)T, the
mass matrix is m_ij = tr(S_i Hc_j S_j^T) when i moves j (i <= j), 0 when neither of i, j
moves the other (two branches), O(n^2).  Units: SI (kg, m, s, rad, N, N m).
"""
from dataclasses import dataclass

import numpy as np

from . import fast
from .point_springs import point_spring_energy, point_spring_forces
from .kinematics import (ChainKinematics, chain_kinematics, twist_velocities,
                         velocity_product_accelerations)


def _as_kin(model, q_or_kin):
    if hasattr(q_or_kin, "S"):
        return q_or_kin
    return chain_kinematics(model, q_or_kin)


def world_pseudo_inertias(model, kin):
    """(n, 4, 4) T^(l) H^(l) T^(l)T, the pseudo-inertia of link l in the world frame."""
    return kin.T @ model.pseudo_inertias @ np.swapaxes(kin.T, 1, 2)


def subtree_sums(a, parents):
    """(n, ...) c_k = sum of a_l over the subtree of link k (k and its descendants);
    parents (n,) parent link indices, -1 the world, each < its child's index."""
    out = np.array(a, dtype=float, copy=True)
    for l in range(len(parents) - 1, -1, -1):
        if parents[l] >= 0:
            out[parents[l]] += out[l]
    return out


def mass_matrix(model, q):
    """(n, n) mass matrix M, m_ij = sum_l tr(T_i^(l) H^(l) T_j^(l)T); q (n,) or kinematics."""
    kin = _as_kin(model, q)
    composite = subtree_sums(world_pseudo_inertias(model, kin), model.parents)
    y = kin.S @ composite                           # S_j Hc_j  (Hc symmetric)
    e = np.einsum("iab,jab->ij", kin.S, y)          # e_ij = tr(S_i Hc_j S_j^T)
    upper = np.where(model.moves, e, 0.0)           # i moves j: i <= j on j's path
    return upper + np.triu(upper, 1).T


def velocity_product_terms(model, q, q_dot):
    """(n,) h = -(Coriolis and centrifugal terms), M q_ddot = h + Q."""
    kin = _as_kin(model, q)
    b = velocity_product_accelerations(kin.S, q_dot, model.parents)
    g_acc = subtree_sums(b @ world_pseudo_inertias(model, kin), model.parents)
    return -np.einsum("iab,iab->i", kin.S, g_acc)


def gravity_forces(model, q):
    """(n,) g = dE_p,g/dq (the generalized gravity force is -g)."""
    kin = _as_kin(model, q)
    first_moments = subtree_sums(kin.T @ model.pseudo_inertias[:, :, 3:4],
                                 model.parents)[:, :, 0]
    return -np.einsum("a,iab,ib->i", model.gamma, kin.S, first_moments)


def spring_forces(model, q):
    """(n,) f = K (q - q_ref), N or N m."""
    return model.stiffness * (np.asarray(q, dtype=float) - model.spring_reference)


def damper_forces(model, q_dot):
    """(n,) d = D q_dot = dR/dq_dot, N or N m."""
    return model.damping * np.asarray(q_dot, dtype=float)


def drive_forces(model, t):
    """(n,) t(t), N or N m."""
    return model.drive_forces(t)


def generalized_forces(model, t, q, q_dot):
    """(n,) Q = -(g + d + f) + t (f and d with the point springs', gpme_core.point_springs)."""
    q_out = -(gravity_forces(model, q) + damper_forces(model, q_dot) + spring_forces(model, q)) \
        + drive_forces(model, t)
    if not model.point_springs:
        return q_out
    f_ps, d_ps = point_spring_forces(model, chain_kinematics(model, q), q_dot)
    return q_out - (f_ps + d_ps)


def kinetic_energy(model, q, q_dot):
    """J, E_k = 1/2 sum_l tr(T_dot^(l) H^(l) T_dot^(l)T) (computed in trace form)."""
    kin = _as_kin(model, q)
    v = twist_velocities(kin.S, q_dot, model.parents)
    hw = world_pseudo_inertias(model, kin)
    return 0.5 * float(np.einsum("lab,lbc,lac->", v, hw, v))


def gravity_potential_energy(model, q):
    """J, E_p,g = -sum_l gamma^T T^(l) H^(l) e_4 (zero at the world origin)."""
    kin = _as_kin(model, q)
    return -float(np.einsum("a,lab,lb->", model.gamma, kin.T, model.pseudo_inertias[:, :, 3]))


def spring_potential_energy(model, q):
    """J, 1/2 (q - q_ref)^T K (q - q_ref) plus the point springs' 1/2 k (L - L0)^2."""
    dq = np.asarray(q, dtype=float) - model.spring_reference
    joints = 0.5 * float(dq @ (model.stiffness * dq))
    if not model.point_springs:
        return joints
    return joints + point_spring_energy(model, chain_kinematics(model, q))


def potential_energy(model, q):
    """J, gravity plus springs."""
    return gravity_potential_energy(model, q) + spring_potential_energy(model, q)


def rayleigh_function(model, q_dot):
    """W, R = 1/2 q_dot^T D q_dot (the dissipated power is 2 R)."""
    qd = np.asarray(q_dot, dtype=float)
    return 0.5 * float(qd @ (model.damping * qd))


@dataclass(frozen=True)
class DynamicsTerms:
    """Every term of M q_ddot = h + Q at one (t, q, q_dot), sharing one kinematics."""

    kin: object
    M: np.ndarray
    h: np.ndarray
    g: np.ndarray
    f: np.ndarray
    d: np.ndarray
    t: np.ndarray

    @property
    def Q(self):
        """(n,) -(g + d + f) + t."""
        return -(self.g + self.d + self.f) + self.t

    @property
    def rhs(self):
        """(n,) h + Q."""
        return self.h + self.Q


def dynamics_terms(model, t, q, q_dot):
    """All terms at once (one forward-kinematics pass).

    Uses the compiled kernels of gpme_core.fast (same formulas, equal to the numpy
    functions above to round-off) unless GPME_NO_JIT=1."""
    q = fast.state_array(q)
    q_dot = fast.state_array(q_dot)
    if fast.ENABLED:
        t_all, s_all, m, h, g = fast.run(
            fast.chain_and_terms, model.origins, model.generators, model.is_revolute,
            model.pseudo_inertias, model.gamma, model.parents, model.moves, q, q_dot)
        kin = ChainKinematics(q, t_all, s_all, model.moves)
        f = model.stiffness * (q - model.spring_reference)
        d = model.damping * q_dot
        if model.point_springs:
            f_ps, d_ps = point_spring_forces(model, kin, q_dot)
            f, d = f + f_ps, d + d_ps
        return DynamicsTerms(kin, m, h, g, f, d, model.drive_forces(t))
    kin = chain_kinematics(model, q)
    f_ps, d_ps = point_spring_forces(model, kin, q_dot)
    return DynamicsTerms(kin, mass_matrix(model, kin), velocity_product_terms(model, kin, q_dot),
                         gravity_forces(model, kin), spring_forces(model, q) + f_ps,
                         damper_forces(model, q_dot) + d_ps, drive_forces(model, t))

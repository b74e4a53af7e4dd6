"""Homogeneous 4x4 transforms and joint motion generators.

Conventions (see docs/conventions.md): right-handed frames, active rotations,
column vectors.  ``T_a_b`` (4, 4) maps homogeneous coordinates expressed in frame b
to frame a, so ``T_0_2 = T_0_1 @ T_1_2``.  A homogeneous point is ``(x, y, z, 1)``.
"""
import numpy as np

IDENTITY = np.eye(4)


def skew(v):
    """(3,) -> (3, 3) cross-product matrix, skew(a) @ b == cross(a, b)."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def rotation_about_axis(axis, angle):
    """(3, 3) rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=float)
    k = skew(a)
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def translation(x=0.0, y=0.0, z=0.0):
    """(4, 4) pure translation by (x, y, z) m."""
    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t


def rot_x(angle):
    """(4, 4) rotation about x by ``angle`` rad."""
    return homogeneous(rotation_about_axis((1.0, 0.0, 0.0), angle))


def rot_y(angle):
    """(4, 4) rotation about y by ``angle`` rad."""
    return homogeneous(rotation_about_axis((0.0, 1.0, 0.0), angle))


def rot_z(angle):
    """(4, 4) rotation about z by ``angle`` rad."""
    return homogeneous(rotation_about_axis((0.0, 0.0, 1.0), angle))


def homogeneous(rotation=None, position=None):
    """(4, 4) transform from a (3, 3) rotation and a (3,) position in m."""
    t = np.eye(4)
    if rotation is not None:
        t[:3, :3] = rotation
    if position is not None:
        t[:3, 3] = position
    return t


def inverse(t):
    """Inverse of a rigid (4, 4) transform."""
    r = t[:3, :3]
    out = np.eye(4)
    out[:3, :3] = r.T
    out[:3, 3] = -r.T @ t[:3, 3]
    return out


def rpy_to_rotation(roll, pitch, yaw):
    """URDF convention: R = Rz(yaw) @ Ry(pitch) @ Rx(roll) (fixed axes x, y, z)."""
    return (rotation_about_axis((0, 0, 1), yaw) @ rotation_about_axis((0, 1, 0), pitch)
            @ rotation_about_axis((1, 0, 0), roll))


def rotation_to_rpy(r):
    """Inverse of :func:`rpy_to_rotation`; returns (roll, pitch, yaw) in rad."""
    pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
    if np.cos(pitch) > 1e-12:
        roll = np.arctan2(r[2, 1], r[2, 2])
        yaw = np.arctan2(r[1, 0], r[0, 0])
    else:  # gimbal lock: put everything in yaw
        roll = 0.0
        yaw = np.arctan2(-r[0, 1], r[1, 1])
    return roll, pitch, yaw


def revolute_generator(axis):
    """(4, 4) se(3) generator Q with dM/dq = M Q for a rotation about unit ``axis``."""
    g = np.zeros((4, 4))
    g[:3, :3] = skew(axis)
    return g


def prismatic_generator(axis):
    """(4, 4) se(3) generator Q with dM/dq = M Q for a translation along unit ``axis``."""
    g = np.zeros((4, 4))
    g[:3, 3] = axis
    return g


def revolute_motion(axis, angle):
    """(4, 4) joint motion for a revolute joint."""
    return homogeneous(rotation_about_axis(axis, angle))


def prismatic_motion(axis, displacement):
    """(4, 4) joint motion for a prismatic joint (displacement in m)."""
    return homogeneous(position=np.asarray(axis, dtype=float) * displacement)

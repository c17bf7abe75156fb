"""Rigid transforms as 4x4 matrices and quaternions (``xyzw`` ROS order, ``wxyz`` MuJoCo)."""

from __future__ import annotations

import numpy as np

from replay.messages import F64

#: MuJoCo cameras look along -z with y up; the optical frame looks along +z with y down.
OPTICAL_FROM_MJCAMERA = np.diag([1.0, -1.0, -1.0])


def frame_from_axes(position_m: F64, *, forward: F64, right: F64) -> F64:
    """``world_from_camera`` (4, 4) of an optical frame with z = ``forward``, x = ``right``."""
    z = np.asarray(forward, dtype=np.float64)
    x = np.asarray(right, dtype=np.float64)
    if np.linalg.norm(z) < 1e-9 or np.linalg.norm(x) < 1e-9:
        raise ValueError("forward and right must be non-zero vectors")
    z = z / np.linalg.norm(z)
    x = x - z * (x @ z)
    if np.linalg.norm(x) < 1e-9:
        raise ValueError("forward and right must not be parallel")
    x = x / np.linalg.norm(x)
    y = np.cross(z, x)
    out = np.eye(4)
    out[:3, :3] = np.column_stack([x, y, z])
    out[:3, 3] = position_m
    return out


def rotation_from_rpy(rpy: F64) -> F64:
    """Rotation (3, 3) = Rz(yaw) @ Ry(pitch) @ Rx(roll)."""
    roll, pitch, yaw = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    rotation: F64 = rz @ ry @ rx
    return rotation


def rotation_about(axis: F64, angle_rad: float) -> F64:
    """Rotation (3, 3) by ``angle_rad`` about unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    rotation: F64 = np.eye(3) + np.sin(angle_rad) * k + (1 - np.cos(angle_rad)) * (k @ k)
    return rotation


def quat_xyzw_from_rotation(rotation: F64) -> F64:
    """Unit quaternion (4,) ``[x, y, z, w]`` with w >= 0 of a rotation matrix (3, 3)."""
    m = np.asarray(rotation, dtype=np.float64)
    t = np.trace(m)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = np.array([(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s,
                      0.25 * s])
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        q = np.zeros(4)
        q[i] = 0.25 * s
        q[j] = (m[j, i] + m[i, j]) / s
        q[k] = (m[k, i] + m[i, k]) / s
        q[3] = (m[k, j] - m[j, k]) / s
    q = q / np.linalg.norm(q)
    out: F64 = -q if q[3] < 0 else q
    return out


def rotation_from_quat_xyzw(q: F64) -> F64:
    """Rotation matrix (3, 3) of a quaternion ``[x, y, z, w]``."""
    x, y, z, w = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def transform_from_pose(position_m: F64, orientation_xyzw: F64) -> F64:
    """Rigid transform (4, 4) of a position (3,) and a quaternion ``[x, y, z, w]``."""
    out = np.eye(4)
    out[:3, :3] = rotation_from_quat_xyzw(orientation_xyzw)
    out[:3, 3] = position_m
    return out


def invert(transform: F64) -> F64:
    """Inverse of a rigid transform (4, 4)."""
    out = np.eye(4)
    out[:3, :3] = transform[:3, :3].T
    out[:3, 3] = -transform[:3, :3].T @ transform[:3, 3]
    return out

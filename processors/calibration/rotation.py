"""Rotation vectors (Rodrigues, as OpenCV's ``rvec``) and matrices, vectorised."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from replay.messages import F64

#: below this angle (rad) the first-order expansions are exact to double precision
_SMALL = 1e-8
#: rotation pairs compared at once by :func:`support` (8 bytes each)
SUPPORT_BLOCK = 1 << 18


def matrices(rvecs: F64) -> F64:
    """Rotation matrices ``(K, 3, 3)`` of rotation vectors ``(K, 3)``.

    ``R = I + sin(t) / t [r]x + (1 - cos t) / t^2 [r]x^2`` with ``t = |r|``.
    """
    rvecs = np.asarray(rvecs, dtype=np.float64).reshape(-1, 3)
    angle = np.linalg.norm(rvecs, axis=1)
    small = angle < _SMALL
    safe = np.where(small, 1.0, angle)
    a = np.where(small, 1.0, np.sin(safe) / safe)
    b = np.where(small, 0.5, (1.0 - np.cos(safe)) / (safe * safe))
    k = np.zeros((len(rvecs), 3, 3))  # cross-product matrices [r]x
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -rvecs[:, 2], rvecs[:, 1], -rvecs[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = rvecs[:, 2], -rvecs[:, 1], rvecs[:, 0]
    out: F64 = np.eye(3) + a[:, None, None] * k + b[:, None, None] * (k @ k)
    return out


def rotation_vectors(rotations: F64) -> F64:
    """Rotation vectors ``(K, 3)`` of rotation matrices ``(K, 3, 3)`` (angles below pi)."""
    rotations = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    cos = np.clip((np.trace(rotations, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(cos)
    axis = np.stack([rotations[:, 2, 1] - rotations[:, 1, 2],
                     rotations[:, 0, 2] - rotations[:, 2, 0],
                     rotations[:, 1, 0] - rotations[:, 0, 1]], axis=1)
    sin = np.sin(angle)
    scale = np.where(sin > 1e-12, angle / (2.0 * np.where(sin > 1e-12, sin, 1.0)), 0.5)
    out: F64 = axis * scale[:, None]
    near_pi = cos < -0.999
    for i in np.flatnonzero(near_pi):  # rare: axis from the symmetric part
        sym = (rotations[i] + np.eye(3)) / 2.0
        column = int(np.argmax(np.diag(sym)))
        unit = sym[:, column] / np.sqrt(max(sym[column, column], 1e-300))
        out[i] = unit * angle[i]
        if np.allclose(matrices(out[i:i + 1])[0], rotations[i], atol=1e-6):
            continue
        out[i] = -out[i]
    return out


def nearest_rotation(matrix: F64) -> F64:
    """The rotation ``(3, 3)`` closest to ``matrix`` ``(3, 3)`` in the Frobenius norm (a sum of
    rotations: their mean)."""
    u, _s, vt = np.linalg.svd(np.asarray(matrix, dtype=np.float64))
    out: F64 = u @ np.diag([1.0, 1.0, float(np.linalg.det(u @ vt))]) @ vt
    return out


def rigid_fit(points_in_a: F64, points_in_b: F64) -> F64:
    """``b_from_a`` ``(4, 4)``: the rigid transform that best maps ``points_in_a`` ``(N, 3)``
    onto ``points_in_b`` ``(N, 3)`` in the least-squares sense (Kabsch)."""
    centre_a, centre_b = points_in_a.mean(axis=0), points_in_b.mean(axis=0)
    rotation = nearest_rotation((points_in_b - centre_b).T @ (points_in_a - centre_a))
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = centre_b - rotation @ centre_a
    return out


def support(rotations: F64, within_rad: float, *, group: int = 1) -> npt.NDArray[np.int64]:
    """Per rotation of ``rotations`` ``(K, 3, 3)``, how many of its groups of ``group``
    consecutive rotations hold one less than ``within_rad`` from it (itself included).

    The angle between ``a`` and ``b`` is ``acos((trace(a^T b) - 1) / 2)`` and ``trace(a^T b)``
    is the dot product of their entries: the ``K^2`` comparisons are one matrix product per
    block of rows, with memory bounded by :data:`SUPPORT_BLOCK`."""
    entries = np.asarray(rotations, dtype=np.float64).reshape(-1, 9)
    limit = 1.0 + 2.0 * math.cos(within_rad)
    rows = max(1, SUPPORT_BLOCK // max(len(entries), 1))
    out = np.empty(len(entries), dtype=np.int64)
    for start in range(0, len(entries), rows):
        traces = (entries[start:start + rows] @ entries.T).reshape(-1, len(entries) // group,
                                                                   group)
        out[start:start + rows] = np.count_nonzero(traces.max(axis=2) > limit, axis=1)
    return out


def within(rotations: F64, reference: F64, within_rad: float) -> npt.NDArray[np.bool_]:
    """``(K,)`` which of ``rotations`` ``(K, 3, 3)`` lie less than ``within_rad`` from
    ``reference`` ``(3, 3)`` (as :func:`support` counts them)."""
    traces = np.asarray(rotations, dtype=np.float64).reshape(-1, 9) @ reference.reshape(9)
    return np.asarray(traces > 1.0 + 2.0 * math.cos(within_rad))

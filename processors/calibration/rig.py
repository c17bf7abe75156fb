"""A rig's transforms between any two cameras, with their covariance from the joint solve.

The joint calibration (:mod:`.joint`) places every camera relative to camera 0, the
reference: ``camera_from_reference = [R | t]``, moved by increments ``d = (dr, dt)`` as
``R <- exp([dr]x) R``, ``t <- t + dt``, with their covariance from the joint problem. The
transform from camera ``a`` to camera ``b``, ``b_from_a = b_from_reference a_from_reference^-1``
(``R = Rb Ra^T``, ``t = tb - R ta``), moves to first order by

    dr = drb - R dra
    dt = dtb - R dta - R [ta]x dra + [R ta]x drb

so its covariance ``(6, 6)`` (same increments) is ``J C J^T`` with ``C`` the joint covariance
``(12, 12)`` of both cameras' rig unknowns (their coupling included).
"""

from __future__ import annotations

import math

import numpy as np

from replay.messages import F64

from .joint import JointResult

__all__ = ["angle_deg", "relative_pose", "rotation_std_deg", "translation_std_m"]


def _skew(v: F64) -> F64:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def relative_pose(joint: JointResult, a: int, b: int,
                  global_covariance: F64 | None = None) -> tuple[F64, F64]:
    """``b_from_a`` ``(4, 4)`` and its covariance ``(6, 6)`` (rotation increment in rad,
    then translation in m); from the reference (``a = 0``) the joint result's own rig
    transform and covariance. ``global_covariance`` ``(G, G)``: the joint problem's, when
    already computed."""
    if a == 0:
        return joint.camera_from_reference[b], joint.rig_covariance[b]
    a_from_reference, b_from_reference = joint.camera_from_reference[a], \
        joint.camera_from_reference[b]
    rotation_a, translation_a = a_from_reference[:3, :3], a_from_reference[:3, 3]
    rotation = b_from_reference[:3, :3] @ rotation_a.T
    b_from_a = np.eye(4)
    b_from_a[:3, :3] = rotation
    b_from_a[:3, 3] = b_from_reference[:3, 3] - rotation @ translation_a
    covariance = joint.problem.global_covariance() if global_covariance is None \
        else global_covariance
    columns = joint.problem.layout.rig_columns
    both = np.concatenate([columns[a], columns[b]]) if b else np.asarray(columns[a])
    jacobian = np.zeros((6, 12))
    jacobian[:3, :3] = -rotation
    jacobian[3:, :3] = -rotation @ _skew(translation_a)
    jacobian[3:, 3:6] = -rotation
    jacobian[:3, 6:9] = np.eye(3)
    jacobian[3:, 6:9] = _skew(rotation @ translation_a)
    jacobian[3:, 9:] = np.eye(3)
    if not b:  # the reference has no unknowns
        jacobian = jacobian[:, :6]
    return b_from_a, jacobian @ covariance[np.ix_(both, both)] @ jacobian.T


def angle_deg(rotation: F64) -> float:
    """Angle of a rotation ``(3, 3)`` (degrees)."""
    cosine = (float(np.trace(rotation)) - 1) / 2
    return math.degrees(math.acos(max(-1.0, min(1.0, cosine))))


def rotation_std_deg(covariance: F64) -> float:
    """Standard deviation of a transform's rotation in its worst direction (degrees), from
    its covariance ``(6, 6)``."""
    return math.degrees(math.sqrt(max(float(np.linalg.eigvalsh(covariance[:3, :3]).max()),
                                      0.0)))


def translation_std_m(covariance: F64, direction: F64) -> float:
    """Standard deviation of a transform's translation along a unit ``direction`` ``(3,)``
    (m), e.g. of the baseline along the translation itself."""
    return math.sqrt(max(float(direction @ covariance[3:, 3:] @ direction), 0.0))

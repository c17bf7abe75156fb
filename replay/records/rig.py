"""The rig part of the calibration summary: every camera's pose and every pair's figures.

Poses are ``camera_from_reference``: they map points from the reference camera's optical
frame (the first camera's) into the camera's, ``X_camera = R X_reference + t``. Rotations are
rotation vectors (axis times angle, rad); standard deviations are those of the increments the
solver moves them by (``R <- exp([d]x) R``, ``t <- t + dt``), per axis, from the joint
covariance of every camera's intrinsics, the rig and every board pose.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .base import OMIT_NONE

__all__ = ["RigCameraSummary", "RigCameraTruth", "RigPairSummary", "RigPairTruth",
           "RigSummary"]


@dataclass(frozen=True)
class RigCameraTruth:
    """The simulator's ``camera_from_reference`` and the estimate's error: ``rotation_error_rad``
    is the increment that takes the true rotation to the estimate, ``translation_error_m``
    the estimate minus the truth."""

    rotation_rad: list[float]
    translation_m: list[float]
    rotation_error_rad: list[float]
    translation_error_m: list[float]


@dataclass(frozen=True)
class RigCameraSummary:
    """One camera's ``camera_from_reference``, with per-axis standard deviations."""

    namespace: str
    frame_id: str
    rotation_rad: list[float]
    rotation_std_rad: list[float]
    translation_m: list[float]
    translation_std_m: list[float]
    rotation_deg: float  # angle of the rotation
    truth: RigCameraTruth | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class RigPairTruth:
    """The simulator's baseline and rotation angle of a pair."""

    baseline_m: float
    rotation_deg: float


@dataclass(frozen=True)
class RigPairSummary:
    """Two cameras that saw the board at the same instants: ``second_from_first``'s
    translation (m) and rotation angle, with the standard deviations of the baseline and of
    the rotation in its worst direction, the reprojection RMS of their joint views and the
    epipolar RMS after rectifying the pair."""

    first: str
    second: str
    joint_views: int
    baseline_m: float
    baseline_std_m: float
    rotation_deg: float
    rotation_std_deg: float
    translation_m: list[float]
    rms_px: float
    epipolar_rms_px: float
    truth: RigPairTruth | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class RigSummary:
    """A rig calibrated jointly: every camera's pose relative to ``reference`` and every
    pair that shares views."""

    reference: str
    convention: str  # "camera_from_reference"
    cameras: list[RigCameraSummary]
    pairs: list[RigPairSummary]

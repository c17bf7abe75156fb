"""OpenCV's calibration functions for each lens model: its pinhole family or ``cv2.fisheye``.

:data:`OPENCV_LENSES` gives every model of :data:`replay.lens_models.LENS_MODELS` (by its ROS
name) the functions calibration takes from OpenCV: the calibration that seeds the joint
refinement (with the flags that hold what the options fix), the stereo rectification, the
new camera matrix of camera_calibration's ``P`` (alpha 0: only valid pixels) and the
refinement of a board pose on the distorted corners (``solvePnP``; the fisheye family has
none, PnP on the undistorted corners stands).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.lens_models import canonical_name, lens_model
from replay.messages import F64

from .options import CalibrationOptions

__all__ = ["FISHEYE", "OPENCV_LENSES", "PINHOLE", "OpenCVLens", "opencv_lens"]

CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-10)

#: ``(points (M_i, 3) per view, corners (M_i, 2) per view, (width, height), options)`` ->
#: ``K`` (3, 3), ``D`` (N,); raises ``cv2.error``
Calibrate = Callable[[list[F64], list[F64], tuple[int, int], CalibrationOptions],
                     tuple[F64, F64]]
#: ``(left, right, rotation (3, 3), translation (3, 1))`` -> ``R1, R2`` (3, 3), ``P1, P2`` (3, 4)
StereoRectify = Callable[[CameraModel, CameraModel, F64, F64], tuple[F64, F64, F64, F64]]
#: ``(points (M, 3), corners (M, 2), model, camera_from_board (4, 4))`` -> refined pose
RefinePose = Callable[[F64, F64, CameraModel, F64], F64]


@dataclass(frozen=True)
class OpenCVLens:
    """One family of OpenCV's calibration functions (``name``: ``pinhole`` or ``fisheye``;
    see the module docstring)."""

    name: str
    calibrate: Calibrate
    stereo_rectify: StereoRectify
    new_camera_matrix: Callable[[CameraModel], F64]  # (3, 3)
    refine_pose: RefinePose


def _pinhole_flags(options: CalibrationOptions) -> int:
    flags = cv2.CALIB_FIX_PRINCIPAL_POINT if options.fix_principal_point else 0
    if options.fix_aspect_ratio:
        flags |= cv2.CALIB_FIX_ASPECT_RATIO
    if options.tangential == "zero":
        flags |= cv2.CALIB_ZERO_TANGENT_DIST
    selects = lens_model(options.distortion_model).opencv_flag
    if selects:
        flags |= int(getattr(cv2, selects))
    for n, flag in enumerate((cv2.CALIB_FIX_K1, cv2.CALIB_FIX_K2, cv2.CALIB_FIX_K3,
                              cv2.CALIB_FIX_K4, cv2.CALIB_FIX_K5, cv2.CALIB_FIX_K6), 1):
        if options.radial_count < n:
            flags |= flag
    return flags


def _fisheye_flag(name: str) -> int:
    """OpenCV 4's ``cv2.fisheye.CALIB_*`` flags are ``cv2.CALIB_*`` in OpenCV 5."""
    flag = getattr(cv2.fisheye, f"CALIB_{name}", None)
    return int(flag if flag is not None else getattr(cv2, f"CALIB_{name}"))


def _fisheye_flags(options: CalibrationOptions) -> int:
    flags = _fisheye_flag("RECOMPUTE_EXTRINSIC") | _fisheye_flag("FIX_SKEW") \
        | _fisheye_flag("USE_INTRINSIC_GUESS")
    if options.fix_principal_point:
        flags |= _fisheye_flag("FIX_PRINCIPAL_POINT")
    for n in range(options.radial_count + 1, 5):
        flags |= _fisheye_flag(f"FIX_K{n}")
    return flags


def _calibrate_pinhole(points: list[F64], corners: list[F64], size: tuple[int, int],
                       options: CalibrationOptions) -> tuple[F64, F64]:
    coefficients = len(lens_model(options.distortion_model).coefficients)
    _rms, k, d, _r, _t = cv2.calibrateCamera(
        [p.astype(np.float32).reshape(1, -1, 3) for p in points],
        [c.astype(np.float32).reshape(1, -1, 2) for c in corners], size, np.eye(3),
        np.zeros(coefficients), flags=_pinhole_flags(options), criteria=CRITERIA)
    return np.asarray(k, dtype=np.float64), np.asarray(d, dtype=np.float64)


def _calibrate_fisheye(points: list[F64], corners: list[F64], size: tuple[int, int],
                       options: CalibrationOptions) -> tuple[F64, F64]:
    width, height = size
    # an equidistant lens seeing 180 degrees across the image
    k0 = np.array([[max(size) / math.pi, 0, (width - 1) / 2],
                   [0, max(size) / math.pi, (height - 1) / 2], [0, 0, 1]])
    _rms, k, d, _r, _t = cv2.fisheye.calibrate(
        [p.astype(np.float64).reshape(1, -1, 3) for p in points],
        [c.astype(np.float64).reshape(1, -1, 2) for c in corners], size, k0, np.zeros(4),
        flags=_fisheye_flags(options), criteria=CRITERIA)
    return np.asarray(k, dtype=np.float64), np.asarray(d, dtype=np.float64)


def _float64(*matrices: npt.ArrayLike) -> tuple[F64, F64, F64, F64]:
    r1, r2, p1, p2 = (np.asarray(m, dtype=np.float64) for m in matrices)
    return r1, r2, p1, p2


def _rectify_pinhole(left: CameraModel, right: CameraModel, rotation: F64, translation: F64
                     ) -> tuple[F64, F64, F64, F64]:
    r1, r2, p1, p2, _q, _roi1, _roi2 = cv2.stereoRectify(
        left.k, left.d, right.k, right.d, (left.width, left.height), rotation, translation,
        flags=cv2.CALIB_ZERO_DISPARITY, alpha=0.0)
    return _float64(r1, r2, p1, p2)


def _rectify_fisheye(left: CameraModel, right: CameraModel, rotation: F64, translation: F64
                     ) -> tuple[F64, F64, F64, F64]:
    # cv2.fisheye reshapes its inputs: a column of a pose matrix must be copied first
    r1, r2, p1, p2, _q = cv2.fisheye.stereoRectify(
        left.k, left.d, right.k, right.d, (left.width, left.height),
        np.ascontiguousarray(rotation), np.ascontiguousarray(translation),
        flags=cv2.CALIB_ZERO_DISPARITY, balance=0.0)
    return _float64(r1, r2, p1, p2)


def _new_pinhole_matrix(model: CameraModel) -> F64:
    new_k, _roi = cv2.getOptimalNewCameraMatrix(model.k, model.d, (model.width, model.height),
                                                0.0)
    return np.asarray(new_k, dtype=np.float64)


def _new_fisheye_matrix(model: CameraModel) -> F64:
    return np.asarray(cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(
        model.k, model.d, (model.width, model.height), np.eye(3), balance=0.0),
        dtype=np.float64)


def _refine_pinhole_pose(points: F64, corners_px: F64, model: CameraModel, pose: F64) -> F64:
    cv_pose = cv2.solvePnP(points, corners_px, model.k, model.d, flags=cv2.SOLVEPNP_ITERATIVE,
                           useExtrinsicGuess=True, rvec=cv2.Rodrigues(pose[:3, :3])[0],
                           tvec=pose[:3, 3].copy())
    if cv_pose[0]:
        pose[:3, :3] = cv2.Rodrigues(cv_pose[1])[0]
        pose[:3, 3] = np.asarray(cv_pose[2]).reshape(3)
    return pose


def _pose_as_is(_points: F64, _corners_px: F64, _model: CameraModel, pose: F64) -> F64:
    return pose


#: OpenCV's pinhole functions (``calibrateCamera``, ``stereoRectify``, ...)
PINHOLE = OpenCVLens("pinhole", _calibrate_pinhole, _rectify_pinhole, _new_pinhole_matrix,
                     _refine_pinhole_pose)
#: ``cv2.fisheye``'s functions
FISHEYE = OpenCVLens("fisheye", _calibrate_fisheye, _rectify_fisheye, _new_fisheye_matrix,
                     _pose_as_is)

#: every lens model's OpenCV functions, by its ROS ``distortion_model``
OPENCV_LENSES: dict[str, OpenCVLens] = {
    "plumb_bob": PINHOLE,
    "rational_polynomial": PINHOLE,
    "equidistant": FISHEYE,
}


def opencv_lens(distortion_model: str) -> OpenCVLens:
    """The OpenCV functions of a lens model (or one of its aliases)."""
    return OPENCV_LENSES[canonical_name(distortion_model)]

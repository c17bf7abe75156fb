"""A calibration against the simulator's truth, and a plain OpenCV script on the same detections.

Both camlog's result and the OpenCV reference are reduced to the same :class:`Accuracy`:
focal length error (%), principal point error (px), the max projection difference against the
true model over the image with a 16 px margin (camera frames aligned by a rotation, as mrcal's
projection difference with an implied rotation; a fisheye only within 80° of its axis) and,
for a stereo pair, the error of the rotation between the cameras (degrees) and of the baseline
(%). Every figure is the worst over the cameras.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from camlog.calibrate.flow import CalibrationRun
from camlog.calibrate.solving import CalibratedCamera
from camlog.calibrate.views import DetectedFrame
from processors.calibration.board import Board
from processors.calibration.validation import projection_difference
from replay.camera import CameraModel
from replay.messages import F64

MARGIN_PX = 16
STEP_PX = 8
#: a fisheye is compared within this angle of its optical axis
FISHEYE_AXIS_DEG = 80.0


@dataclass(frozen=True)
class Accuracy:
    """Errors against the truth, worst over the cameras; ``max_difference_px`` per camera."""

    focal_percent: float  # signed, the largest |fx| or |fy| error
    cx_px: float
    cy_px: float
    max_difference_px: list[float]
    rotation_deg: float | None = None
    baseline_percent: float | None = None
    fx_percent: float | None = None  # signed, the largest |fx| error over the cameras
    fy_percent: float | None = None
    principal_px: float | None = None  # the largest principal point distance


def compared_pixels(truth: CameraModel) -> F64:
    """The grid pixels ``(N, 2)`` the projection difference is taken over."""
    us, vs = np.meshgrid(np.arange(MARGIN_PX, truth.width - MARGIN_PX + 1, STEP_PX),
                         np.arange(MARGIN_PX, truth.height - MARGIN_PX + 1, STEP_PX))
    pixels = np.column_stack([us.ravel(), vs.ravel()]).astype(np.float64)
    if truth.is_fisheye:
        rays = truth.pixel_rays(pixels)
        angle = np.degrees(np.arccos(np.clip(rays[:, 2] / np.linalg.norm(rays, axis=1),
                                             -1.0, 1.0)))
        pixels = pixels[np.isfinite(angle) & (angle <= FISHEYE_AXIS_DEG)]
    return pixels


def max_difference_px(model: CameraModel, truth: CameraModel) -> float:
    """Max distance between where ``truth`` and ``model`` image the same ray (aligned)."""
    return float(np.nanmax(projection_difference(model, truth, compared_pixels(truth))))


def rotation_deg(a: F64, b: F64) -> float:
    """Angle (degrees) of the rotation between the 3x3 rotations ``a`` and ``b``."""
    cos = (np.trace(a @ b.T) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, float(cos)))))


def accuracy(models: list[CameraModel], truths: list[CameraModel],
             right_from_left: F64 | None = None, true_right_from_left: F64 | None = None
             ) -> Accuracy:
    """The errors of ``models`` against ``truths`` (and of a stereo rig, with both given)."""
    pairs = list(zip(models, truths, strict=True))
    fx, fy = (max((100 * (m.k[i, i] - t.k[i, i]) / t.k[i, i] for m, t in pairs), key=abs)
              for i in (0, 1))
    focal = max(fx, fy, key=abs)
    principal = max(math.hypot(m.k[0, 2] - t.k[0, 2], m.k[1, 2] - t.k[1, 2]) for m, t in pairs)
    cx = max((m.k[0, 2] - t.k[0, 2] for m, t in zip(models, truths, strict=True)), key=abs)
    cy = max((m.k[1, 2] - t.k[1, 2] for m, t in zip(models, truths, strict=True)), key=abs)
    rotation = baseline = None
    if right_from_left is not None and true_right_from_left is not None:
        rotation = rotation_deg(right_from_left[:3, :3], true_right_from_left[:3, :3])
        true_b = float(np.linalg.norm(true_right_from_left[:3, 3]))
        baseline = 100 * (float(np.linalg.norm(right_from_left[:3, 3])) - true_b) / true_b
    return Accuracy(float(focal), float(cx), float(cy),
                    [max_difference_px(m, t) for m, t in zip(models, truths, strict=True)],
                    rotation, baseline, float(fx), float(fy), principal)


def true_models(run: CalibrationRun) -> list[CameraModel]:
    """The simulator's camera models of a run's cameras."""
    out = []
    for camera in run.cameras:
        assert camera.truth is not None, "the log has no ground truth"
        out.append(camera.truth.model())
    return out


def true_right_from_left(run: CalibrationRun) -> F64 | None:
    """The simulator's ``right_from_left`` (4, 4) of a stereo run (None: mono)."""
    if len(run.cameras) != 2:
        return None
    left, right = (c.truth for c in run.cameras)
    assert left is not None and right is not None, "the log has no ground truth"
    return np.asarray(np.linalg.inv(right.world_from_camera) @ left.world_from_camera,
                      dtype=np.float64)


def camlog_accuracy(run: CalibrationRun) -> Accuracy:
    """camlog's result against the truth."""
    return accuracy([c.model for c in run.cameras], true_models(run),
                    run.solved.stereo.right_from_left if run.solved.stereo is not None else None,
                    true_right_from_left(run))


def detected(camera: CalibratedCamera) -> list[DetectedFrame]:
    """The frames a plain script calibrates from: every distinct frame whose board passed
    detection."""
    return [f for f in camera.views.frames if f.candidate and f.detection is not None]


def nominal_focal_px(truth: CameraModel) -> float:
    """The focal length a user would start a peer from: the true fx to the nearest 100 px
    (what a lens's data sheet gives)."""
    return float(round(float(truth.k[0, 0]), -2))


def _calibrate_one(objects: list[F64], images: list[F64], size: tuple[int, int],
                   truth: CameraModel) -> CameraModel:
    """``cv2.calibrateCamera`` with default flags in the true lens model; for a fisheye
    ``cv2.fisheye.calibrate`` started, as mrcal is, from :func:`nominal_focal_px` at the
    image centre (without a start OpenCV 5 takes fx = max(W, H) / 2, 320 px for a 232 px
    lens, and stops with its ``InitExtrinsics`` assertion)."""
    if truth.is_fisheye:
        focal = nominal_focal_px(truth)
        start = np.array([[focal, 0.0, (size[0] - 1) / 2], [0.0, focal, (size[1] - 1) / 2],
                          [0.0, 0.0, 1.0]])
        _rms, k, d, _r, _t = cv2.fisheye.calibrate(
            [o.reshape(1, -1, 3) for o in objects], [i.reshape(1, -1, 2) for i in images],
            size, start, np.zeros(4), flags=cv2.CALIB_RECOMPUTE_EXTRINSIC | cv2.CALIB_FIX_SKEW
            | cv2.CALIB_USE_INTRINSIC_GUESS)
        return CameraModel(size[0], size[1], np.asarray(k, dtype=np.float64), "equidistant",
                           np.asarray(d, dtype=np.float64).reshape(-1)[:4])
    rational = truth.distortion_model == "rational_polynomial"
    _rms, k, d, _r, _t = cv2.calibrateCamera(
        [o.astype(np.float32) for o in objects], [i.astype(np.float32) for i in images],
        size, None, None, flags=cv2.CALIB_RATIONAL_MODEL if rational else 0)
    return CameraModel(size[0], size[1], np.asarray(k, dtype=np.float64),
                       truth.distortion_model,
                       np.asarray(d, dtype=np.float64).reshape(-1)[:8 if rational else 5])


def opencv_reference(run: CalibrationRun, board: Board) -> Accuracy:
    """A plain OpenCV script on the same detections (:func:`opencv_models`) against the
    truth."""
    models, right_from_left = opencv_models(run, board)
    return accuracy(models, true_models(run), right_from_left, true_right_from_left(run))


def opencv_models(run: CalibrationRun, board: Board) -> tuple[list[CameraModel], F64 | None]:
    """A plain OpenCV script on the same detections: each camera calibrated from every
    :func:`detected` frame, then for a pair ``cv2.stereoCalibrate`` with its default flags
    (intrinsics fixed) on the pairs camlog paired; the models and ``right_from_left``
    (4, 4) (None: mono)."""
    points = board.points_in_board()
    truths = true_models(run)
    models = []
    for camera, truth in zip(run.cameras, truths, strict=True):
        found = [f.detection for f in detected(camera) if f.detection is not None]
        models.append(_calibrate_one([points[d.ids] for d in found],
                                     [d.corners_px for d in found], camera.views.size, truth))
    if len(models) == 1:
        return models, None
    rig = run.solved.rig
    objects, lefts, rights = [], [], []
    for lv, rv in rig.pairs:
        left, right = rig.views[lv], rig.views[rv]
        shared, li, ri = np.intersect1d(left.point_ids, right.point_ids, return_indices=True)
        if len(shared) >= 4:
            objects.append(points[shared].astype(np.float32))
            lefts.append(left.corners_px[li].astype(np.float32))
            rights.append(right.corners_px[ri].astype(np.float32))
    left_m, right_m = models
    _rms, _k1, _d1, _k2, _d2, rotation, translation, _e, _f = cv2.stereoCalibrate(
        objects, lefts, rights, left_m.k, left_m.d, right_m.k, right_m.d,
        (left_m.width, left_m.height))
    right_from_left = np.eye(4)
    right_from_left[:3, :3], right_from_left[:3, 3] = rotation, np.ravel(translation)
    return models, right_from_left

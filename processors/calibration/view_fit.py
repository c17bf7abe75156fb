"""Measure an existing calibration on views of a board (camera_calibration's checks)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from .board import Board
from .discs import view_centroids
from .opencv_lens import opencv_lens
from .seed import board_pose

#: pose fits of a circle grid's view, at most: the disc shift settles in a few
MAX_ROUNDS = 10
#: the disc shifts of two pose fits agree within this (px): settled
SETTLED_PX = 1e-7


def linearity_error(corners_px: F64, model: CameraModel, board: Board) -> float:
    """RMS distance (px) of undistorted corners from the line through each row's ends.

    camera_calibration's "linear error": a perfect model makes every row of board corners a
    straight line once lens distortion is removed.
    """
    undistorted = model.undistort_pixels(corners_px) * [model.fx, model.fy]
    rows = np.asarray(undistorted, dtype=np.float64).reshape(board.rows, board.cols, 2)
    errors = []
    for row in rows:
        a, b = row[0], row[-1]
        direction = b - a
        length = math.hypot(*direction)
        if length == 0:
            continue
        offsets = row - a
        errors.append(np.abs(offsets[:, 0] * direction[1] - offsets[:, 1] * direction[0]) / length)
    if not errors:
        return float("nan")
    return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))


@dataclass(frozen=True)
class ViewFit:
    """One view with its board pose fitted: ``camera_from_board`` (4, 4); ``predicted_px``
    ``(M, 2)``, where the detector should see each point (a circle grid's: the centroid of
    its disc's image); ``centres_px`` ``(M, 2)``, the detections moved onto the points'
    projections by that disc shift (the detections themselves for point targets); the RMS
    distance (px) of the detections from the prediction."""

    camera_from_board: F64
    predicted_px: F64
    centres_px: F64
    rms_px: float

    @classmethod
    def of(cls, camera_from_board: F64, predicted_px: F64, corners_px: F64,
           shift_px: F64) -> ViewFit:
        """The fit of the detections ``corners_px`` with the disc shift ``shift_px``."""
        rms = float(np.sqrt(np.mean(np.sum((predicted_px - corners_px) ** 2, axis=1))))
        return cls(camera_from_board, predicted_px, corners_px - shift_px, rms)


def fit_view(corners_px: F64, model: CameraModel, points_in_board: F64, *,
             disc_diameter_m: float | None = None) -> ViewFit | None:
    """The board pose of one view (PnP, refined by OpenCV for pinhole lenses); None when it
    fails. With ``disc_diameter_m`` the points are centres of circles that diameter across
    seen as their discs' centroids: as in the solver (:mod:`.discs`), the pose is fitted to
    the detections moved by the disc shift, which is recomputed at each pose until it
    settles."""
    pose = _pose(points_in_board, corners_px, model)
    if pose is None:
        return None
    shift = np.zeros_like(corners_px)
    if disc_diameter_m is None:
        projected = model.project(points_in_board @ pose[:3, :3].T + pose[:3, 3])
        return ViewFit.of(pose, projected, corners_px, shift)
    for rounds in range(1, MAX_ROUNDS + 1):
        centre_px, centroid_px = view_centroids(model, pose, points_in_board,
                                                radius_m=disc_diameter_m / 2.0)
        previous, shift = shift, centroid_px - centre_px
        if float(np.abs(shift - previous).max(initial=0.0)) <= SETTLED_PX \
                or rounds == MAX_ROUNDS:
            break
        moved = _pose(points_in_board, corners_px - shift, model)
        if moved is None:
            return None
        pose = moved
    return ViewFit.of(pose, centroid_px, corners_px, shift)


def _pose(points: F64, corners_px: F64, model: CameraModel) -> F64 | None:
    pose = board_pose(points, corners_px, model)
    if pose is None:
        return None
    return opencv_lens(model.distortion_model).refine_pose(points, corners_px, model, pose)


def reprojection_rms(corners_px: F64, model: CameraModel, board: Board,
                     point_ids: np.ndarray | None = None, *,
                     disc_diameter_m: float | None = None) -> float:
    """RMS reprojection error (px) of one view (of the points ``point_ids``, default all)
    with the board pose fitted (:func:`fit_view`; ``disc_diameter_m``: a circle grid's
    circles, seen as their discs' centroids)."""
    points = board.points_in_board()
    if point_ids is not None:
        points = points[point_ids]
    fit = fit_view(corners_px, model, points, disc_diameter_m=disc_diameter_m)
    return float("nan") if fit is None else fit.rms_px

"""Measure an existing calibration on views of a board (camera_calibration's checks)."""

from __future__ import annotations

import math

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from .board import Board
from .seed import board_pose


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


def reprojection_rms(corners_px: F64, model: CameraModel, board: Board,
                     point_ids: np.ndarray | None = None) -> float:
    """RMS reprojection error (px) of one view (of the points ``point_ids``, default all)
    with the board pose fitted (PnP, then refined by the joint solver's model)."""
    points = board.points_in_board()
    if point_ids is not None:
        points = points[point_ids]
    pose = board_pose(points, corners_px, model)
    if pose is None:
        return float("nan")
    cv_pose = cv2.solvePnP(points, corners_px, model.k, model.d, flags=cv2.SOLVEPNP_ITERATIVE,
                           useExtrinsicGuess=True, rvec=cv2.Rodrigues(pose[:3, :3])[0],
                           tvec=pose[:3, 3].copy()) if not model.is_fisheye else None
    if cv_pose is not None and cv_pose[0]:
        pose[:3, :3] = cv2.Rodrigues(cv_pose[1])[0]
        pose[:3, 3] = np.asarray(cv_pose[2]).reshape(3)
    projected = model.project(points @ pose[:3, :3].T + pose[:3, 3])
    return float(np.sqrt(np.mean(np.sum((projected - corners_px) ** 2, axis=1))))

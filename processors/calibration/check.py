"""Measure an existing calibration on views of a board (camera_calibration's checks)."""

from __future__ import annotations

import math

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from .board import Board


def linearity_error(corners_px: F64, model: CameraModel, board: Board) -> float:
    """RMS distance (px) of undistorted corners from the line through each row's ends.

    camera_calibration's "linear error": a perfect model makes every row of board corners a
    straight line once lens distortion is removed.
    """
    undistorted = cv2.undistortPoints(corners_px.reshape(-1, 1, 2), model.k, model.d, P=model.k)
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


def reprojection_rms(corners_px: F64, model: CameraModel, board: Board) -> float:
    """RMS reprojection error (px) of one view with the board pose fitted (solvePnP)."""
    points = board.points_in_board()
    ok, rvec, tvec = cv2.solvePnP(points, corners_px, model.k, model.d,
                                  flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        return float("nan")
    projected, _ = cv2.projectPoints(points, rvec, tvec, model.k, model.d)
    return float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - corners_px) ** 2, axis=1))))

"""The calibration a log carries (its camera_info) beside camlog's, on the views camlog used.

A log imported from camera_calibration's archive carries that tool's result as camera_info; a
robot's log carries whatever its driver published. Both models are measured the same way on
the same views: each used view's board pose fitted to the model (PnP, refined; the log's model
on a flat board, camlog's on the board as it estimated it, bowed when it estimated a warp), the
reprojection RMS over the corners camlog kept; and the two models are compared where they
image one ray (:func:`~processors.calibration.mono.max_projection_difference`, after the
rotation that best aligns the camera frames: intrinsic calibration cannot observe it). For a
pair, the rig the two camera_infos imply (:func:`~replay.camera.stereo_right_from_left`)
against camlog's. A simulated log is compared with its truth instead.
"""

from __future__ import annotations

import math

import numpy as np

from processors.calibration.board import Board
from processors.calibration.mono import max_projection_difference
from processors.calibration.opencv_lens import opencv_lens
from processors.calibration.rig import angle_deg
from processors.calibration.view_fit import fit_view
from processors.calibration.warp import warped
from replay.camera import CameraModel, stereo_right_from_left
from replay.errors import ReplayError
from replay.messages import F64
from replay.records import LogCalibration, LogStereoCalibration

from .solving import CalibratedCamera, RigSolution

__all__ = ["log_calibration", "log_stereo_calibration"]


def _log_model(camera: CalibratedCamera) -> CameraModel | None:
    """The model of the log's camera_info; None without one, in a simulated log, or when
    it is not a model (zero focal length, a lens model camlog does not know)."""
    info = camera.views.log_info
    if info is None or camera.truth is not None or not (info.k[0, 0] > 0 and info.k[1, 1] > 0):
        return None
    try:
        return CameraModel.from_camera_info(info)
    except (ReplayError, ValueError, KeyError):
        return None


def _view_rms_px(model: CameraModel, corners_px: F64, flat: F64, bowed: F64,
                 diameter_m: float | None) -> float:
    """One view's reprojection RMS (px) with its pose fitted to the board ``bowed`` (N, 3):
    fitted on the ``flat`` board first (PnP needs a plane), then refined; nan when it
    fails."""
    fit = fit_view(corners_px, model, flat, disc_diameter_m=diameter_m)
    if fit is None:
        return math.nan
    if bowed is flat:
        return fit.rms_px
    pose = opencv_lens(model.distortion_model).refine_pose(bowed, corners_px, model,
                                                           fit.camera_from_board)
    projected = model.project(bowed @ pose[:3, :3].T + pose[:3, 3])
    return float(np.sqrt(np.mean(np.sum((projected - corners_px) ** 2, axis=1))))


def _rms_px(model: CameraModel, camera: CalibratedCamera, solved: RigSolution, *,
            flat: F64, bowed: F64) -> float:
    """Reprojection RMS (px) of ``model`` over the corners of the camera's used views that
    camlog kept (a corner it left out as an outlier would swamp both models' figure), each
    view's board pose fitted to it with the board points ``bowed`` (N, 3) (a view it cannot
    fit makes the figure nan)."""
    diameter = solved.circles.diameter_m if solved.circles is not None else None
    squares, count = 0.0, 0
    for v in solved.used_views(camera):
        view, kept = solved.rig.views[v], solved.joint.inliers[v]
        ids = view.point_ids[kept]
        rms = _view_rms_px(model, view.corners_px[kept], flat[ids],
                           flat[ids] if bowed is flat else bowed[ids], diameter)
        squares += rms ** 2 * len(ids)
        count += len(ids)
    return math.sqrt(squares / count) if count else math.nan


def log_calibration(camera: CalibratedCamera, solved: RigSolution,
                    board: Board) -> LogCalibration | None:
    """The log's camera_info beside camlog's model (None: the log has none to compare)."""
    theirs = _log_model(camera)
    if theirs is None or (theirs.width, theirs.height) != (camera.model.width,
                                                            camera.model.height):
        return None
    seen = np.concatenate(solved.used_corners(camera))
    # each model on the board it was solved with: the log's flat, camlog's as it estimated it
    flat = board.points_in_board()
    warp = solved.joint.board_warp_m
    bowed = warped(flat, warp[0]) if warp is not None else flat
    return LogCalibration(
        info_topic=camera.views.source.info_topic or "",
        distortion_model=theirs.distortion_model,
        fx=theirs.fx, fy=theirs.fy, cx=theirs.cx, cy=theirs.cy,
        rms_px=_rms_px(theirs, camera, solved, flat=flat, bowed=flat),
        camlog_rms_px=_rms_px(camera.model, camera, solved, flat=flat, bowed=bowed),
        max_projection_difference_px=max_projection_difference(camera.model, theirs,
                                                               align_rotation=True),
        max_projection_difference_covered_px=max_projection_difference(
            camera.model, theirs, within=seen, align_rotation=True))


def log_stereo_calibration(solved: RigSolution) -> LogStereoCalibration | None:
    """The rig of the log's two camera_infos beside camlog's (None: they imply none)."""
    left, right = solved.cameras
    if solved.stereo is None or _log_model(left) is None or _log_model(right) is None:
        return None
    assert left.views.log_info is not None and right.views.log_info is not None
    theirs = stereo_right_from_left(left.views.log_info, right.views.log_info)
    if theirs is None:
        return None
    baseline_m = float(np.linalg.norm(theirs[:3, 3]))
    ours = solved.stereo.right_from_left
    return LogStereoCalibration(
        baseline_m=baseline_m,
        baseline_difference_percent=100 * (solved.stereo.baseline_m - baseline_m) / baseline_m,
        rotation_difference_deg=angle_deg(ours[:3, :3] @ theirs[:3, :3].T))

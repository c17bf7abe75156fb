"""Intrinsic calibration of one camera: every view in one least-squares problem.

:func:`~.joint.calibrate_cameras` with one camera (its result is the joint result, camera
0): outlier corners are left out one by one (views that are not the board whole), tangential
distortion is estimated when the views show it (see :mod:`.options`), and every parameter
comes with its standard deviation. Also the CameraInfo a mono calibration publishes and projection
differences between two models.
"""

from __future__ import annotations

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64, CameraInfo

from .bundle import cross
from .joint import MIN_VIEWS, BoardView, JointResult, calibrate_cameras
from .lens import intrinsics_of, project
from .opencv_lens import opencv_lens
from .options import (
    TANGENTIAL_P_VALUE,
    CalibrationOptions,
    TangentialTest,
    tangential_mode,
)
from .rotation import matrices

__all__ = [
    "MIN_VIEWS",
    "TANGENTIAL_P_VALUE",
    "CalibrationOptions",
    "TangentialTest",
    "calibrate_mono",
    "max_projection_difference",
    "mono_camera_info",
    "tangential_mode",
]


def calibrate_mono(points_in_board: F64, corners: list[F64], size: tuple[int, int],
                   options: CalibrationOptions, *, reject_outliers: bool = True,
                   point_ids: list[np.ndarray] | None = None,
                   weights: list[float] | None = None) -> JointResult:
    """Calibrate camera 0 from views ``corners[i]`` ``(M_i, 2)`` of the board points
    ``(N, 3)`` (all of them in order, or ``point_ids[i]``), each weighted by ``weights[i]``;
    view ``i`` is board pose ``i``."""
    ids = point_ids or [np.arange(len(points_in_board))] * len(corners)
    weight = weights or [1.0] * len(corners)
    views = [BoardView(0, i, np.asarray(ids[i], dtype=np.int64), c, weight[i])
             for i, c in enumerate(corners)]
    return calibrate_cameras(points_in_board, views, [size], options,
                             reject_outliers=reject_outliers)


def mono_camera_info(model: CameraModel, frame_id: str) -> CameraInfo:
    """Calibrated CameraInfo; P is camera_calibration's (alpha 0: only valid pixels)."""
    p = np.zeros((3, 4))
    p[:, :3] = opencv_lens(model.distortion_model).new_camera_matrix(model)
    return CameraInfo(0, frame_id, model.width, model.height, model.distortion_model,
                      model.d, model.k, np.eye(3), p)


def max_projection_difference(a: CameraModel, b: CameraModel, step_px: int = 8,
                              within: F64 | None = None, *, align_rotation: bool = False) -> float:
    """Largest pixel distance between where ``a`` and ``b`` image the same ray.

    Over the whole image, or only inside the convex hull of the points ``within`` (N, 2),
    e.g. every corner the calibration saw: outside it a model only extrapolates.

    With ``align_rotation`` the rays of ``a`` are first turned by the rotation that best
    maps them onto ``b`` (least squares in pixels). Intrinsic calibration cannot observe a
    rotation of the camera frame: the board poses absorb it, and a principal point shift of
    δ px with tangential distortion is nearly such a rotation at a narrow field of view. The
    aligned difference is what two models disagree on once their frames agree, as mrcal's
    projection difference with an implied rotation.
    """
    us, vs = np.meshgrid(np.arange(0, a.width, step_px, dtype=np.float64),
                         np.arange(0, a.height, step_px, dtype=np.float64))
    pixels = np.column_stack([us.ravel(), vs.ravel()])
    if within is not None:
        hull = cv2.convexHull(np.asarray(within, dtype=np.float32).reshape(-1, 1, 2))
        inside = [cv2.pointPolygonTest(hull, (float(u), float(v)), False) >= 0
                  for u, v in pixels]
        pixels = pixels[np.asarray(inside, dtype=bool)]
    rays_in_a = a.pixel_rays(pixels)
    keep = np.isfinite(rays_in_a).all(axis=1)
    rays_in_a, pixels = rays_in_a[keep], pixels[keep]
    b_from_a = best_rotation(rays_in_a, pixels, b) if align_rotation else np.eye(3)
    uv = b.project(rays_in_a @ b_from_a.T)
    return float(np.linalg.norm(uv - pixels, axis=1).max())


def best_rotation(rays: F64, pixels: F64, model: CameraModel, iterations: int = 20) -> F64:
    """Rotation ``R`` (3, 3) minimising the pixel error of ``model`` imaging ``R rays``
    ``(N, 3)`` at ``pixels`` ``(N, 2)`` (Gauss-Newton on ``R <- exp([d]x) R`` from the
    identity: the rotation is small)."""
    turn = np.eye(3)
    intrinsics = intrinsics_of(model)
    for _ in range(iterations):
        turned = rays @ turn.T
        uv, d_point, _ = project(model.distortion_model, intrinsics, turned)
        jacobian = cross(turned[:, None, :], d_point).reshape(-1, 3)
        step = np.linalg.lstsq(jacobian, -(uv - pixels).reshape(-1), rcond=None)[0]
        turn = matrices(np.asarray(step, dtype=np.float64)[None])[0] @ turn
        if np.abs(step).max() < 1e-12:
            break
    return turn

"""Cross-validation: the evidence split in two disjoint halves, calibrated separately, compared
in the terms of the projection uncertainty.

The halves are every other board point of every view: both see every board pose, so they can
be compared as :mod:`.uncertainty` measures an error (mrcal's mean frames): the point half A
puts at a pixel (at ``range_m``: far away, rays) is carried into every board frame by A's
poses and back by B's, then imaged by B (:func:`~.uncertainty.error_against`). Splitting by
views instead leaves the halves no pose in common; compared through the full calibration's
poses they cannot show the error of the mean over the poses (each view's pose error is the
same in a half and in the whole), and compared after the rotation that best aligns the
cameras (mrcal's implied rotation, :func:`projection_difference`) they leave out every error
that turns the camera frame, which the mean over the poses keeps.

Scaling, to first order: each half has half the corners, so its estimate is off by ``d_A``
with covariance ``2 S`` (``S``: the full calibration's covariance; half the information,
twice the variance), independently of the other. Their difference ``d_A - d_B`` has ``4 S``:
half of it, a factor ``sqrt(4 S / S) = 2``, is distributed as the full calibration's own error,
without trusting the noise model's scale. It does assume the corners' errors independent: an
error shared by a view's corners, or a lens model that fits every view alike, is the same in
both halves and invisible here.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError
from .joint import MIN_VIEWS, BoardView, JointResult, calibrate_cameras, camera_views
from .options import CalibrationOptions
from .robust import MIN_VIEW_POINTS
from .uncertainty import GRID_STEP_PX, OverImage, error_against, grid


@dataclass(frozen=True)
class CrossValidation(OverImage):
    """``error_px`` ``(rows, cols)``: the full calibration's error expected at the grid pixels
    ``pixels`` ``(rows, cols, 2)`` of one camera, half the halves' difference there (RMS of
    the two directions of comparison); its worst and median over the image are the full
    calibration's expected worst and median errors."""

    camera: int
    pixels: F64
    error_px: F64

    @property
    def values_px(self) -> F64:
        """The expected error ``error_px``."""
        return self.error_px


def projection_difference(a: CameraModel, b: CameraModel, pixels: F64, *,
                          align_rotation: bool = True) -> F64:
    """Distance ``(...)`` between where ``b`` images the rays ``a`` sees at ``pixels``
    ``(..., 2)`` and ``pixels``, after the rotation that best maps one onto the other."""
    from .mono import best_rotation

    flat = pixels.reshape(-1, 2)
    rays = a.pixel_rays(flat)
    keep = np.isfinite(rays).all(axis=1)
    out = np.full(len(flat), np.nan)
    turn = best_rotation(rays[keep], flat[keep], b) if align_rotation else np.eye(3)
    out[keep] = np.linalg.norm(b.project(rays[keep] @ turn.T) - flat[keep], axis=1)
    return out.reshape(pixels.shape[:-1])


def halves(views: list[BoardView]) -> list[list[BoardView]]:
    """Every view split into its even- and odd-numbered points (a view's half with fewer than
    :data:`~.robust.MIN_VIEW_POINTS` points left out)."""
    out: list[list[BoardView]] = [[], []]
    for view in views:
        for half, part in enumerate(out):
            keep = view.point_ids % 2 == half
            if keep.sum() >= MIN_VIEW_POINTS:
                part.append(BoardView(view.camera, view.instant, view.point_ids[keep],
                                      view.corners_px[keep], speed_px=view.speed_px))
    return out


def _difference_px(a: JointResult, b: JointResult, camera: int, pixels: F64,
                   range_m: float) -> F64:
    """Length ``(rows, cols)`` of where ``b`` images the points ``a`` puts at ``pixels``,
    carried through the poses of the instants both solved, minus ``pixels``."""
    problem = b.problem
    poses = {int(problem.instants[p]): b.reference_from_board[int(problem.instants[p])]
             for p in np.flatnonzero(problem.normal.seen)}
    error = error_against(a.problem, camera, b.models[camera],
                          true_camera_from_reference=b.camera_from_reference[camera],
                          true_reference_from_board=poses, range_m=range_m, pixels=pixels)
    return np.asarray(np.linalg.norm(error, axis=-1), dtype=np.float64)


def cross_validate(points_in_board: F64, views: list[BoardView], sizes: list[tuple[int, int]],
                   options: list[CalibrationOptions], *, range_m: float,
                   step_px: int = GRID_STEP_PX,
                   disc_diameter_m: float | None = None) -> list[CrossValidation] | None:
    """Per camera, half the halves' difference for points at ``range_m``; None when a half
    would have fewer than :data:`~.joint.MIN_VIEWS` views of some camera, or does not solve
    (its views leave an unknown free: a statistic, not the calibration, is then missing).
    ``disc_diameter_m``: as :func:`~.joint.calibrate_cameras`'s."""
    parts = halves(views)
    for part in parts:
        for camera in range(len(sizes)):
            if len(camera_views(part, camera)) < MIN_VIEWS:
                return None

    def solve(part: list[BoardView]) -> JointResult:
        return calibrate_cameras(points_in_board, part, sizes, options,
                                 disc_diameter_m=disc_diameter_m)

    try:
        # the halves side by side: their solves are mostly numpy on long arrays, which lets
        # go of the GIL (each half's result is the same either way)
        with ThreadPoolExecutor(max_workers=2, thread_name_prefix="camlog-half") as pool:
            a, b = pool.map(solve, parts)
    except (ProcessorError, np.linalg.LinAlgError):  # a half that does not solve: no figure
        return None
    out = []
    for camera, size in enumerate(sizes):
        pixels = grid(size, step_px)
        squared = [_difference_px(a, b, camera, pixels, range_m) ** 2,
                   _difference_px(b, a, camera, pixels, range_m) ** 2]
        out.append(CrossValidation(camera, pixels, np.sqrt(np.mean(squared, axis=0)) / 2))
    return out

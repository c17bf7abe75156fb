"""Cross-validation: two disjoint halves of the instants, calibrated separately, compared.

Each half has half the evidence, so each is off by about sqrt(2) times the full
calibration's error, independently; the halves differ by about twice the full calibration's
error. The reported figure is that difference over the image, halved: it estimates the
error of the calibration from every view, in the same units as the projection uncertainty
(:mod:`.uncertainty`), without trusting the noise model. The halves know nothing of each
other's board poses, so the difference is taken after the rotation that best aligns their
camera frames (mrcal's implied rotation), for rays (points far away).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from .joint import MIN_VIEWS, BoardView, calibrate_cameras
from .options import CalibrationOptions
from .uncertainty import GRID_STEP_PX, grid


@dataclass(frozen=True)
class CrossValidation:
    """``difference_px`` ``(rows, cols)``: how far apart the two halves image the rays of
    the grid pixels ``pixels`` ``(rows, cols, 2)`` of one camera."""

    camera: int
    pixels: F64
    difference_px: F64

    @property
    def worst_px(self) -> float:
        """Expected worst error of the full calibration: half the worst difference."""
        return float(np.nanmax(self.difference_px)) / 2.0

    @property
    def median_px(self) -> float:
        """Expected median error of the full calibration: half the median difference."""
        return float(np.nanmedian(self.difference_px)) / 2.0


def projection_difference(a: CameraModel, b: CameraModel, pixels: F64, *,
                          align_rotation: bool = True) -> F64:
    """Distance ``(...)`` between where ``b`` images the rays ``a`` sees at ``pixels``
    ``(..., 2)`` and ``pixels``, after the rotation that best maps one onto the other."""
    from .solve import best_rotation

    flat = pixels.reshape(-1, 2)
    rays = a.pixel_rays(flat)
    keep = np.isfinite(rays).all(axis=1)
    out = np.full(len(flat), np.nan)
    turn = best_rotation(rays[keep], flat[keep], b) if align_rotation else np.eye(3)
    out[keep] = np.linalg.norm(b.project(rays[keep] @ turn.T) - flat[keep], axis=1)
    return out.reshape(pixels.shape[:-1])


def cross_validate(points_in_board: F64, views: list[BoardView], sizes: list[tuple[int, int]],
                   options: list[CalibrationOptions], *, seed: int = 0,
                   step_px: int = GRID_STEP_PX) -> list[CrossValidation] | None:
    """Per camera, the halves' difference; None when a half would have fewer than
    :data:`~.joint.MIN_VIEWS` views of some camera."""
    instants = np.unique([v.instant for v in views])
    order = np.random.default_rng(seed).permutation(instants)
    halves = [set(order[: len(order) // 2].tolist()), set(order[len(order) // 2:].tolist())]
    parts = [[v for v in views if v.instant in half] for half in halves]
    for part in parts:
        for camera in range(len(sizes)):
            if sum(v.camera == camera for v in part) < MIN_VIEWS:
                return None
    models = [calibrate_cameras(points_in_board, part, sizes, options).models for part in parts]
    return [CrossValidation(camera, grid(size, step_px),
                            projection_difference(models[0][camera], models[1][camera],
                                                  grid(size, step_px)))
            for camera, size in enumerate(sizes)]

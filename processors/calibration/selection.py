"""Which views to calibrate from: camera_calibration's coverage parameters, chosen better.

camera_calibration describes a view by four numbers in [0, 1] — board X and Y position,
size and skew — and keeps a view when it lies at L1 distance > 0.2 from every view kept so
far, in arrival order. Here the same descriptors drive a farthest-point selection over all
candidate views: each pick is the view that adds the most new coverage, so the result does
not depend on the order frames arrive in and redundant views are left out first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from replay.messages import F64

from .board import Board

PARAMETERS = ("X", "Y", "size", "skew")
#: ranges camera_calibration expects each parameter to cover for a good calibration
GOOD_RANGES = np.array([0.7, 0.7, 0.4, 0.5])
MIN_DISTANCE = 0.2


def outside_corners(corners_px: F64, board: Board) -> F64:
    """The 4 outer corners (up-left, up-right, down-right, down-left) ``(4, 2)``."""
    grid = corners_px.reshape(board.rows, board.cols, 2)
    return np.array([grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0]])


def _angle(a: F64, b: F64, c: F64) -> float:
    ab, cb = a - b, c - b
    cos = float(ab @ cb / (np.linalg.norm(ab) * np.linalg.norm(cb)))
    return math.acos(max(-1.0, min(1.0, cos)))


def _cross(a: F64, b: F64) -> float:
    """z of the cross product of two 2-D vectors (NumPy 2 deprecates ``np.cross`` on them)."""
    return float(a[0] * b[1] - a[1] * b[0])


def view_parameters(corners_px: F64, board: Board, size: tuple[int, int],
                    point_ids: np.ndarray | None = None) -> F64:
    """camera_calibration's (X, Y, size, skew) of one view, each in [0, 1]. A view of some
    of the points (``point_ids``) is described by the whole board where the homography of
    the points it shows puts it."""
    width, height = size
    if point_ids is not None and len(point_ids) < board.corner_count:
        plane = board.points_in_board()[:, :2]
        homography, _mask = cv2.findHomography(plane[point_ids].astype(np.float64),
                                               corners_px.astype(np.float64))
        corners_px = np.asarray(cv2.perspectiveTransform(plane.reshape(-1, 1, 2), homography),
                                dtype=np.float64).reshape(-1, 2)
    ul, ur, dr, dl = outside_corners(corners_px, board)
    a, b, c = ur - ul, dr - ur, dl - dr
    area = abs(_cross(b + c, a + b)) / 2.0  # half the cross product of the diagonals
    skew = min(1.0, 2.0 * abs(math.pi / 2.0 - _angle(ul, ur, dr)))
    border = math.sqrt(area)
    mean = corners_px.mean(axis=0)
    x = min(1.0, max(0.0, (mean[0] - border / 2) / (width - border)))
    y = min(1.0, max(0.0, (mean[1] - border / 2) / (height - border)))
    return np.array([x, y, math.sqrt(area / (width * height)), skew])


@dataclass(frozen=True)
class Coverage:
    """Per-parameter (min, max, progress) and the share of image cells holding a corner."""

    ranges: dict[str, tuple[float, float, float]]
    image_cells: float

    @property
    def good_enough(self) -> bool:
        """Whether every view parameter's range is fully covered."""
        return all(p >= 1.0 for _, _, p in self.ranges.values())

    def bars(self) -> str:
        """Text progress bars like camera_calibration's display."""
        lines = []
        for name, (lo, hi, progress) in self.ranges.items():
            filled = round(progress * 20)
            lines.append(f"{name:>5} [{'#' * filled}{'.' * (20 - filled)}] {100 * progress:3.0f}% "
                         f"({lo:.2f}..{hi:.2f})")
        lines.append(f"image cells with corners: {100 * self.image_cells:.0f}%")
        return "\n".join(lines)


def coverage(params: F64, corners_px: list[F64], size: tuple[int, int],
             cells: tuple[int, int] = (8, 6)) -> Coverage:
    """Coverage of selected views ``params (N, 4)`` and their corners."""
    ranges = {}
    for i, name in enumerate(PARAMETERS):
        lo, hi = (float(params[:, i].min()), float(params[:, i].max())) if len(params) else (0, 0)
        ranges[name] = (lo, hi, min(1.0, (hi - lo) / GOOD_RANGES[i]))
    hit = np.zeros(cells[::-1], dtype=bool)
    for corners in corners_px:
        cx = np.clip((corners[:, 0] / size[0] * cells[0]).astype(int), 0, cells[0] - 1)
        cy = np.clip((corners[:, 1] / size[1] * cells[1]).astype(int), 0, cells[1] - 1)
        hit[cy, cx] = True
    return Coverage(ranges, float(hit.mean()))


def select_views(params: F64, *, max_views: int, min_distance: float = MIN_DISTANCE) -> list[int]:
    """Indices of views chosen by farthest-point sampling in parameter space.

    Starts from the view farthest from the mean, then repeatedly adds the view whose L1
    distance to the chosen set is largest, while it exceeds ``min_distance``.
    """
    n = len(params)
    if n == 0:
        return []
    first = int(np.argmax(np.abs(params - params.mean(axis=0)).sum(axis=1)))
    chosen = [first]
    distance = np.abs(params - params[first]).sum(axis=1)
    while len(chosen) < min(max_views, n):
        best = int(np.argmax(distance))
        if distance[best] <= min_distance:
            break
        chosen.append(best)
        distance = np.minimum(distance, np.abs(params - params[best]).sum(axis=1))
    return sorted(chosen)

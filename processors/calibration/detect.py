"""Chessboard detection with checks that reject partial and false detections.

OpenCV's detector can return a grid that is not the board: a board cut by the image border
may be "found" one row off, its outer row laid on the white margin. Every detection is
therefore checked square by square: around each inner corner the four squares must
alternate dark / bright with the board's parity. A shifted grid puts "squares" on the
margin and fails this check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from replay.messages import F64

from .board import Board

#: corners closer than this to the image border are left out of a view: their refinement
#: window is cut by the border (camera_calibration rejects the whole view at 8 px)
BORDER_PX = 8.0
#: fewest chessboard corners left inside the border that still make a view
MIN_INSIDE_CORNERS = 6
#: fraction of corners whose four squares may fail the parity check (noise, blur)
PARITY_TOLERANCE = 0.08
MIN_CONTRAST = 12.0
#: a tracked board with a corner that does not settle back within this fraction of a square
#: (:func:`unsettled_px`) is found afresh instead: tracking through motion blur can let an
#: outer corner slide along the board's edge, a little further each frame, while every other
#: corner stays right and every square still alternates
MAX_UNSETTLED = 0.1
#: squares are sampled this far (in squares, along both grid axes) from a corner: well inside
#: a square even where perspective or a fisheye shrinks the outer squares, or the board's
#: edge cuts them (half a square lands on the edge there)
SAMPLE_AT = 0.35


@dataclass(frozen=True)
class Detection:
    """A board found in one image: ``corners_px`` ``(M, 2)`` of the board points
    ``point_ids`` ``(M,)`` (None: every point, in board order); a circle grid's also the
    circles' diameter the image shows (m, None when not measured)."""

    corners_px: F64
    accepted: bool
    reason: str = ""  # why a found board was rejected
    point_ids: npt.NDArray[np.int64] | None = None
    diameter_m: float | None = None

    @property
    def ids(self) -> npt.NDArray[np.int64]:
        """The board points seen, ``(M,)``."""
        if self.point_ids is None:
            return np.arange(len(self.corners_px), dtype=np.int64)
        return self.point_ids


def find_chessboard(gray: np.ndarray, board: Board, *, thorough: bool = False
                    ) -> Detection | None:
    """Detect ``board`` in a ``(H, W)`` uint8 image; None when no board is found.

    OpenCV's classic detector with its fast check first (a few ms on a frame without a
    board); ``thorough`` (a photo, whose view no neighbouring frame can replace) then tries
    the classic detector without the fast check and the sector-based one
    (``findChessboardCornersSB``), which find boards on strongly distorted lenses and under
    uneven light that the fast check turns away, at up to tens of times the cost."""
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(gray, board.pattern_size,
                                               flags=flags | cv2.CALIB_CB_FAST_CHECK)
    if thorough and not found:
        found, corners = cv2.findChessboardCornersSB(gray, board.pattern_size,
                                                     flags=cv2.CALIB_CB_EXHAUSTIVE)
    if thorough and not found:
        found, corners = cv2.findChessboardCorners(gray, board.pattern_size, flags=flags)
    if not found or corners is None or len(corners) != board.corner_count:
        return None
    corners = corners.reshape(-1, 2).astype(np.float32)
    spacing = _min_spacing(corners, board)
    radius = max(2, min(11, math.ceil(spacing * 0.5)))
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 60, 0.001)
    refined = cv2.cornerSubPix(gray, corners.reshape(-1, 1, 2), (radius, radius), (-1, -1),
                               criteria).reshape(-1, 2).astype(np.float64)
    refined = canonical_order(refined, board)
    return check_detection(gray, refined, board)


def track_chessboard(gray: np.ndarray, predicted_px: F64, board: Board) -> Detection | None:
    """The board near where it is expected: ``cornerSubPix`` from ``predicted_px``
    ``(N, 2)`` (e.g. the previous frame's corners moved on by the board's velocity), kept
    only if every corner stayed within a third of a square of its prediction (so none slid
    to a neighbouring corner), settles back when started elsewhere (:func:`unsettled_px`: it
    is a junction of squares, not a point of a blurred edge) and the result passes the same
    checks as a detection. None otherwise: detect the board afresh."""
    spacing = _min_spacing(predicted_px, board)
    if not spacing > 4.0:
        return None
    radius = max(2, min(11, math.ceil(spacing * 0.5)))
    h, w = gray.shape
    if (predicted_px < radius + 1).any() or (predicted_px[:, 0] > w - 2 - radius).any() \
            or (predicted_px[:, 1] > h - 2 - radius).any():
        return None  # a window would leave the image: detect afresh
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 60, 0.001)
    start = predicted_px.astype(np.float32).reshape(-1, 1, 2)
    refined = cv2.cornerSubPix(gray, start.copy(), (radius, radius), (-1, -1),
                               criteria).reshape(-1, 2).astype(np.float64)
    if float(np.linalg.norm(refined - predicted_px, axis=1).max()) > spacing / 3.0:
        return None
    if unsettled_px(gray, refined, board, radius=radius).max(initial=0.0) \
            > MAX_UNSETTLED * spacing:
        return None  # a corner slid along a blurred edge of the board: detect afresh
    found = check_detection(gray, canonical_order(refined, board), board)
    return found if found.accepted and found.point_ids is None else None


def unsettled_px(gray: np.ndarray, corners_px: F64, board: Board, *, radius: int) -> F64:
    """Per corner of a whole board ``(N, 2)``, how far (px) ``cornerSubPix`` (window
    ``radius``) settles from it when started elsewhere: at the straight continuation of its
    two neighbours along a row (a column when rows are shorter than 3), from the board's
    middle outwards. The junction of four squares draws cornerSubPix to it from anywhere in
    the window, whatever the lens and the tilt bend the grid; a point on a blurred edge,
    where tracking lets a corner slide, holds it wherever it starts. Zeros for a board too
    small to continue a line."""
    grid = corners_px.reshape(board.rows, board.cols, 2)
    turned = board.cols < 3
    if turned:
        grid = grid.transpose(1, 0, 2)
    count = grid.shape[1]
    if count < 3:
        return np.zeros(len(corners_px))
    start = np.empty_like(grid)
    for j in range(count):
        step = 1 if j < count / 2 else -1
        start[:, j] = 2 * grid[:, j + step] - grid[:, j + 2 * step]
    if turned:
        start = start.transpose(1, 0, 2)
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 60, 0.001)
    h, w = gray.shape
    start = np.clip(start.reshape(-1, 2), radius + 1, [w - 2 - radius, h - 2 - radius])
    again = cv2.cornerSubPix(gray, start.astype(np.float32).reshape(-1, 1, 2),
                             (radius, radius), (-1, -1), criteria).reshape(-1, 2)
    return np.asarray(np.linalg.norm(again - corners_px, axis=1), dtype=np.float64)


def _min_spacing(corners: np.ndarray, board: Board) -> float:
    grid = corners.reshape(board.rows, board.cols, 2)
    along = np.linalg.norm(np.diff(grid, axis=1), axis=2)
    across = np.linalg.norm(np.diff(grid, axis=0), axis=2)
    return float(min(along.min(), across.min()))


def canonical_order(corners_px: F64, board: Board) -> F64:
    """Reverse the order when OpenCV started from the far end (first corner below the last),
    so that left and right views of a stereo pair agree."""
    if corners_px[0, 1] > corners_px[-1, 1]:
        return np.ascontiguousarray(corners_px[::-1])
    return corners_px


def check_detection(gray: np.ndarray, corners_px: F64, board: Board) -> Detection:
    """Accept a detection only if it alternates like a board in every row and column and is
    not part of a larger board (``--size`` too small); corners within :data:`BORDER_PX` of
    the image border are left out (``point_ids`` then says which remain)."""
    h, w = gray.shape
    if not np.isfinite(corners_px).all():
        return Detection(corners_px, False, "corner refinement failed")
    grid: F64 = corners_px.reshape(board.rows, board.cols, 2)
    # local grid axes; with one axis np.gradient returns a single array
    dx: F64 = np.gradient(grid, axis=1)
    dy: F64 = np.gradient(grid, axis=0)
    rows, cols = np.meshgrid(np.arange(board.rows), np.arange(board.cols), indexing="ij")
    parity = np.where((rows + cols) % 2 == 0, 1.0, -1.0)
    blurred = cv2.blur(gray, (3, 3)).astype(np.float32)
    values = _square_values(blurred, grid, dx, dy)
    # the board's own phase is whichever sign dominates
    phase = 1.0 if np.median((values[0] + values[1] - values[2] - values[3]) * parity) >= 0 \
        else -1.0
    good = _alternates(values, parity * phase)
    worst_line = min(good.mean(axis=1).min(), good.mean(axis=0).min())
    if good.mean() < 1.0 - PARITY_TOLERANCE or worst_line < 0.5:
        return Detection(
            corners_px, False,
            f"squares do not alternate around {100 * (1 - good.mean()):.0f}% of corners "
            "(partial or shifted board)",
        )
    # one step beyond each side: a real board's outer squares meet the plain margin there,
    # so the pattern must stop; if it goes on, the board has more corners than --size
    for line, step, axis_u, axis_v, line_parity in (
        (grid[0], -dy[0], dx[0], dy[0], -parity[0]),
        (grid[-1], dy[-1], dx[-1], dy[-1], -parity[-1]),
        (grid[:, 0], -dx[:, 0], dx[:, 0], dy[:, 0], -parity[:, 0]),
        (grid[:, -1], dx[:, -1], dx[:, -1], dy[:, -1], -parity[:, -1]),
    ):
        beyond = line + step
        margin = 0.5 * float(np.linalg.norm(step, axis=-1).max())
        inside = (beyond[:, 0].min() > margin and beyond[:, 1].min() > margin
                  and beyond[:, 0].max() < w - 1 - margin and beyond[:, 1].max() < h - 1 - margin)
        if not inside:
            continue
        extra = _alternates(_square_values(blurred, beyond[None], axis_u[None], axis_v[None]),
                            (line_parity * phase)[None])
        if extra.mean() >= 0.8:
            return Detection(corners_px, False,
                             f"the board goes on beyond this {board.cols}x{board.rows} grid "
                             "(board size too small?)")
    return _inside_border(corners_px, (w, h), board)


def _inside_border(corners_px: F64, size: tuple[int, int], board: Board) -> Detection:
    """The detection without its corners within :data:`BORDER_PX` of the image border;
    rejected when fewer than :data:`MIN_INSIDE_CORNERS` remain or they lie on one line."""
    w, h = size
    inside = ((corners_px >= BORDER_PX) & (corners_px <= [w - 1 - BORDER_PX, h - 1 - BORDER_PX])
              ).all(axis=1)
    if inside.all():
        return Detection(corners_px, True)
    ids = np.flatnonzero(inside).astype(np.int64)
    kept = corners_px[inside]
    if len(ids) < MIN_INSIDE_CORNERS or len(np.unique(ids // board.cols)) < 2 \
            or len(np.unique(ids % board.cols)) < 2:
        return Detection(corners_px, False,
                         f"touches the image border ({len(ids)} corners inside, need "
                         f"{MIN_INSIDE_CORNERS} not on one line)")
    return Detection(kept, True, point_ids=ids)


def _square_values(blurred: np.ndarray, points: F64, dx: F64, dy: F64) -> np.ndarray:
    """Brightness ``(4, ...)`` inside the squares around each point (:data:`SAMPLE_AT`): the
    two diagonal ones (+x+y, -x-y), then the two anti-diagonal ones."""
    centers = np.stack([points + sx * SAMPLE_AT * dx + sy * SAMPLE_AT * dy
                        for sx, sy in ((1, 1), (-1, -1), (1, -1), (-1, 1))])
    h, w = blurred.shape
    xs = np.clip(np.rint(centers[..., 0]), 0, w - 1).astype(int)
    ys = np.clip(np.rint(centers[..., 1]), 0, h - 1).astype(int)
    return np.asarray(blurred[ys, xs])


def _alternates(values: np.ndarray, signed_parity: np.ndarray) -> np.ndarray:
    """Which points are X-junctions of the expected phase.

    Each square is judged on its own: summed pairs would pass a corner on the board's edge
    (one dark square and three bright ones), where a grid shifted by one row puts its outer
    row.
    """
    diagonal_bright = np.minimum(values[0], values[1]) - np.maximum(values[2], values[3])
    anti_bright = np.minimum(values[2], values[3]) - np.maximum(values[0], values[1])
    return np.asarray(np.where(signed_parity > 0, diagonal_bright, anti_bright) > MIN_CONTRAST)

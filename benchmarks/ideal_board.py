"""A chessboard imaged without noise, and what camlog's corner refinement makes of it.

The image is the exact footprint average of the board over each pixel (``supersample`` x
``supersample`` rays per pixel through the camera model, each ray shaded by the square it
hits: dark 30, bright 220, the margin bright), quantised to 8 bits like a camera's. The
corners are then refined as :func:`processors.calibration.detect.track_chessboard` refines
them, from their true projections; the difference is the refinement's own error, with no
pixel noise at all.
"""

from __future__ import annotations

import numpy as np

from processors.calibration.board import Board
from processors.calibration.detect import track_chessboard
from replay.camera import CameraModel
from replay.messages import F64

DARK, BRIGHT = 30.0, 220.0
#: pixels rendered around the board's corners (the refinement window and the margin squares)
PAD_PX = 40


def ideal_image(model: CameraModel, camera_from_board: F64, board: Board, *,
                supersample: int = 4) -> np.ndarray:
    """``(H, W)`` uint8 image of a chessboard at ``camera_from_board`` ``(4, 4)``; only the
    pixels near the board are rendered (the rest is mid grey)."""
    rotation, translation = camera_from_board[:3, :3], camera_from_board[:3, 3]
    points = board.points_in_board()
    corners_px = model.project(points @ rotation.T + translation)
    low = np.maximum(np.floor(corners_px.min(axis=0)) - PAD_PX, 0).astype(int)
    high = np.minimum(np.ceil(corners_px.max(axis=0)) + PAD_PX,
                      [model.width - 1, model.height - 1]).astype(int)
    image = np.full((model.height, model.width), 128.0)
    us, vs = np.meshgrid(np.arange(low[0], high[0] + 1), np.arange(low[1], high[1] + 1))
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    sub = np.stack(np.meshgrid(offsets, offsets), axis=-1).reshape(-1, 2)
    pixels = (np.stack([us, vs], axis=-1)[:, :, None, :] + sub).reshape(-1, 2)
    rays = model.pixel_rays(pixels)
    normal = rotation[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = (translation @ normal) / (rays @ normal)
    in_board = (rays * depth[:, None] - translation) @ rotation
    step_x = (points[1] - points[0]) / board.square_m
    step_y = (points[board.cols] - points[0]) / board.square_m
    a = (in_board - points[0]) @ step_x / board.square_m
    b = (in_board - points[0]) @ step_y / board.square_m
    hit = np.isfinite(depth) & (depth > 0)
    on_squares = hit & (a > -1) & (a < board.cols) & (b > -1) & (b < board.rows)
    dark = (np.floor(a) + np.floor(b)) % 2 == 0
    shade = np.where(on_squares & dark, DARK, BRIGHT)
    shade[~hit] = 128.0
    image[low[1]:high[1] + 1, low[0]:high[0] + 1] = \
        shade.reshape(*us.shape, supersample * supersample).mean(axis=-1)
    quantised: np.ndarray = np.clip(np.rint(image), 0, 255).astype(np.uint8)
    return quantised


def refinement_error_px(model: CameraModel, camera_from_board: F64, board: Board, *,
                        supersample: int = 4) -> F64 | None:
    """Refined minus true corners ``(N, 2)`` in board order on the ideal image (None when the
    refinement rejects the view, e.g. a board at the image border)."""
    points = board.points_in_board()
    true_px = model.project(points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])
    found = track_chessboard(ideal_image(model, camera_from_board, board,
                                         supersample=supersample), true_px, board)
    if found is None:
        return None
    refined = found.corners_px
    if np.abs(refined[0] - true_px[0]).sum() > np.abs(refined[0] - true_px[-1]).sum():
        refined = refined[::-1]  # put back in board order
    return np.asarray(refined - true_px)

"""Synthetic calibration data: known cameras, random board poses, exact projections.

Everything the solver tests compare against comes from here, so the expectations are the
ground truth the views were made from, never the solver's own output.
"""

from __future__ import annotations

import cv2
import numpy as np

from processors.calibration.board import Board
from processors.calibration.discs import view_centroids
from replay.camera import CameraModel
from replay.messages import F64

W, H = 640, 480
BOARD = Board(8, 6, 0.025)
#: a camera with every parameter away from its default (fx != fy, off-centre principal point)
K_TRUE = np.array([[800.0, 0.0, 326.0], [0.0, 806.0, 233.0], [0.0, 0.0, 1.0]])
D_TRUE = np.array([-0.2, 0.05, 0.0008, -0.0005, 0.0])
#: image margin (px) every synthetic corner keeps from the border
MARGIN_PX = 12.0


def true_model(d: F64 | None = None, k: F64 | None = None) -> CameraModel:
    return CameraModel(W, H, K_TRUE if k is None else k, "plumb_bob",
                       D_TRUE if d is None else d)


def pinhole_model() -> CameraModel:
    return CameraModel(W, H, K_TRUE)


def pose(rvec: F64, tvec: F64) -> F64:
    """``camera_from_board`` (4, 4) from a rotation vector and translation (m)."""
    out = np.eye(4)
    out[:3, :3] = cv2.Rodrigues(np.asarray(rvec, dtype=np.float64))[0]
    out[:3, 3] = tvec
    return out


def project(model: CameraModel, camera_from_board: F64, board: Board = BOARD) -> F64:
    points = board.points_in_board()
    return model.project(points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])


def random_poses(rng: np.random.Generator, count: int, models: list[CameraModel], *,
                 board: Board = BOARD, max_tilt_rad: float = 0.7,
                 camera_from_reference: list[F64] | None = None) -> list[F64]:
    """``count`` poses ``reference_from_board`` whose corners every model sees inside the image.

    The board turns about its centre: tilted up to ``max_tilt_rad`` about an in-plane axis and
    rolled freely, 0.3-0.7 m away. ``camera_from_reference[i]`` places camera ``i``
    (default: every camera at the reference).
    """
    extents = np.array([(board.cols - 1) * board.square_m, (board.rows - 1) * board.square_m, 0])
    board_from_centred = np.eye(4)
    board_from_centred[:3, 3] = -extents / 2
    placements = camera_from_reference or [np.eye(4)] * len(models)
    poses: list[F64] = []
    while len(poses) < count:
        axis_angle = rng.uniform(0, 2 * np.pi)
        tilt = rng.uniform(0, max_tilt_rad) * np.array([np.cos(axis_angle), np.sin(axis_angle), 0])
        roll = pose(np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)]), np.zeros(3))
        z = rng.uniform(0.3, 0.7)
        xy = rng.uniform(-0.45, 0.45, 2) * z * np.array([W, H]) / K_TRUE[0, 0]
        candidate = pose(tilt, np.array([xy[0], xy[1], z])) @ roll @ board_from_centred
        inside = True
        for model, placement in zip(models, placements, strict=True):
            uv = project(model, placement @ candidate, board)
            inside &= bool((uv >= MARGIN_PX).all() and (uv[:, 0] <= W - 1 - MARGIN_PX).all()
                           and (uv[:, 1] <= H - 1 - MARGIN_PX).all())
        if inside:
            poses.append(candidate)
    return poses


def views(model: CameraModel, poses: list[F64], noise_px: float, seed: int,
          board: Board = BOARD) -> list[F64]:
    """Projected corners of every pose plus Gaussian noise of ``noise_px`` per coordinate."""
    rng = np.random.default_rng(seed)
    return [project(model, p, board) + rng.normal(0.0, noise_px, (board.corner_count, 2))
            for p in poses]


def disc_views(model: CameraModel, poses: list[F64], board: Board, radius_m: float
               ) -> list[F64]:
    """What a blob detector measures of a circle grid's circles of ``radius_m`` at every pose
    ``camera_from_board``: the centroids ``(N, 2)`` of their discs' images (no noise)."""
    return [view_centroids(model, p, board.points_in_board(), radius_m=radius_m)[1]
            for p in poses]


def render_board(board: Board, origin_px: tuple[float, float], square_px: float,
                 size: tuple[int, int] = (W, H), supersample: int = 4) -> tuple[np.ndarray, F64]:
    """A fronto-parallel board image ``(H, W)`` uint8 and its true inner corners ``(N, 2)``.

    Squares are drawn ``supersample`` times larger and area-averaged down, so edges are
    anti-aliased like a camera's. The board has a one-square white margin on a grey
    background; its first inner corner lies at ``origin_px`` (pixel centres are integers).
    """
    s = supersample
    w, h = size
    big = np.full((h * s, w * s), 150, np.uint8)
    # a pixel centre u of the small image is the big image's coordinate (u + 0.5) * s
    x0, y0 = (origin_px[0] + 0.5 - square_px) * s, (origin_px[1] + 0.5 - square_px) * s
    q = square_px * s

    def box(c0: float, r0: float, c1: float, r1: float, value: int) -> None:
        cv2.rectangle(big, (round(x0 + c0 * q), round(y0 + r0 * q)),
                      (round(x0 + c1 * q) - 1, round(y0 + r1 * q) - 1), value, -1)

    box(-1, -1, board.cols + 2, board.rows + 2, 235)
    for r in range(board.rows + 1):
        for c in range(board.cols + 1):
            if (r + c) % 2 == 0:
                box(c, r, c + 1, r + 1, 25)
    image = cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA)
    cols, rows = np.meshgrid(np.arange(board.cols), np.arange(board.rows))
    corners = np.column_stack([origin_px[0] + cols.ravel() * square_px,
                               origin_px[1] + rows.ravel() * square_px])
    return image, corners


def warp_texture(texture: np.ndarray, px_per_m: float, origin_px: tuple[float, float],
                 k: F64, camera_from_board: F64, *, size: tuple[int, int] = (W, H),
                 supersample: int = 4) -> np.ndarray:
    """A flat board texture ``(h, w)`` uint8 seen by the pinhole camera ``k`` (3, 3) at
    ``camera_from_board``: texture pixel centre ``p`` shows the board point
    ``((p - origin_px) / px_per_m, 0)``. Rendered ``supersample`` times larger and
    area-averaged down; the background is mid grey."""
    s = supersample
    # board metres -> texture pixel centres, and board metres -> big output pixel centres
    board_from_texture = np.array([[1 / px_per_m, 0, -origin_px[0] / px_per_m],
                                   [0, 1 / px_per_m, -origin_px[1] / px_per_m], [0, 0, 1]])
    plane = k @ np.column_stack([camera_from_board[:3, 0], camera_from_board[:3, 1],
                                 camera_from_board[:3, 3]])
    big_from_small = np.array([[s, 0, (s - 1) / 2], [0, s, (s - 1) / 2], [0, 0, 1]])
    homography = big_from_small @ plane @ board_from_texture
    big = cv2.warpPerspective(texture, homography, (size[0] * s, size[1] * s),
                              flags=cv2.INTER_AREA, borderValue=128)
    return np.asarray(cv2.resize(big, size, interpolation=cv2.INTER_AREA))


def circle_texture(board: Board, px_per_m: float, radius_m: float, supersample: int = 8
                   ) -> tuple[np.ndarray, tuple[float, float]]:
    """A white card with black discs of ``radius_m`` at the board's points, and the texture
    pixel of the first point. Each pixel's darkness is the share of it a disc covers
    (``supersample`` x ``supersample`` samples), so the discs are exactly that size."""
    points = board.points_in_board()[:, :2]
    margin = 2 * radius_m
    extent = points.max(axis=0) + 2 * margin
    texture = np.full((int(extent[1] * px_per_m), int(extent[0] * px_per_m)), 245.0)
    origin = (margin * px_per_m - 0.5, margin * px_per_m - 0.5)
    r = radius_m * px_per_m
    s = supersample
    for x, y in points:
        cu, cv = x * px_per_m + origin[0], y * px_per_m + origin[1]
        u0, v0 = int(cu - r) - 1, int(cv - r) - 1
        n = int(2 * r) + 3
        sub = (np.arange(n * s) + 0.5) / s - 0.5  # sample offsets from the patch's first pixel
        du, dv = np.meshgrid(u0 + sub - cu, v0 + sub - cv)
        covered = (du * du + dv * dv <= r * r).reshape(n, s, n, s).mean(axis=(1, 3))
        texture[v0:v0 + n, u0:u0 + n] -= covered * (245.0 - 15.0)
    return np.asarray(np.rint(texture), dtype=np.uint8), origin

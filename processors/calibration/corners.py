"""Chessboard corners measured again on the board plane, once a camera model and the board's
pose are known (the iterative refinement of control points of Datta et al., 2009).

``cv2.cornerSubPix`` finds the point where the image gradients around it all point away from
it: exact for straight edges, but a strongly distorted or foreshortened square's edges are
curved or unevenly scaled across its window, and the corner comes out biased by up to a
twentieth of a pixel, always the same way at the same place in the image (a bias field the
solver reads as a lens). Here every corner's neighbourhood is resampled onto the board plane:
a small fronto-parallel patch whose samples are board points projected through the model, so
the squares' edges in it are straight and at right angles. The corner is located in the patch
with the same symmetric estimator, the patch moved onto it and the corner located again, and
the board point found there is projected back through the same model: the pixel is where the
image shows the corner, whatever small error the model and pose still have (they only shape
the patch).

A ChArUco board's corners are measured so for every lens (:func:`remeasures`), with another
estimator on the patch (:func:`cross_corners`): its markers begin 1.5 mm from each corner
on a typical board, so OpenCV refines ChArUco corners in windows a few pixels wide (0.06 px
of noise per coordinate on ``mono_charuco``, against 0.04 px for a chessboard's), and a
wider window would let the markers' edges pull the corner. On the board plane the two edges
through the corner are straight lines, and only they are used, as far out as a chessboard's
window reaches: 0.050 px per coordinate there, and 22 % closer to the true corners.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.lens_models import LENS_MODELS
from replay.messages import F64

from .board import Board

__all__ = ["MAX_WINDOW", "OVERSAMPLE", "REMEASURED_MODELS", "cross_corners", "edge_band_m",
           "refine_on_board", "remeasures"]

#: lens models whose chessboard corners calibration measures again on the board plane. On
#: the fisheye, cornerSubPix's corners lie 0.03-0.05 px outwards of the truth, growing with
#: the radius, and the board plane's within 0.01 px; on the pinhole and plumb_bob cameras of
#: the calibration scenarios cornerSubPix's bias is below 0.003 px and measuring again did
#: not make the calibration more accurate
REMEASURED_MODELS = frozenset(name for name, m in LENS_MODELS.items() if m.fisheye)

#: largest half-window of the corner search (image pixels, as cornerSubPix's in detect)
MAX_WINDOW = 11
#: image pixels around the window: room for the search to move and for its gradients
_MARGIN_PX = 3
#: a corner moving further than this fraction of a square is left where it was
_MAX_SHIFT = 0.25
#: patch samples per image pixel: a corner between samples of a patch at the image's own
#: resolution comes out pulled by the resampling (up to 0.04 px), at twice it by 0.002 px
OVERSAMPLE = 2
_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 0.001)


def refine_on_board(gray: np.ndarray, model: CameraModel, camera_from_board: F64,
                    points_in_board: F64, square_m: float, *, rounds: int = 2,
                    band_m: float | None = None) -> tuple[F64, npt.NDArray[np.bool_]]:
    """Pixels ``(M, 2)`` of the board corners ``points_in_board`` ``(M, 3)`` (z = 0) measured
    in the ``(H, W)`` grey image ``gray`` (uint8, or float: e.g. the mean of a held pose's
    frames) on patches of the board plane laid by ``model`` at
    ``camera_from_board`` ``(4, 4)``, ``rounds`` times, each patch centred on the last
    estimate; and which corners were measured ``(M,)`` (not: a patch beyond the image border,
    a search that ran off its patch or moved the corner by more than a quarter square).
    ``band_m`` (:func:`edge_band_m`): locate the corners with :func:`cross_corners` on bands
    that wide along their edges instead of with cornerSubPix."""
    points = np.asarray(points_in_board, dtype=np.float64).reshape(-1, 3)
    rotation, translation = camera_from_board[:3, :3], camera_from_board[:3, 3]

    def pixels(board_points: F64) -> F64:
        return model.project(board_points @ rotation.T + translation)

    # OVERSAMPLE patch samples per image pixel along the board's less foreshortened axis
    step = square_m / 4.0
    steps = np.array([[step, 0, 0], [-step, 0, 0], [0, step, 0], [0, -step, 0]])
    across = pixels((points[None] + steps[:, None]).reshape(-1, 3)).reshape(4, len(points), 2)
    along_x = np.linalg.norm(across[0] - across[1], axis=1)
    along_y = np.linalg.norm(across[2] - across[3], axis=1)
    px_per_m = np.maximum(along_x, along_y) / (2 * step)
    sample_m = 1.0 / (OVERSAMPLE * px_per_m)  # (M,)
    square_samples = float((square_m * OVERSAMPLE * px_per_m).min())
    window = max(2, min(OVERSAMPLE * MAX_WINDOW, math.floor(0.45 * square_samples)))
    margin = _MARGIN_PX * OVERSAMPLE
    half = window + margin
    side = 2 * half + 1
    offsets = np.arange(-half, half + 1, dtype=np.float64) / half
    patch = _monomials(*[g.ravel() for g in np.meshgrid(offsets, offsets)])  # (side², 9)
    # the sample map of a patch is a cubic in the board offset through the centre's exact
    # pixel, fitted to a 5 x 5 grid of projections: exact where the corner is
    coarse = np.linspace(-1.0, 1.0, 5)
    coarse_x, coarse_y = (g.ravel() for g in np.meshgrid(coarse, coarse))
    around = np.flatnonzero((coarse_x != 0) | (coarse_y != 0))
    fit = np.linalg.pinv(_monomials(coarse_x[around], coarse_y[around]))  # (9, 24)
    h, w = gray.shape
    source = gray.astype(np.float32)
    found = points.copy()
    ok = np.ones(len(points), dtype=bool)
    for _ in range(rounds):
        reach = (half * sample_m)[:, None]
        grid = np.zeros((len(points), len(coarse_x), 3))
        grid[..., :2] = found[:, None, :2] + reach[..., None] * np.stack(
            [coarse_x, coarse_y], axis=-1)[None]
        projected = pixels(grid.reshape(-1, 3)).reshape(len(points), len(coarse_x), 2)
        centre_px = projected[:, len(coarse_x) // 2]
        coefficients = fit @ (projected[:, around] - centre_px[:, None])  # (M, 9, 2)
        maps = (centre_px[:, None] + patch @ coefficients).astype(np.float32).reshape(
            len(points) * side, side, 2)
        inside = ((maps >= 0) & (maps <= [w - 1, h - 1])).all(axis=-1)
        ok &= inside.reshape(len(points), -1).all(axis=1)
        patches = cv2.remap(source, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE)
        centres = np.column_stack([np.full(len(points), float(half)),
                                   half + side * np.arange(len(points), dtype=np.float64)])
        if band_m is None:
            located = cv2.cornerSubPix(patches, centres.astype(np.float32).reshape(-1, 1, 2),
                                       (window, window), (-1, -1), _CRITERIA).reshape(-1, 2)
        else:
            located = cross_corners(patches.reshape(len(points), side, side), window,
                                    band_m / sample_m)
            located[:, 1] += side * np.arange(len(points))
        shift = located.astype(np.float64) - centres
        ok &= np.isfinite(shift).all(axis=1) & (np.abs(shift).max(axis=1) < margin - 1)
        found[:, :2] += np.where(ok[:, None], shift * sample_m[:, None], 0.0)
    ok &= np.linalg.norm(found - points, axis=1) <= _MAX_SHIFT * square_m
    return pixels(found), ok


def cross_corners(patches: np.ndarray, half_samples: int, band_samples: F64,
                  iterations: int = 6) -> F64:
    """Corners ``(M, 2)`` (x, y in samples) of fronto-parallel board patches ``(M, S, S)``
    whose corner lies near the centre, from the gradients along the two edges through it
    only: the samples within ``band_samples`` ``(M,)`` of the corner's row or column and
    within ``half_samples`` of it along them. The estimator is cornerSubPix's (every gradient there
    points away from the corner: ``sum g g^T (q - p) = 0``), without the squares' interiors,
    where a ChArUco board's markers begin a fraction of a square from the corner and would
    pull it: the edges are used out to ``half_samples`` however close the markers come."""
    m, side, _ = patches.shape
    gy, gx = np.gradient(patches.astype(np.float64), axis=(1, 2))
    axis = np.arange(side, dtype=np.float64)
    xs, ys = np.meshgrid(axis, axis)
    gxx, gxy, gyy = gx * gx, gx * gy, gy * gy
    qx, qy = gxx * xs + gxy * ys, gxy * xs + gyy * ys  # (g g^T q) per sample
    corner = np.full((m, 2), (side - 1) / 2.0)
    for _ in range(iterations):
        dx = np.abs(xs[None] - corner[:, 0, None, None])
        dy = np.abs(ys[None] - corner[:, 1, None, None])
        # each sample weighted by the fraction of it inside the bands, so that the bands
        # stay centred on the corner between samples (a hard edge would pull it to the side
        # where more of an edge's blurred profile is kept)
        limit = band_samples[:, None, None] + 0.5
        w = np.maximum(np.clip(limit - dx, 0.0, 1.0), np.clip(limit - dy, 0.0, 1.0)) \
            * np.clip(half_samples + 0.5 - dx, 0.0, 1.0) \
            * np.clip(half_samples + 0.5 - dy, 0.0, 1.0)
        a11, a12, a22 = ((w * g).sum(axis=(1, 2)) for g in (gxx, gxy, gyy))
        b1, b2 = (w * qx).sum(axis=(1, 2)), (w * qy).sum(axis=(1, 2))
        det = a11 * a22 - a12 * a12
        with np.errstate(divide="ignore", invalid="ignore"):
            corner = np.column_stack([(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det])
    return corner


def remeasures(board: Board, distortion_model: str) -> bool:
    """Whether calibration measures ``board``'s corners again on the board plane through a
    first solution with a ``distortion_model`` lens: a chessboard's for
    :data:`REMEASURED_MODELS`, a ChArUco board's always (see the module)."""
    if board.pattern == "charuco":
        return True
    return board.pattern == "chessboard" and distortion_model in REMEASURED_MODELS


def edge_band_m(board: Board) -> float | None:
    """Half-width (m) of the bands along a corner's two edges that :func:`cross_corners`
    uses on ``board``: half the gap between a ChArUco corner and the markers beside it
    (clear of their blurred edges); None for a chessboard, whose corners cornerSubPix
    measures."""
    if board.pattern != "charuco":
        return None
    return (board.square_m - board.marker_m) / 4.0


def _monomials(x: F64, y: F64) -> F64:
    """``(N, 9)``: the monomials of a cubic without its constant term."""
    return np.column_stack([x, y, x * x, x * y, y * y, x ** 3, x * x * y, x * y * y, y ** 3])

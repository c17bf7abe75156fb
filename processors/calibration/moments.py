"""A circle grid's discs in one image: their area centroids and size, from grey levels.

Around each circle the detected grid gives the local map from board to image (an affine fit
to the centres of its neighbours). The pixels within half the smallest spacing of the centre
on the board hold that circle's disc and no other, since discs do not overlap. A pixel's
value is the share of its area the disc covers, between the card's brightness and the
disc's darkness, so its *darkness* ``w = (bright - value) / (bright - dark)`` is that share:
summed over the window it is the disc's area in pixels, and the darkness-weighted mean pixel
is the disc's area centroid. Blur only moves darkness around inside the window, so neither
depends on it, nor on a threshold. The blob detector's centroids come from thresholded
contours: on mono_circles' renders they overstate the perspective shift of the centroid by
about 8 % and leave calibration residuals of 0.016 px RMS, where these leave 0.0075 px.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from replay.messages import F64

from .board import Board

#: grey levels between a disc and its card below which a circle is not measured
MIN_CONTRAST = 20.0
#: a point's neighbours for the local map: within this many smallest spacings
NEIGHBOURHOOD = 1.6
#: pixels beyond a disc's edge its window keeps: the blur of its edge
SKIRT_PX = 3.0


@dataclass(frozen=True)
class DiscMoments:
    """Per circle of one view: the area centroid ``centroid_px`` ``(N, 2)`` and the diameter
    ``diameter_m`` ``(N,)`` of its disc (NaN where it could not be measured: the window
    leaves the image, or shows no contrast)."""

    centroid_px: F64
    diameter_m: F64

    @property
    def measured(self) -> np.ndarray:
        """``(N,)`` which circles were measured."""
        return np.isfinite(self.diameter_m)


def disc_moments(gray: np.ndarray, centres_px: F64, board: Board) -> DiscMoments:
    """The discs of a circle grid found at ``centres_px`` ``(N, 2)`` in a ``(H, W)`` uint8
    image (see the module docstring).

    A first pass measures every third circle in a window half the smallest spacing wide; the
    second every circle in a window :data:`SKIRT_PX` wider than the discs the first found,
    so that what lies around the grid (the card's edge, the background) stays out of the
    outer circles' windows.
    """
    image_from_board = _local_maps(centres_px, board)
    half_gap = np.full(len(centres_px), board.nearest_m / 2.0)
    first = _measure(gray, centres_px[::3], image_from_board[::3], half_gap[::3])
    if not first.measured.any():
        return _measure(gray, centres_px, image_from_board, half_gap)
    radius_m = float(np.median(first.diameter_m[first.measured])) / 2.0
    # the smallest scale of each map: SKIRT_PX on the board in the direction it is narrowest
    scale = np.linalg.svd(image_from_board, compute_uv=False)[:, -1]
    window_m = np.minimum(half_gap, radius_m + SKIRT_PX / np.maximum(scale, 1e-12))
    return _measure(gray, centres_px, image_from_board, window_m)


def _local_maps(centres_px: F64, board: Board) -> F64:
    """``(N, 2, 2)`` pixels per metre about each point: the affine fit to the centres of the
    point and its neighbours."""
    points = board.points_in_board()[:, :2]
    offsets_m = points[None, :, :] - points[:, None, :]  # (N, N, 2): neighbour j of point i
    near = (np.linalg.norm(offsets_m, axis=2) <= NEIGHBOURHOOD * board.nearest_m) \
        .astype(np.float64)
    design = np.concatenate([offsets_m, np.ones((*near.shape, 1))], axis=2)  # (N, N, 3)
    normal = np.einsum("ij,ijk,ijl->ikl", near, design, design)
    fit = np.linalg.solve(normal, np.einsum("ij,ijk,jl->ikl", near, design, centres_px))
    return np.asarray(np.swapaxes(fit[:, :2, :], 1, 2))


def _measure(gray: np.ndarray, centres_px: F64, image_from_board: F64, window_m: F64
             ) -> DiscMoments:
    """Darkness sums and centroids over the pixels within ``window_m`` ``(N,)`` of each
    centre on the board."""
    n = len(centres_px)
    det = np.linalg.det(image_from_board)
    reach = int(np.ceil((np.linalg.norm(image_from_board, 2, axis=(1, 2)) * window_m).max())) + 1
    base = np.rint(centres_px).astype(np.int64)
    h, w = gray.shape
    fits = (base.min(axis=1) >= reach) & (base[:, 0] + reach <= w - 1) \
        & (base[:, 1] + reach <= h - 1) & (np.abs(det) > 0)
    centroid_px = np.full((n, 2), np.nan)
    diameter_m = np.full(n, np.nan)
    if not fits.any():
        return DiscMoments(centroid_px, diameter_m)
    step = np.arange(-reach, reach + 1)
    du, dv = (a.ravel() for a in np.meshgrid(step, step))
    us, vs = base[fits, 0, None] + du, base[fits, 1, None] + dv  # (K, S)
    board_from_image = np.linalg.inv(image_from_board[fits])  # (K, 2, 2)
    ou = us - centres_px[fits, 0, None]
    ov = vs - centres_px[fits, 1, None]
    x = board_from_image[:, 0, 0, None] * ou + board_from_image[:, 0, 1, None] * ov
    y = board_from_image[:, 1, 0, None] * ou + board_from_image[:, 1, 1, None] * ov
    inside = x * x + y * y <= window_m[fits, None] ** 2
    values = gray[vs, us].astype(np.float64)
    # each row sorted, the pixels outside the window last: levels are ranks
    ranked = np.sort(np.where(inside, values, np.inf), axis=1)
    count = inside.sum(axis=1)
    rows = np.arange(len(ranked))
    low, high = ranked[rows, count // 20], ranked[rows, count - 1 - count // 20]
    darker = np.sum(ranked < ((low + high) / 2.0)[:, None], axis=1)
    dark = ranked[rows, darker // 2]
    bright = ranked[rows, np.minimum(darker + (count - darker) // 2, count - 1)]
    darkness = np.where(inside, bright[:, None] - values, 0.0) \
        / np.maximum(bright - dark, 1.0)[:, None]
    area_px = darkness.sum(axis=1)
    measured = (high - low >= MIN_CONTRAST) & (area_px > 0)
    where = np.flatnonzero(fits)[measured]
    darkness, area_px = darkness[measured], area_px[measured]
    # about each window's middle pixel: small offsets, no cancellation
    centroid_px[where] = base[where] + np.column_stack([darkness @ du, darkness @ dv]) \
        / area_px[:, None]
    diameter_m[where] = 2.0 * np.sqrt(area_px / (np.pi * np.abs(det[where])))
    return DiscMoments(centroid_px, diameter_m)

"""The board's departure from a plane: a parabolic bow along its x and along its y.

A printed board bows. As mrcal's ``calobject_warp``, two parameters ``warp_m = (wx, wy)``
(metres) move the board point ``(x, y, 0)`` to ``z = wx (1 - u^2) + wy (1 - v^2)``, where
``u``, ``v`` are the point's x and y scaled to [-1, 1] across the board's extent: ``wx`` is
how far the middle of the board stands out of the plane of its left and right edges, ``wy``
of its top and bottom edges. The bundle (:mod:`.bundle`) estimates them with the rest, held
at zero unless chosen (:mod:`.warp_choice`).
"""

from __future__ import annotations

import numpy as np

from replay.messages import F64

__all__ = ["WARP_NAMES", "warp_shapes", "warp_text", "warped"]

WARP_NAMES = ("wx", "wy")


def warp_shapes(points_in_board: F64) -> F64:
    """``(N, 2)`` how far each board point ``(N, 3)`` moves along the board's z per metre of
    ``wx`` and of ``wy``: ``1 - u^2`` and ``1 - v^2`` (zero along an axis the board does not
    extend along)."""
    xy = points_in_board[:, :2]
    low, high = xy.min(axis=0), xy.max(axis=0)
    half = (high - low) / 2.0
    scaled = np.divide(xy - (low + half), half, out=np.ones_like(xy), where=half > 0)
    return np.asarray(1.0 - scaled ** 2, dtype=np.float64)


def warp_text(warp_m: F64, std_m: F64) -> str:
    """``board warp 1.50 ± 0.01 mm along x, -1.00 ± 0.01 mm along y``."""
    return "board warp " + ", ".join(
        f"{1000 * w:.3f} ± {1000 * s:.3f} mm along {axis}"
        for w, s, axis in zip(warp_m, std_m, "xy", strict=True))


def warped(points_in_board: F64, warp_m: F64) -> F64:
    """The board points ``(N, 3)`` of a board bowed by ``warp_m`` ``(2,)``."""
    if not np.any(warp_m):
        return points_in_board
    out = points_in_board.copy()
    out[:, 2] += warp_shapes(points_in_board) @ warp_m
    return out

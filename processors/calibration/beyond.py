"""Where a calibration is extrapolated: the image no board reached, and what is stated there.

A lens model is measured only where corners were seen; elsewhere (typically the image's
corners, which a board held or waved in front of a camera seldom reaches) its projections are
the polynomial's extrapolation. :func:`reached` marks the pixels inside the outline (convex
hull) of at least one used view's corners; :func:`beyond_boards` summarises an uncertainty
map's pixels outside every outline: their share of the grid, the worst stated uncertainty
there and which parts of the image they lie in (:func:`parts`), so that the calibration can
say in one line where it is extrapolated and how far it can be trusted there.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from replay.messages import F64

__all__ = ["BeyondBoards", "beyond_boards", "parts", "reached"]

B8 = npt.NDArray[np.bool_]
#: a view's outline is widened by this many pixels (a corner's own neighbourhood is measured)
OUTLINE_MARGIN_PX = 4
#: the image is cut into thirds along each side to name the parts a region lies in
THIRDS = 3
#: parts of the image, by (row third, column third)
_PART_OF = {(0, 0): "corners", (0, 2): "corners", (2, 0): "corners", (2, 2): "corners",
            (0, 1): "top edge", (2, 1): "bottom edge", (1, 0): "left edge",
            (1, 2): "right edge", (1, 1): "centre"}
_PART_ORDER = ("corners", "edges", "top edge", "bottom edge", "left edge", "right edge",
               "centre")


@dataclass(frozen=True)
class BeyondBoards:
    """The grid pixels no board reached: their ``share`` of the image grid, the worst stated
    uncertainty among them ``worst_px`` (1 sigma) and the parts of the image they lie in
    (``where``, e.g. ``corners of the image``); stated as
    :attr:`~replay.records.calibration.UncertaintySummary.beyond_boards_line`."""

    share: float
    worst_px: float
    where: str


def reached(size: tuple[int, int], corners_px: Sequence[F64]) -> B8:
    """``(H, W)`` True at the pixels inside the outline of at least one view's corners
    (each ``(M, 2)``, pixels), widened by :data:`OUTLINE_MARGIN_PX`."""
    width, height = size
    mask = np.zeros((height, width), dtype=np.uint8)
    for corners in corners_px:
        finite = corners[np.isfinite(corners).all(axis=1)]
        if len(finite) < 3:
            continue
        hull = cv2.convexHull(np.round(finite).astype(np.int32))
        cv2.fillConvexPoly(mask, hull, 1)
    if OUTLINE_MARGIN_PX:
        kernel = np.ones((2 * OUTLINE_MARGIN_PX + 1,) * 2, dtype=np.uint8)
        return np.asarray(cv2.dilate(mask, kernel), dtype=bool)
    return mask.astype(bool)


def parts(pixels: F64, size: tuple[int, int]) -> str:
    """The parts of the image pixels ``(M, 2)`` lie in, by thirds of each side: ``corners of
    the image``, ``corners and left edge of the image``, ``corners and edges of the image``
    (all four edges), ... (empty: no pixels)."""
    if not len(pixels):
        return ""
    width, height = size
    columns = np.clip((pixels[:, 0] * THIRDS // width).astype(int), 0, THIRDS - 1)
    rows = np.clip((pixels[:, 1] * THIRDS // height).astype(int), 0, THIRDS - 1)
    found = {_PART_OF[(int(r), int(c))] for r, c in zip(rows, columns, strict=True)}
    edges = {"top edge", "bottom edge", "left edge", "right edge"}
    if edges <= found:
        found = (found - edges) | {"edges"}
    names = [p for p in _PART_ORDER if p in found]
    listed = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
    return f"{listed} of the image"


def beyond_boards(pixels: F64, sigma_px: F64, reached_mask: B8) -> BeyondBoards | None:
    """The uncertainty ``sigma_px`` ``(rows, cols)`` at grid pixels ``pixels``
    ``(rows, cols, 2)`` where ``reached_mask`` ``(H, W)`` (:func:`reached`) is False; None
    where the boards reached every grid pixel with a figure."""
    height, width = reached_mask.shape
    flat, sigma = pixels.reshape(-1, 2), sigma_px.reshape(-1)
    u = np.clip(np.round(flat[:, 0]).astype(int), 0, width - 1)
    v = np.clip(np.round(flat[:, 1]).astype(int), 0, height - 1)
    has = np.isfinite(sigma)
    beyond = has & ~reached_mask[v, u]
    if not beyond.any():
        return None
    return BeyondBoards(float(beyond.sum() / max(int(has.sum()), 1)),
                        float(sigma[beyond].max()), parts(flat[beyond], (width, height)))

"""Where a calibration is extrapolated: the image no board reached, and what is stated there.

A lens model is measured only where corners were seen; elsewhere (typically the image's
corners, which a board held or waved in front of a camera seldom reaches) its projections are
the polynomial's extrapolation. :func:`reached` marks the pixels inside the outline (convex
hull) of at least one used view's corners; :func:`beyond_boards` summarises an uncertainty
map's pixels outside every outline: their share of the grid, the worst stated uncertainty
there and which parts of the image they lie in (:func:`parts`), so that the calibration can
say in one line where it is extrapolated and how far it can be trusted there.

**k3 beyond the views.** Cross-validation over views chooses the radial order
(:mod:`.model_order`), but held-out views lie where the training views lie: a k3 the image's
corners need and the views do not show never wins it. :func:`k3_beyond_the_views` fits k1 k2 k3
(k3 held by the prior at its stated width, :func:`.prior.stated_weights`: the lens as it could
be, not the solve's pull towards the low orders) beside the k1 k2 the views chose and compares
their projections over the whole image with k1 k2's own uncertainty (rays): where they part by
more than :data:`~.model_order.BEYOND_RATIO` times it, k1 k2 do not hold their own figure there
and k1 k2 k3 is kept (as solved with the prior's own weight, of which the lens as it could be is
one Gauss-Newton step away, :meth:`.robust.Problem.at_stated_prior`); otherwise k1 k2 stay, and
the k3 fit at the stated width is their left-out model (its difference is added to their
uncertainty, :func:`~.uncertainty.with_left_out`). On a waved board through a k3 lens the ratio
grows with the log: k1 k2's uncertainty shrinks with the views, the difference k3 makes beyond
them does not.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from replay.messages import F64

from .joint import BoardView, JointResult, calibrate_cameras
from .lens import model_of
from .model_order import BEYOND_RATIO, OrderChoice
from .options import CalibrationOptions
from .uncertainty import projection_uncertainty
from .validation import projection_difference

__all__ = ["BeyondBoards", "beyond_boards", "k3_beyond_the_views", "parts", "reached"]

B8 = npt.NDArray[np.bool_]
#: a view's outline is widened by this many pixels (a corner's own neighbourhood is measured)
OUTLINE_MARGIN_PX = 4
#: "far away": k1 k2 and k1 k2 k3 are compared for rays
FAR_M = 1e4
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


def _asks_k3(order: OrderChoice | None) -> bool:
    """Whether the views chose plumb_bob k1 k2 over a k1 k2 k3 they tried."""
    if order is None or order.why_not is not None or order.chosen != 0:
        return False
    return len(order.candidates) > 1 and order.candidates[1].radial_count == 3 \
        and order.candidates[1].distortion_model == "plumb_bob"


def k3_beyond_the_views(points_in_board: F64, views: list[BoardView],
                        sizes: list[tuple[int, int]], *, wanted: list[CalibrationOptions],
                        orders: list[OrderChoice | None], joint: JointResult,
                        disc_diameter_m: float | None = None
                        ) -> tuple[list[OrderChoice | None], list[CalibrationOptions],
                                   JointResult]:
    """The orders, options and solution after k1 k2 k3 is set beside every camera whose
    views chose k1 k2 (``orders``; ``joint`` the solution of ``views`` with the options
    ``wanted``): k3 kept where the two part by more than
    :data:`~.model_order.BEYOND_RATIO` times k1 k2's uncertainty, the k3 fit recorded as
    the left-out model of the cameras that keep k1 k2 (see the module docstring). Unchanged
    when no camera chose k1 k2."""
    asked = [c for c, order in enumerate(orders) if _asks_k3(order)]
    if not asked:
        return orders, wanted, joint
    warp = joint.options[0].board_warp  # as the first solve decided it

    def radial3(cameras: list[int]) -> list[CalibrationOptions]:
        return [dataclasses.replace(o, k_coefficients=3 if c in cameras else o.k_coefficients,
                                    board_warp=warp) for c, o in enumerate(wanted)]

    with_k3 = calibrate_cameras(points_in_board, views, sizes, radial3(asked),
                                seeds=joint.models, disc_diameter_m=disc_diameter_m)
    # the lens as it could be: k3 held only as far as real lenses hold it (.prior)
    stated = with_k3.problem.at_stated_prior()
    could_be = [model_of(s.distortion_model, stated.intrinsics[c], s.size)
                for c, s in enumerate(with_k3.problem.layout.setups)]
    out = list(orders)
    kept: list[int] = []
    for camera in asked:
        order = orders[camera]
        assert order is not None
        own = projection_uncertainty(joint.problem, camera, range_m=FAR_M)
        difference = projection_difference(joint.models[camera], could_be[camera], own.pixels)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = float(np.nanmax(difference / own.sigma_px))
        taken = ratio > BEYOND_RATIO
        out[camera] = dataclasses.replace(order, chosen=1 if taken else 0, beyond_ratio=ratio,
                                          beyond_px=float(np.nanmax(difference)))
        if taken:
            kept.append(camera)
    if not kept:
        left = list(joint.left_out_models or [None] * len(sizes))
        for camera in asked:
            richest = with_k3.left_out_models[camera] if with_k3.left_out_models else None
            left[camera] = richest if richest is not None else could_be[camera]
        joint.left_out_models = left
        return out, wanted, joint
    chosen = [dataclasses.replace(o, k_coefficients=3) if c in kept else o
              for c, o in enumerate(wanted)]
    if kept != asked:
        seeds = [with_k3.models[c] if c in kept else joint.models[c] for c in range(len(sizes))]
        with_k3 = calibrate_cameras(points_in_board, views, sizes, radial3(kept), seeds=seeds,
                                    disc_diameter_m=disc_diameter_m)
    with_k3.warp_choice = joint.warp_choice  # the warp as the views decided it
    return out, chosen, with_k3

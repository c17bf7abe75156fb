"""The calibration's projection uncertainty map, as a camera shows it.

``camlog calibrate`` records each camera's projection uncertainty (1 sigma, px) on a grid
over its image (:attr:`replay.topics.CameraTopics.uncertainty`). It is drawn once, for the
whole recording, over each pinhole view of the camera (remapped like its images) or, for a
pinhole camera, over its image under its ``Pinhole``: viridis colours from 0 (dark) to the
map's largest value (yellow), half transparent, white contours at round values labelled in
px, and a frame whose label gives the scale.
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
import rerun as rr

from replay.messages import F64

from .lens import Lens

__all__ = ["UNCERTAINTY_LEVELS", "field_colours", "field_contours", "field_over_image",
           "uncertainty_overlays"]

U8 = npt.NDArray[np.uint8]
#: draw order over a view's image (images draw at -10, overlays from -9 up)
ORDER_UNCERTAINTY = -9.5
#: the contours' and the frame's colours and line width
WHITE, CYAN = (255, 255, 255), (0, 220, 255)
LINE_RADIUS = rr.components.Radius.ui_points(0.5)


def field_over_image(values: F64, width: int, height: int) -> F64:
    """A figure given on a grid ``(rows, cols)`` spread over an image, both edges included
    (value ``(i, j)`` at pixel ``(j (W - 1) / (cols - 1), i (H - 1) / (rows - 1))``), at
    every pixel ``(H, W)``, bilinear between grid points.

    >>> field_over_image(np.array([[0.0, 2.0]]), 3, 1).tolist()
    [[0.0, 1.0, 2.0]]
    """
    rows, cols = values.shape
    u = np.arange(width, dtype=np.float32) * ((cols - 1) / max(width - 1, 1))
    v = np.arange(height, dtype=np.float32) * ((rows - 1) / max(height - 1, 1))
    map_u, map_v = np.meshgrid(u, v)
    return np.asarray(cv2.remap(values.astype(np.float32), map_u, map_v, cv2.INTER_LINEAR,
                                borderMode=cv2.BORDER_REPLICATE), dtype=np.float64)


#: opacity of a figure drawn over an image
FIELD_ALPHA = 110


def field_colours(field: F64, top: float) -> U8:
    """RGBA ``(H, W, 4)`` of a figure from 0 (dark) to ``top`` (yellow), viridis, half
    transparent; transparent where it has no value (NaN)."""
    known = np.isfinite(field)
    levels = np.clip(np.nan_to_num(field / max(top, 1e-12)) * 255, 0, 255).astype(np.uint8)
    bgr = cv2.applyColorMap(levels, cv2.COLORMAP_VIRIDIS)
    alpha = np.where(known, FIELD_ALPHA, 0).astype(np.uint8)
    return np.dstack([bgr[..., ::-1], alpha])


#: contour levels (px) of an uncertainty map, where they fall inside its range
UNCERTAINTY_LEVELS = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0)


def field_contours(field: F64, levels: tuple[float, ...] = UNCERTAINTY_LEVELS
                   ) -> list[tuple[float, list[F64]]]:
    """The contour lines ``(N, 2)`` of a figure at each level inside its range."""
    known = field[np.isfinite(field)]
    if known.size == 0:
        return []
    out = []
    for level in levels:
        if not float(known.min()) < level < float(known.max()):
            continue
        found, _ = cv2.findContours((np.nan_to_num(field) >= level).astype(np.uint8),
                                    cv2.RETR_LIST, cv2.CHAIN_APPROX_SIMPLE)
        strips = [c.reshape(-1, 2).astype(np.float64) for c in found if len(c) > 1]
        if strips:
            out.append((level, strips))
    return out


def uncertainty_overlays(sigma_px: F64, size: tuple[int, int], lens: Lens | None, *,
                         camera_entity: str) -> list[tuple[str, Any]]:
    """(entity, archetype) of the map ``sigma_px`` ``(rows, cols)`` of a camera whose raw
    images are ``size`` (width, height): over each of ``lens``'s views, or under the
    camera's own ``Pinhole`` (``{camera_entity}/calibration/uncertainty``) without one."""
    width, height = size
    field_raw = field_over_image(sigma_px, width, height)
    top = float(np.nanmax(sigma_px)) if np.isfinite(sigma_px).any() else 1.0
    label = f"projection uncertainty, 1 sigma: dark 0, yellow {top:.3g} px"
    fields = [(f"{camera_entity}/calibration/uncertainty", field_raw)]
    if lens is not None:
        fields = [(f"{camera_entity}/{view.name}/uncertainty", lens.remap_field(field_raw, index))
                  for index, view in enumerate(lens.views)]
    out: list[tuple[str, Any]] = []
    for entity, field_px in fields:
        strips: list[F64] = []
        labels: list[str] = []
        for level, lines in field_contours(field_px):
            strips += lines
            labels += [f"{level:g} px"] * len(lines)
        rows, cols = field_px.shape
        out += [
            (entity, rr.Image(field_colours(field_px, top), color_model="RGBA",
                              draw_order=ORDER_UNCERTAINTY)),
            (f"{entity}/contours", rr.LineStrips2D(strips, labels=labels, colors=[WHITE],
                                                   radii=LINE_RADIUS,
                                                   draw_order=ORDER_UNCERTAINTY + 0.1)),
            (f"{entity}/scale", rr.Boxes2D(mins=[[0, 0]], sizes=[[cols, rows]], colors=[CYAN],
                                           labels=[label])),
        ]
    return out

"""From an ideal pinhole render to the camera's image: distortion and intrinsics by warp.

MuJoCo renders square-pixel, centred, distortion-free images. A camera with any other model
is made by rendering a wider ideal view ``s`` times denser, then, for every output pixel,
looking up the ideal ray its *distorted* centre comes from (exact iterative undistortion)
and averaging the render over the pixel's footprint there: ``s x s`` bilinear samples one
render pixel apart.

That average is computed as an ``s x s`` box filter of the render followed by one bilinear
sample per output pixel. A sum of bilinear samples at unit spacing equals one bilinear
sample of the box-filtered image, so the two are the same where the distortion leaves a
footprint one render pixel per sub-sample wide; elsewhere (a few percent at the corners of
a k1 = -0.2 lens) only the width of the averaging differs, never where it is centred. It
costs a quarter of the samples at s = 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from .errors import ScenarioError

MAX_RENDER_SIDE = 4096


@dataclass(frozen=True)
class View:
    """One ideal pinhole render from a camera's optical centre (OpenCV conventions: pixel
    centres at integer coordinates), and where it sits in the camera's atlas of renders."""

    camera_from_view: F64  # (3, 3) rotation of the view's optical frame
    width: int
    height: int
    focal_px: float
    cx: float
    cy: float
    atlas_row: int  # first row of this view in the atlas (views stacked top to bottom)


@dataclass(frozen=True)
class Optics:
    """How to render one camera: ideal render size and vertical FOV, plus the warp maps."""

    render_width: int
    render_height: int
    fovy_deg: float
    supersample: int
    #: (H, W) float32: where each output pixel samples the box-filtered render (the render
    #: position of its ideal ray plus :attr:`box_offset_px`); None: an ideal camera, whose
    #: image is the box-filtered render itself
    map_x: np.ndarray | None
    map_y: np.ndarray | None
    output_size: tuple[int, int]  # (W, H)

    @property
    def views(self) -> tuple[View, ...]:
        """The one render: the camera's own view, centred, square pixels."""
        focal = (self.render_height / 2) / math.tan(math.radians(self.fovy_deg) / 2)
        return (View(np.eye(3), self.render_width, self.render_height, focal,
                     (self.render_width - 1) / 2, (self.render_height - 1) / 2, 0),)

    @property
    def render_sizes(self) -> list[tuple[int, int]]:
        """(W, H) of the render."""
        return [(self.render_width, self.render_height)]

    @property
    def box_offset_px(self) -> float:
        """OpenCV's s x s box filter puts the mean of render pixels x - s//2 .. x - s//2 + s - 1
        at x: a footprint centred at render position p is read at p + this offset."""
        return self.supersample // 2 - (self.supersample - 1) / 2.0

    def apply(self, rendered: np.ndarray) -> np.ndarray:
        """Camera image ``(H, W, 3)`` uint8 from an ideal render ``(Hr, Wr, 3)``."""
        if self.map_x is None or self.map_y is None:
            if self.supersample == 1:
                return rendered
            return cv2.resize(rendered, self.output_size, interpolation=cv2.INTER_AREA)
        if self.supersample > 1:
            rendered = cv2.blur(rendered, (self.supersample, self.supersample),
                                borderType=cv2.BORDER_REPLICATE)
        return cv2.remap(rendered, self.map_x, self.map_y, cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)


def plan_optics(model: CameraModel, supersample: int) -> Optics:
    """Ideal render and warp that produce images of ``model``."""
    w, h = model.width, model.height
    s = supersample
    if model.is_ideal:
        # An ideal camera is an exact s-times denser render: output pixel u covers render
        # pixels s*u .. s*u + s - 1, so a box filter (area resize) is the whole warp.
        fovy = 2.0 * math.degrees(math.atan((h / 2.0) / model.fy))
        return Optics(w * s, h * s, fovy, s, None, None, (w, h))
    # Output pixel centres (pixel u covers [u - 0.5, u + 0.5]).
    grid_u, grid_v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    pixels = np.column_stack([grid_u.ravel(), grid_v.ravel()])
    xy = model.undistort_pixels(pixels)
    check = model.distort_normalized(xy)
    err = np.abs(check - pixels).max()
    if not np.isfinite(err) or err > 1e-3:
        raise ScenarioError(
            f"distortion {model.distortion_model} {model.d.tolist()} is not invertible over the "
            f"{w}x{h} image (round-trip error {err:.3g} px); use smaller coefficients"
        )
    f_render = s * max(model.fx, model.fy)
    # room for the footprint (s / 2 render pixels), the bilinear sample and the box filter
    half_w = f_render * np.abs(xy[:, 0]).max() + s + 2.0
    half_h = f_render * np.abs(xy[:, 1]).max() + s + 2.0
    render_w, render_h = 2 * math.ceil(half_w), 2 * math.ceil(half_h)
    if max(render_w, render_h) > MAX_RENDER_SIDE:
        raise ScenarioError(
            f"camera needs a {render_w}x{render_h} ideal render (limit {MAX_RENDER_SIDE}); "
            "lower supersample, the field of view or the distortion"
        )
    cx_r, cy_r = (render_w - 1) / 2.0, (render_h - 1) / 2.0
    offset = s // 2 - (s - 1) / 2.0  # Optics.box_offset_px
    map_x = (f_render * xy[:, 0] + cx_r + offset).astype(np.float32).reshape(h, w)
    map_y = (f_render * xy[:, 1] + cy_r + offset).astype(np.float32).reshape(h, w)
    fovy = 2.0 * math.degrees(math.atan((render_h / 2.0) / f_render))
    return Optics(render_w, render_h, fovy, s, map_x, map_y, (w, h))

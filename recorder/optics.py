"""From an ideal pinhole render to the camera's image: distortion and intrinsics by warp.

MuJoCo renders square-pixel, centred, distortion-free images. A camera with any other model
is made by rendering a wider ideal view ``s`` times denser, then, for each of the ``s x s``
sub-pixel samples of every output pixel, looking up the ideal ray its *distorted* position
comes from (exact iterative undistortion), sampling the render there, and averaging the
samples (a box filter over the pixel's footprint).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from replay.camera import CameraModel

from .errors import ScenarioError

MAX_RENDER_SIDE = 4096


@dataclass(frozen=True)
class Optics:
    """How to render one camera: ideal render size and vertical FOV, plus the warp maps."""

    render_width: int
    render_height: int
    fovy_deg: float
    supersample: int
    map_x: np.ndarray | None  # (H * s, W * s) float32 render x per sub-pixel; None: box filter
    map_y: np.ndarray | None
    output_size: tuple[int, int]  # (W, H)

    def apply(self, rendered: np.ndarray) -> np.ndarray:
        """Camera image ``(H, W, 3)`` uint8 from an ideal render ``(Hr, Wr, 3)``."""
        if self.map_x is None or self.map_y is None:
            if self.supersample == 1:
                return rendered
            return cv2.resize(rendered, self.output_size, interpolation=cv2.INTER_AREA)
        samples = cv2.remap(rendered, self.map_x, self.map_y, cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE)
        if self.supersample == 1:
            return samples
        return cv2.resize(samples, self.output_size, interpolation=cv2.INTER_AREA)


def plan_optics(model: CameraModel, supersample: int) -> Optics:
    """Ideal render and warp that produce images of ``model``."""
    w, h = model.width, model.height
    s = supersample
    if model.is_ideal:
        # An ideal camera is an exact s-times denser render: output pixel u covers render
        # pixels s*u .. s*u + s - 1, so a box filter (area resize) is the whole warp.
        fovy = 2.0 * math.degrees(math.atan((h / 2.0) / model.fy))
        return Optics(w * s, h * s, fovy, s, None, None, (w, h))
    # Sub-pixel sample centres: pixel u covers [u - 0.5, u + 0.5].
    us = (np.arange(w * s) + 0.5) / s - 0.5
    vs = (np.arange(h * s) + 0.5) / s - 0.5
    grid_u, grid_v = np.meshgrid(us, vs)
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
    half_w = f_render * np.abs(xy[:, 0]).max() + 2.0
    half_h = f_render * np.abs(xy[:, 1]).max() + 2.0
    render_w, render_h = 2 * math.ceil(half_w), 2 * math.ceil(half_h)
    if max(render_w, render_h) > MAX_RENDER_SIDE:
        raise ScenarioError(
            f"camera needs a {render_w}x{render_h} ideal render (limit {MAX_RENDER_SIDE}); "
            "lower supersample, the field of view or the distortion"
        )
    cx_r, cy_r = (render_w - 1) / 2.0, (render_h - 1) / 2.0
    map_x = (f_render * xy[:, 0] + cx_r).astype(np.float32).reshape(h * s, w * s)
    map_y = (f_render * xy[:, 1] + cy_r).astype(np.float32).reshape(h * s, w * s)
    fovy = 2.0 * math.degrees(math.atan((render_h / 2.0) / f_render))
    return Optics(render_w, render_h, fovy, s, map_x, map_y, (w, h))

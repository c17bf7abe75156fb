"""Wide-angle cameras (fisheye, up to the full sphere) from several pinhole renders.

One pinhole render cannot hold a field of view near or past 180 degrees, so a wide camera is
rendered as several pinhole views from its optical centre: a cube map refined to 26
directions (the cube's 6 faces, 12 edges and 8 corners). Each output pixel belongs to the
view whose direction is closest to its ray. Across a plain cube face a pinhole's pixel
density varies threefold (1 / cos^2 at 55 degrees off axis), so its renders would be three
times denser than needed at the face corners; 26 directions keep every view within about 30
degrees of its axis (1.5-fold), which costs fewer rendered pixels and fewer samples. Each
view is cropped to the pixels it serves (an off-centre principal point) and is dense enough
that every output pixel spans at least ``supersample`` render pixels in every direction.

Each output pixel is the mean of ``n x n`` bilinear samples of its view at its sub-pixel
centres' rays. The pixel's map into its view is the quadratic through the exact model's rays
at the pixel centre and 8 points half a pixel around it, which puts every sample within
1e-3 px of its exact ray at a fisheye's usual pixel scale. ``n`` keeps neighbouring samples
at most one render pixel apart, so no render pixel is skipped: the footprint average of the
pinhole warp (:mod:`recorder.optics`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from .errors import ScenarioError
from .optics import MAX_RENDER_SIDE, Optics, View, plan_optics

#: render pixels kept around the outermost sample of a view: the bilinear sample's second
#: pixel plus a guard
VIEW_MARGIN_PX = 2.0
#: samples per output pixel side at most: where a lens squeezes its rim harder than this
#: (the far corners of some fisheyes), samples there skip render pixels
MAX_SAMPLES_PER_SIDE = 8
ROUND_TRIP_TOLERANCE_PX = 1e-3
#: a view's focal length is at most this many times the camera's (times ``supersample``):
#: towards 180 degrees a fisheye's pixels shrink without bound across the radius (by
#: theta / sin(theta)), and only there (past ~125 degrees for an equisolid lens) does the
#: render get coarser than ``supersample`` pixels per output pixel
MAX_DENSITY_RATIO = 2.0


def view_rotations() -> list[F64]:
    """``camera_from_view`` (3, 3) of the 26 view directions (view z = the direction): the
    cube's views_of, edges and corners, in a fixed order."""
    out = []
    for direction in itertools.product((-1, 0, 1), repeat=3):
        if not any(direction):
            continue
        z = np.array(direction, dtype=np.float64)
        z /= np.linalg.norm(z)
        helper = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
        x = np.cross(helper, z)
        x /= np.linalg.norm(x)
        out.append(np.column_stack([x, np.cross(z, x), z]))
    return out


@dataclass(frozen=True)
class MultiViewOptics:
    """How to render one wide camera: its pinhole views and where each sample reads them.

    The renderer stacks the views' renders top to bottom into one atlas (``View.atlas_row``);
    ``map_x``, ``map_y`` (``(H * n, W * n)`` float32) are each sample's atlas position.
    """

    views: tuple[View, ...]
    supersample: int
    samples_per_side: int
    map_x: np.ndarray
    map_y: np.ndarray
    output_size: tuple[int, int]  # (W, H)

    @property
    def render_sizes(self) -> list[tuple[int, int]]:
        """(W, H) of every view."""
        return [(v.width, v.height) for v in self.views]

    def apply(self, atlas: np.ndarray) -> np.ndarray:
        """Camera image ``(H, W, C)`` from the atlas of the views' renders."""
        samples = cv2.remap(atlas, self.map_x, self.map_y, cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE)
        if self.samples_per_side == 1:
            return samples
        # an integer-factor area resize is the exact mean of each n x n block
        return cv2.resize(samples, self.output_size, interpolation=cv2.INTER_AREA)


def _pixel_centres(width: int, height: int) -> F64:
    """Pixel centres ``(H * W, 2)``, row-major."""
    grid_u, grid_v = np.meshgrid(np.arange(width, dtype=np.float64),
                                 np.arange(height, dtype=np.float64))
    return np.column_stack([grid_u.ravel(), grid_v.ravel()])


def _rays(model: CameraModel, pixels: F64) -> F64:
    rays = model.pixel_rays(pixels)
    back = model.project(rays)
    err = np.abs(back - pixels).max() if len(pixels) else 0.0
    if not np.isfinite(err) or err > ROUND_TRIP_TOLERANCE_PX:
        raise ScenarioError(
            f"distortion {model.distortion_model} {model.d.tolist()} is not invertible over the "
            f"{model.width}x{model.height} image (round-trip error {err:.3g} px); use smaller "
            "coefficients"
        )
    return rays


def _views_of(rays: F64, rotations: list[F64]) -> np.ndarray:
    """Index of the view each ray belongs to: the direction closest to it."""
    axes = np.stack([r[:, 2] for r in rotations])
    return np.asarray(np.argmax(rays @ axes.T, axis=1))


def _tangents(rays: F64, rotation: F64) -> F64:
    """Pinhole coordinates ``(N, 2)`` of rays in a view (z > 0 for the rays it serves)."""
    in_view = rays @ rotation
    return np.asarray(in_view[:, :2] / in_view[:, 2:3])


#: offsets (du, dv) in output pixels of the stencil that fits each pixel's local map
_STENCIL = ((0.5, 0.0), (-0.5, 0.0), (0.0, 0.5), (0.0, -0.5),
            (0.5, 0.5), (0.5, -0.5), (-0.5, 0.5), (-0.5, -0.5))


def _local_maps(model: CameraModel, centres: F64, rays: F64, rotation: F64) -> F64:
    """Per pixel, the quadratic that maps offsets within it to view pinhole coordinates,
    fitted to the exact model at the centre and its 8 neighbours half a pixel away:
    ``(N, 6, 2)`` rows p0, d/du, d/dv, d2/du2, d2/dudv, d2/dv2."""
    p0 = _tangents(rays, rotation)
    at = [_tangents(model.pixel_rays(centres + np.array(o)), rotation) for o in _STENCIL]
    up, um, vp, vm, pp, pm, mp, mm = at
    h = 0.5
    return np.stack([p0, (up - um) / (2 * h), (vp - vm) / (2 * h),
                     (up - 2 * p0 + um) / h**2, (pp - pm - mp + mm) / (4 * h * h),
                     (vp - 2 * p0 + vm) / h**2], axis=1)


def _singular_values(jacobians: F64) -> tuple[F64, F64]:
    """Largest and smallest singular values ``(N,)`` of 2 x 2 matrices ``(N, 2, 2)``."""
    a, b = jacobians[:, 0, 0], jacobians[:, 0, 1]
    c, d = jacobians[:, 1, 0], jacobians[:, 1, 1]
    total = a * a + b * b + c * c + d * d
    det = np.abs(a * d - b * c)
    root = np.sqrt(np.maximum(total * total - 4 * det * det, 0.0))
    largest = np.sqrt((total + root) / 2)
    return largest, det / np.maximum(largest, 1e-300)


def plan_multiview_optics(model: CameraModel, supersample: int) -> MultiViewOptics:
    """Pinhole views and sampling maps that produce images of a wide ``model``."""
    w, h = model.width, model.height
    s = supersample
    rotations = view_rotations()
    centres = _pixel_centres(w, h)
    rays = _rays(model, centres)
    views_of = _views_of(rays, rotations)
    used = [int(i) for i in np.unique(views_of)]
    local = np.empty((len(centres), 6, 2))  # see _local_maps
    focal = {}
    for index in used:
        mask = views_of == index
        local[mask] = _local_maps(model, centres[mask], rays[mask], rotations[index])
        # every pixel spans >= s render pixels in every direction, up to a density cap
        jacobians = np.stack([local[mask, 1], local[mask, 2]], axis=2)
        focal[index] = min(s / float(_singular_values(jacobians)[1].min()),
                           s * MAX_DENSITY_RATIO * max(model.fx, model.fy))
    local *= np.array([focal[i] for i in used])[np.searchsorted(used, views_of)][:, None, None]
    spread = float(_singular_values(np.stack([local[:, 1], local[:, 2]], axis=2))[0].max())
    n = min(max(s, math.ceil(spread - 1e-9)), MAX_SAMPLES_PER_SIDE)
    # a bound on how far a pixel's samples reach from its centre, in view pixels
    reach = 0.5 * (np.abs(local[:, 1]) + np.abs(local[:, 2])) + 0.125 * (
        np.abs(local[:, 3]) + 2 * np.abs(local[:, 4]) + np.abs(local[:, 5]))
    views: list[View] = []
    row = 0
    for index in used:
        mask = views_of == index
        low = (local[mask, 0] - reach[mask]).min(axis=0) - VIEW_MARGIN_PX
        high = (local[mask, 0] + reach[mask]).max(axis=0) + VIEW_MARGIN_PX
        width, height = (int(v) + 1 for v in np.ceil(high - low))
        if max(width, height) > MAX_RENDER_SIDE:
            raise ScenarioError(
                f"camera needs a {width}x{height} view (limit {MAX_RENDER_SIDE}); lower "
                "supersample or the resolution"
            )
        # view pixel = f * tangent - low: the principal point sits at -low
        views.append(View(rotations[index], width, height, focal[index], float(-low[0]),
                          float(-low[1]), row))
        local[mask, 0] += -low + np.array([0.0, row])  # atlas position of the centre
        row += height
    coeff = local.reshape(h, w, 6, 2).astype(np.float32)[:, None, :, None]  # (H,1,W,1,6,2)
    offsets = ((np.arange(n) + 0.5) / n - 0.5).astype(np.float32)
    du = offsets[None, None, None, :, None]  # across a pixel
    dv = offsets[None, :, None, None, None]  # down a pixel
    maps = (coeff[..., 0, :] + coeff[..., 1, :] * du + coeff[..., 2, :] * dv
            + 0.5 * coeff[..., 3, :] * du * du + coeff[..., 4, :] * du * dv
            + 0.5 * coeff[..., 5, :] * dv * dv)  # (H, n, W, n, 2)
    maps = maps.reshape(h * n, w * n, 2)
    return MultiViewOptics(tuple(views), s, n, np.ascontiguousarray(maps[..., 0]),
                           np.ascontiguousarray(maps[..., 1]), (w, h))


#: how one camera is rendered: one warped pinhole view, or several
CameraOptics = Optics | MultiViewOptics


def plan_camera_optics(model: CameraModel, supersample: int) -> CameraOptics:
    """Optics of any camera: the pinhole warp for pinhole models, several views for a fisheye."""
    if model.is_fisheye:
        return plan_multiview_optics(model, supersample)
    return plan_optics(model, supersample)

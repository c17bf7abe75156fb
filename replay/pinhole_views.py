"""Distortion-free pinhole cameras that a lens's raw image is remapped to.

A viewer that knows only pinholes (rerun's ``Pinhole`` holds ``K`` and a resolution, no
distortion) draws a raw image of a real lens in the wrong place everywhere off its centre.
The image it should draw is the raw one remapped to a pinhole camera: each pixel of a
:class:`PinholeView` shows the ray ``rotation^T K^-1 (u, v, 1)`` of the lens's optical
frame, sampled in the raw image where the lens images that ray (``cv2.remap`` with
OpenCV's undistortion maps, :meth:`~replay.camera.CameraModel.rectify_maps`).

:func:`pinhole_views` chooses the views of a camera_info:

* none when the camera is a pinhole already (``plumb_bob`` or ``rational_polynomial``
  with every coefficient zero, ``R`` the identity): its raw image is the pinhole image;
* ``rectified`` for one camera of a rectified stereo pair (``R`` not the identity): the
  pair's own ``P[:, :3]``, turned by ``R``, so that rows match across the pair;
* ``undistorted`` otherwise: same pixel aspect as ``K``, focal length and principal point
  chosen so that the raw image's whole field of view fits, up to :data:`MAX_HALF_ANGLE_RAD`
  off the axis along each image direction (every pixel edge of the raw image's border is
  inside, so every raw pixel is);
* ``wide`` too when a lens sees further than that (a fisheye): the same up to
  :data:`WIDE_HALF_ANGLE_RAD`. A pinhole image cannot reach 90 degrees; what is beyond a
  view's field shows only in the raw image, and :attr:`PinholeView.covered` says how much
  of the raw image a view holds.

>>> import numpy as np
>>> from replay.messages import CameraInfo
>>> k = np.array([[400.0, 0, 319.5], [0, 400.0, 239.5], [0, 0, 1]])
>>> info = CameraInfo(0, "cam", 640, 480, "plumb_bob", np.array([-0.2, 0.05, 0, 0, 0]), k)
>>> (view,) = pinhole_views(info)
>>> view.name, view.covered, round(view.k[0, 0], 1) < 400.0
('undistorted', 1.0, True)
>>> pinhole_views(CameraInfo(0, "cam", 640, 480, "plumb_bob", np.zeros(5), k))
[]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .camera import CameraModel
from .lens_models import LENS_MODELS, canonical_name
from .messages import F64, CameraInfo
from .projections import PINHOLE

__all__ = ["MAX_HALF_ANGLE_RAD", "WIDE_HALF_ANGLE_RAD", "PinholeView", "is_pinhole",
           "pinhole_views"]

#: the undistorted view reaches at most this far off the axis along x and along y (60
#: degrees: a pinhole's pixels there are 4 times as long as at the centre)
MAX_HALF_ANGLE_RAD = math.radians(60.0)
#: the wide view of a lens that sees further (75 degrees: 15 times as long)
WIDE_HALF_ANGLE_RAD = math.radians(75.0)
#: raw pixels sampled to measure a view's coverage: every this many along each axis
COVERAGE_STEP_PX = 8
#: a border pixel whose ray reprojects further than this from it does not undistort (a
#: rational polynomial that folds over near the corners): it counts as outside every view
REPROJECTION_TOLERANCE_PX = 0.01


@dataclass(frozen=True)
class PinholeView:
    """A pinhole camera ``k`` (3, 3), ``width`` x ``height`` pixels, whose optical frame is
    the lens's turned by ``rotation`` (3, 3): a ray ``d`` of the lens's frame is ``rotation @
    d`` in the view's. ``covered``: the share of the raw image's pixels the view shows."""

    name: str
    k: F64
    width: int
    height: int
    rotation: F64
    covered: float

    @property
    def fov_rad(self) -> tuple[float, float]:
        """The view's field across and top to bottom, edge to edge of its pixels."""
        fx, fy, cx, cy = self.k[0, 0], self.k[1, 1], self.k[0, 2], self.k[1, 2]
        across = math.atan((cx + 0.5) / fx) + math.atan((self.width - 0.5 - cx) / fx)
        down = math.atan((cy + 0.5) / fy) + math.atan((self.height - 0.5 - cy) / fy)
        return across, down

    def maps(self, model: CameraModel, map_type: int = cv2.CV_16SC2
             ) -> tuple[np.ndarray, np.ndarray]:
        """``cv2.remap`` maps from the raw image of ``model`` to this view."""
        return model.rectify_maps(self.rotation, self.k, map_type,
                                  size=(self.width, self.height))

    def describe(self) -> str:
        """One line: the view's size, field of view and coverage.

        >>> k = np.array([[200.0, 0, 99.5], [0, 200.0, 49.5], [0, 0, 1]])
        >>> PinholeView("undistorted", k, 200, 100, np.eye(3), 0.5).describe()
        'undistorted 200x100, 53.1 x 28.1 degrees, 50.0 % of the raw image'
        """
        across, down = (math.degrees(a) for a in self.fov_rad)
        return (f"{self.name} {self.width}x{self.height}, {across:.1f} x {down:.1f} degrees, "
                f"{100 * self.covered:.1f} % of the raw image")


def is_pinhole(info: CameraInfo) -> bool:
    """Whether the raw image of ``info`` is already a pinhole image (a pinhole lens model
    with every coefficient zero, no rectifying rotation)."""
    model = LENS_MODELS.get(canonical_name(info.distortion_model))
    return model is not None and not model.fisheye and not np.any(info.d) and \
        bool(np.array_equal(info.r, np.eye(3)) or not np.any(info.r))


def _rotated(info: CameraInfo) -> bool:
    return bool(np.any(info.r)) and not np.allclose(info.r, np.eye(3), rtol=0, atol=1e-12) \
        and bool(np.any(info.p[:, :3]))


def _border_px(width: int, height: int) -> F64:
    """The outer edges of the border pixels ``(N, 2)``: every pixel's edge along each side
    of the image (pixel centres at integer coordinates, so the edges at -0.5 and W - 0.5)."""
    us = np.arange(-0.5, width, 1.0)
    vs = np.arange(-0.5, height, 1.0)
    top = np.column_stack([us, np.full_like(us, -0.5)])
    bottom = np.column_stack([us, np.full_like(us, height - 0.5)])
    left = np.column_stack([np.full_like(vs, -0.5), vs])
    right = np.column_stack([np.full_like(vs, width - 0.5), vs])
    return np.vstack([top, bottom, left, right])


def _rays(model: CameraModel, uv: F64) -> F64:
    """Unit rays ``(N, 3)`` of pixels ``uv`` (N, 2); NaN where the lens model does not
    invert (its ray does not reproject onto the pixel)."""
    rays = model.pixel_rays(uv)
    if model.projection is PINHOLE:
        back = model.project(rays / rays[:, 2:])
        wrong = ~(np.linalg.norm(back - uv, axis=1) <= REPROJECTION_TOLERANCE_PX)
        rays[wrong] = np.nan
    return rays


def _scaled(k: F64, sx: float, sy: float) -> F64:
    """``k`` of an image resized by ``sx``, ``sy`` (pixel centres stay at integers)."""
    out = np.array(k, dtype=np.float64, copy=True)
    out[0, 0], out[0, 1], out[1, 1] = k[0, 0] * sx, k[0, 1] * sx, k[1, 1] * sy
    out[0, 2] = sx * (k[0, 2] + 0.5) - 0.5
    out[1, 2] = sy * (k[1, 2] + 0.5) - 0.5
    return out


def _fitting(rays: F64, k: F64, width: int, height: int, half_angle_rad: float) -> F64:
    """The pinhole ``K`` of a ``width`` x ``height`` image with ``k``'s pixel aspect that
    holds every ray in ``rays`` up to ``half_angle_rad`` off the axis along x and y."""
    ok = np.all(np.isfinite(rays), axis=1)
    x_angle = np.clip(np.arctan2(rays[ok, 0], rays[ok, 2]), -half_angle_rad, half_angle_rad)
    y_angle = np.clip(np.arctan2(rays[ok, 1], rays[ok, 2]), -half_angle_rad, half_angle_rad)
    x, y = np.tan(x_angle), np.tan(y_angle)
    aspect = float(k[1, 1] / k[0, 0])
    # the bounding box's edges land on the outer edges of the view's pixels
    fx = min(width / float(x.max() - x.min()), height / (aspect * float(y.max() - y.min())))
    fy = aspect * fx
    cx = (width - 1) / 2 - fx * float(x.max() + x.min()) / 2
    cy = (height - 1) / 2 - fy * float(y.max() + y.min()) / 2
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def _covered(model: CameraModel, k: F64, rotation: F64, width: int, height: int) -> float:
    """The share of the raw image's pixels (sampled) whose rays land inside the view."""
    us, vs = np.meshgrid(np.arange(0, model.width, COVERAGE_STEP_PX, dtype=np.float64),
                         np.arange(0, model.height, COVERAGE_STEP_PX, dtype=np.float64))
    rays = _rays(model, np.column_stack([us.ravel(), vs.ravel()])) @ rotation.T
    ahead = np.isfinite(rays).all(axis=1) & (rays[:, 2] > 1e-9)
    uv = rays[ahead] @ k.T
    uv = uv[:, :2] / uv[:, 2:]
    inside = ((uv[:, 0] >= -0.5) & (uv[:, 0] <= width - 0.5)
              & (uv[:, 1] >= -0.5) & (uv[:, 1] <= height - 0.5))
    share = float(inside.sum()) / len(rays)
    return 1.0 if share > 1.0 - 1e-9 else share


def pinhole_views(info: CameraInfo, *, scale: float = 1.0) -> list[PinholeView]:
    """The views of the camera ``info`` describes (see the module), each ``scale`` times the
    raw image's width and height; ValueError for a lens model camlog does not know."""
    if is_pinhole(info):
        return []
    model = CameraModel.from_camera_info(info)
    width, height = max(1, round(info.width * scale)), max(1, round(info.height * scale))
    if _rotated(info):
        k = _scaled(info.p[:, :3], width / info.width, height / info.height)
        rotation = np.asarray(info.r, dtype=np.float64)
        return [PinholeView("rectified", k, width, height, rotation,
                            _covered(model, k, rotation, width, height))]
    border_rays = _rays(model, _border_px(info.width, info.height))
    caps = [("undistorted", MAX_HALF_ANGLE_RAD)]
    if _off_axis_rad(border_rays) > MAX_HALF_ANGLE_RAD:
        caps.append(("wide", WIDE_HALF_ANGLE_RAD))
    views = []
    for name, half_angle in caps:
        k = _fitting(border_rays, model.k, width, height, half_angle)
        views.append(PinholeView(name, k, width, height, np.eye(3),
                                 _covered(model, k, np.eye(3), width, height)))
    return views


def _off_axis_rad(rays: F64) -> float:
    """How far the rays reach off the axis along x or y (the larger)."""
    ok = np.all(np.isfinite(rays), axis=1)
    return float(max(np.abs(np.arctan2(rays[ok, 0], rays[ok, 2])).max(),
                     np.abs(np.arctan2(rays[ok, 1], rays[ok, 2])).max()))

"""Each lens model's projection: OpenCV's pinhole functions or its ``cv2.fisheye`` ones.

:data:`PROJECTIONS` gives every model of :data:`~replay.lens_models.LENS_MODELS` (by its ROS
name) the functions :class:`~replay.camera.CameraModel` images and unprojects with, and the
``cv2.remap`` maps it rectifies with. Every function takes ``K`` (3, 3) and ``D`` (N,) in
OpenCV's order.

The equidistant model maps a ray at angle ``theta`` from the optical axis to the distorted
radius ``theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)`` along the
ray's direction in the image plane, then applies ``K``; it holds beyond 90 degrees, where
pinhole coordinates ``X / Z`` do not exist.

>>> projection("fisheye") is PROJECTIONS["equidistant"], projection("plumb_bob").name
(True, 'pinhole')
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

from .lens_models import canonical_name
from .messages import F64

__all__ = ["EQUIDISTANT", "PINHOLE", "PROJECTIONS", "Projection", "projection"]

_FISHEYE_NEWTON_STEPS = 30
_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14)

#: ``(K, D, points (N, 3) or pixels (N, 2))`` -> ``(N, 2)`` or ``(N, 3)``
LensFunction = Callable[[F64, F64, F64], F64]
#: ``cv2.initUndistortRectifyMap``'s signature: ``(K, D, R, new_K, size, map_type)``
RectifyMap = Callable[..., tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Projection:
    """One family of OpenCV's lens functions (``name``: ``pinhole`` or ``fisheye``):
    ``project`` images points ``(N, 3)`` in the optical frame at pixels ``(N, 2)``;
    ``pixel_rays`` gives the unit rays ``(N, 3)`` of pixels, ``undistort_pixels`` their
    ideal normalized coordinates ``(N, 2)`` (NaN for rays 90 degrees or more off the axis);
    ``rectify_map`` is OpenCV's ``initUndistortRectifyMap`` of the family."""

    name: str
    project: LensFunction
    pixel_rays: LensFunction
    undistort_pixels: LensFunction
    rectify_map: RectifyMap


def _project_pinhole(k: F64, d: F64, points: F64) -> F64:
    uv, _ = cv2.projectPoints(points, np.zeros(3), np.zeros(3), k, d)
    return np.asarray(uv, dtype=np.float64).reshape(-1, 2)


def _undistort_pinhole(k: F64, d: F64, uv: F64) -> F64:
    """OpenCV's fixed-point undistortion iterated to convergence: the result re-projects to
    ``uv`` within 1e-6 px for distortion that is invertible over the image."""
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 1, 2)
    if not np.any(d):
        xy = cv2.undistortPoints(uv, k, None)
    else:
        xy = cv2.undistortPoints(uv, k, d, criteria=_UNDISTORT_CRITERIA)
    return np.asarray(xy, dtype=np.float64).reshape(-1, 2)


def _pinhole_rays(k: F64, d: F64, uv: F64) -> F64:
    rays = np.column_stack([_undistort_pinhole(k, d, uv), np.ones(len(uv))])
    return np.asarray(rays / np.linalg.norm(rays, axis=1, keepdims=True))


def _project_equidistant(k: F64, d: F64, points: F64) -> F64:
    # cv2.fisheye.projectPoints, with theta = atan2(r, z) so that it holds past 90 degrees
    r = np.hypot(points[:, 0], points[:, 1])
    theta = np.arctan2(r, points[:, 2])
    k1, k2, k3, k4 = d
    t2 = theta * theta
    theta_d = theta * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
    scale = np.divide(theta_d, r, out=np.zeros_like(r), where=r > 0)
    distorted = np.column_stack([points[:, 0] * scale, points[:, 1] * scale,
                                 np.ones(len(points))])
    return np.asarray(distorted @ k[:2].T, dtype=np.float64)


def _equidistant_rays(k: F64, d: F64, uv: F64) -> F64:
    homogeneous = np.column_stack([uv, np.ones(len(uv))])
    distorted = (homogeneous @ np.linalg.inv(k).T)[:, :2]
    theta_d = np.hypot(distorted[:, 0], distorted[:, 1])
    k1, k2, k3, k4 = d
    theta = theta_d.copy()
    for _ in range(_FISHEYE_NEWTON_STEPS):  # theta (1 + k1 t^2 + ...) = theta_d
        t2 = theta * theta
        value = theta * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))) - theta_d
        slope = 1 + t2 * (3 * k1 + t2 * (5 * k2 + t2 * (7 * k3 + t2 * 9 * k4)))
        step = value / slope
        theta = theta - step
        if not np.any(np.abs(step) > 1e-15):
            break
    direction = np.divide(distorted, theta_d[:, None], out=np.zeros_like(distorted),
                          where=theta_d[:, None] > 0)
    return np.column_stack([direction * np.sin(theta)[:, None], np.cos(theta)])


def _undistort_equidistant(k: F64, d: F64, uv: F64) -> F64:
    rays = _equidistant_rays(k, d, np.asarray(uv, dtype=np.float64).reshape(-1, 2))
    ahead = rays[:, 2:] > 0
    xy = np.divide(rays[:, :2], rays[:, 2:], out=np.full((len(rays), 2), np.nan), where=ahead)
    return np.asarray(xy, dtype=np.float64)


#: OpenCV's pinhole functions (``projectPoints``, ``undistortPoints``)
PINHOLE = Projection("pinhole", _project_pinhole, _pinhole_rays, _undistort_pinhole,
                     cv2.initUndistortRectifyMap)
#: the equidistant fisheye (``cv2.fisheye``'s model, beyond 90 degrees too)
EQUIDISTANT = Projection("fisheye", _project_equidistant, _equidistant_rays,
                         _undistort_equidistant, cv2.fisheye.initUndistortRectifyMap)

#: every lens model's projection, by its ROS ``distortion_model``
PROJECTIONS: dict[str, Projection] = {
    "plumb_bob": PINHOLE,
    "rational_polynomial": PINHOLE,
    "equidistant": EQUIDISTANT,
}


def projection(name: str) -> Projection:
    """The projection of the lens model ``name`` (or one of its aliases)."""
    return PROJECTIONS[canonical_name(name)]

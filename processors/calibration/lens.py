"""Projection with derivatives, vectorised over points: the calibration solver's camera math.

Every model has an intrinsic vector in a fixed order (:data:`INTRINSIC_NAMES`):
``plumb_bob`` fx fy cx cy k1 k2 p1 p2 k3, ``rational_polynomial`` the same plus k4 k5 k6 (the
radial factor is (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)), and
``equidistant`` fx fy cx cy k1 k2 k3 k4 (OpenCV's fisheye model, ``theta`` from the optical
axis). The values agree with :meth:`replay.camera.CameraModel.project`, which uses OpenCV.
:data:`DISTORTIONS` holds each model's distortion, by name.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

from replay.camera import CameraModel
from replay.lens_models import LENS_MODELS, canonical_name
from replay.messages import F64

#: every lens model's intrinsic vector (:data:`replay.lens_models.LENS_MODELS`)
INTRINSIC_NAMES: dict[str, tuple[str, ...]] = {
    name: model.intrinsic_names for name, model in LENS_MODELS.items()}
#: points nearer the optical axis than this (relative to their depth) use its limit
_AXIS_EPS = 1e-9


def intrinsics_of(model: CameraModel) -> F64:
    """The intrinsic vector of a camera model, in :data:`INTRINSIC_NAMES` order."""
    return np.concatenate([[model.fx, model.fy, model.cx, model.cy], model.d])


def model_of(distortion_model: str, intrinsics: F64, size: tuple[int, int]) -> CameraModel:
    """The camera model ``(width, height)`` of an intrinsic vector."""
    fx, fy, cx, cy = intrinsics[:4]
    k = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    return CameraModel(size[0], size[1], k, distortion_model, np.asarray(intrinsics[4:]))


def project(distortion_model: str, intrinsics: F64, points: F64) -> tuple[F64, F64, F64]:
    """Pixels ``(M, 2)`` of points ``(M, 3)`` in the camera frame, with the derivatives
    d pixel / d point ``(M, 2, 3)`` and d pixel / d intrinsics ``(M, 2, K)``. A point in the
    camera's plane (z = 0), which a poor starting pose can put there, has no projection: its
    rows are NaN (or infinite), without numpy's warnings."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return _project(distortion_model, intrinsics, points)


def _project(distortion_model: str, intrinsics: F64, points: F64) -> tuple[F64, F64, F64]:
    distort = DISTORTIONS[canonical_name(distortion_model)]
    normalized, d_point, d_dist = distort(intrinsics[4:], points)
    focal = intrinsics[:2]
    uv = normalized * focal + intrinsics[2:4]
    m = len(points)
    d_intrinsics = np.zeros((m, 2, len(intrinsics)))
    d_intrinsics[:, 0, 0] = normalized[:, 0]
    d_intrinsics[:, 1, 1] = normalized[:, 1]
    d_intrinsics[:, 0, 2] = 1.0
    d_intrinsics[:, 1, 3] = 1.0
    d_intrinsics[:, :, 4:] = d_dist * focal[None, :, None]
    return uv, d_point * focal[None, :, None], d_intrinsics


def _pinhole(d: F64, points: F64, *, rational: bool) -> tuple[F64, F64, F64]:
    """Distorted normalized coordinates, d/d point and d/d distortion (plumb_bob order;
    ``rational``: k4 k5 k6 of the denominator after them)."""
    z = points[:, 2]
    x, y = points[:, 0] / z, points[:, 1] / z
    k1, k2, p1, p2, k3 = d[:5]
    k4, k5, k6 = d[5:8] if rational else (0.0, 0.0, 0.0)
    r2 = x * x + y * y
    r4, r6 = r2 * r2, r2 * r2 * r2
    a = 1 + k1 * r2 + k2 * r4 + k3 * r6
    b = 1 + k4 * r2 + k5 * r4 + k6 * r6
    radial = a / b
    d_radial = ((k1 + 2 * k2 * r2 + 3 * k3 * r4) * b - a * (k4 + 2 * k5 * r2 + 3 * k6 * r4)) \
        / (b * b)
    xy = x * y
    xd = x * radial + 2 * p1 * xy + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * xy
    # d (xd, yd) / d (x, y)
    dxd_dx = radial + 2 * x * x * d_radial + 2 * p1 * y + 6 * p2 * x
    dxd_dy = 2 * xy * d_radial + 2 * p1 * x + 2 * p2 * y
    dyd_dx = 2 * xy * d_radial + 2 * p1 * x + 2 * p2 * y
    dyd_dy = radial + 2 * y * y * d_radial + 6 * p1 * y + 2 * p2 * x
    inv_z = 1.0 / z
    d_point = np.empty((len(points), 2, 3))
    d_point[:, 0, 0] = dxd_dx * inv_z
    d_point[:, 0, 1] = dxd_dy * inv_z
    d_point[:, 0, 2] = -(dxd_dx * x + dxd_dy * y) * inv_z
    d_point[:, 1, 0] = dyd_dx * inv_z
    d_point[:, 1, 1] = dyd_dy * inv_z
    d_point[:, 1, 2] = -(dyd_dx * x + dyd_dy * y) * inv_z
    d_dist = np.zeros((len(points), 2, 8 if rational else 5))
    over_b = 1.0 / b
    for column, power in ((0, r2), (1, r4), (4, r6)):  # k1, k2, k3
        d_dist[:, 0, column] = x * power * over_b
        d_dist[:, 1, column] = y * power * over_b
    d_dist[:, 0, 2], d_dist[:, 1, 2] = 2 * xy, r2 + 2 * y * y  # p1
    d_dist[:, 0, 3], d_dist[:, 1, 3] = r2 + 2 * x * x, 2 * xy  # p2
    if rational:
        for column, power in ((5, r2), (6, r4), (7, r6)):  # k4, k5, k6
            d_dist[:, 0, column] = -x * radial * power * over_b
            d_dist[:, 1, column] = -y * radial * power * over_b
    return np.column_stack([xd, yd]), d_point, d_dist


def _equidistant(d: F64, points: F64) -> tuple[F64, F64, F64]:
    """theta_d (cos phi, sin phi), d/d point and d/d (k1..k4); any point off the backward
    axis (``theta = atan2(rho, z)``)."""
    px, py, pz = points[:, 0], points[:, 1], points[:, 2]
    rho2 = px * px + py * py
    rho = np.sqrt(rho2)
    theta = np.arctan2(rho, pz)
    t2 = theta * theta
    powers = np.stack([theta * t2, theta * t2 * t2, theta * t2 ** 3, theta * t2 ** 4], axis=1)
    theta_d = theta + powers @ d
    d_theta_d = 1 + t2 * (3 * d[0] + t2 * (5 * d[1] + t2 * (7 * d[2] + t2 * 9 * d[3])))
    near_axis = rho <= _AXIS_EPS * np.abs(pz)
    safe_rho = np.where(near_axis, 1.0, rho)
    cos_phi, sin_phi = px / safe_rho, py / safe_rho
    r2z2 = rho2 + pz * pz
    # d theta / d point
    dt = np.column_stack([pz * cos_phi, pz * sin_phi, -rho]) / r2z2[:, None]
    d_point = np.empty((len(points), 2, 3))
    d_point[:, 0, :] = (d_theta_d * cos_phi)[:, None] * dt
    d_point[:, 1, :] = (d_theta_d * sin_phi)[:, None] * dt
    # d (cos phi, sin phi) / d (x, y), scaled by theta_d
    rho3 = safe_rho ** 3
    d_point[:, 0, 0] += theta_d * py * py / rho3
    d_point[:, 0, 1] -= theta_d * px * py / rho3
    d_point[:, 1, 0] -= theta_d * px * py / rho3
    d_point[:, 1, 1] += theta_d * px * px / rho3
    normalized = np.column_stack([theta_d * cos_phi, theta_d * sin_phi])
    d_dist = np.stack([powers * cos_phi[:, None], powers * sin_phi[:, None]], axis=1)
    if near_axis.any():
        # on the axis the lens is a pinhole: theta_d ~ theta ~ rho / z
        inv_z = 1.0 / pz[near_axis]
        normalized[near_axis] = points[near_axis, :2] * inv_z[:, None]
        limit = np.zeros((int(near_axis.sum()), 2, 3))
        limit[:, 0, 0] = limit[:, 1, 1] = inv_z
        limit[:, 0, 2] = -points[near_axis, 0] * inv_z ** 2
        limit[:, 1, 2] = -points[near_axis, 1] * inv_z ** 2
        d_point[near_axis] = limit
        d_dist[near_axis] = 0.0
    return normalized, d_point, d_dist


#: distorted normalized coordinates ``(M, 2)`` of points ``(M, 3)`` in the camera frame, with
#: d / d point ``(M, 2, 3)`` and d / d distortion coefficients ``(M, 2, len(D))``, given D
Distortion = Callable[[F64, F64], tuple[F64, F64, F64]]

#: every lens model's distortion with derivatives, by its ROS ``distortion_model``
DISTORTIONS: dict[str, Distortion] = {
    "plumb_bob": partial(_pinhole, rational=False),
    "rational_polynomial": partial(_pinhole, rational=True),
    "equidistant": _equidistant,
}

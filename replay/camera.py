"""Camera models in OpenCV conventions: pinhole with plumb_bob / rational_polynomial
distortion, and the equidistant fisheye (OpenCV's ``cv2.fisheye``, Kannala-Brandt).

Optical frame: x right, y down, z forward. Pixel centres sit at integer coordinates, so an
ideal W x H camera has its principal point at ((W - 1) / 2, (H - 1) / 2). Each model's
projection is its entry in :data:`replay.projections.PROJECTIONS`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .lens_models import LENS_MODELS, LensModel, canonical_name, lens_model
from .messages import F64, CameraInfo
from .projections import PROJECTIONS, Projection


def focal_from_hfov(width: int, hfov_rad: float) -> float:
    """Focal length in pixels: ``fx = (W / 2) / tan(hfov / 2)``."""
    return (width / 2.0) / math.tan(hfov_rad / 2.0)


@dataclass(frozen=True)
class CameraModel:
    """Intrinsics of one camera. ``k`` (3, 3); ``d`` (N,) in OpenCV order."""

    width: int
    height: int
    k: F64
    distortion_model: str = "plumb_bob"
    d: F64 = field(default_factory=lambda: np.zeros(5))

    def __post_init__(self) -> None:
        if self.distortion_model not in LENS_MODELS:
            raise ValueError(
                f"unknown distortion model {self.distortion_model!r} "
                f"(use {', '.join(LENS_MODELS)})"
            )
        n = len(LENS_MODELS[self.distortion_model].coefficients)
        d = np.zeros(n)
        given = np.asarray(self.d, dtype=np.float64).reshape(-1)
        if given.size > n:
            raise ValueError(f"{self.distortion_model} takes at most {n} coefficients")
        d[: given.size] = given
        object.__setattr__(self, "d", d)
        object.__setattr__(self, "k", np.asarray(self.k, dtype=np.float64).reshape(3, 3))

    @classmethod
    def ideal(cls, width: int, height: int, hfov_rad: float) -> CameraModel:
        """Square pixels, centred principal point, no distortion."""
        f = focal_from_hfov(width, hfov_rad)
        k = np.array([[f, 0.0, (width - 1) / 2.0], [0.0, f, (height - 1) / 2.0], [0, 0, 1.0]])
        return cls(width, height, k)

    @classmethod
    def from_camera_info(cls, info: CameraInfo) -> CameraModel:
        """The model of a CameraInfo (``fisheye`` read as ``equidistant``)."""
        return cls(info.width, info.height, info.k, canonical_name(info.distortion_model),
                   info.d)

    @property
    def fx(self) -> float:
        """Focal length along x, in pixels."""
        return float(self.k[0, 0])

    @property
    def fy(self) -> float:
        """Focal length along y, in pixels."""
        return float(self.k[1, 1])

    @property
    def cx(self) -> float:
        """Principal point x, in pixels."""
        return float(self.k[0, 2])

    @property
    def cy(self) -> float:
        """Principal point y, in pixels."""
        return float(self.k[1, 2])

    @property
    def is_fisheye(self) -> bool:
        """True for a model OpenCV handles with ``cv2.fisheye`` (equidistant)."""
        return self.lens.fisheye

    @property
    def lens(self) -> LensModel:
        """The lens model's entry in :data:`replay.lens_models.LENS_MODELS`."""
        return lens_model(self.distortion_model)

    @property
    def projection(self) -> Projection:
        """How the model images rays (:data:`replay.projections.PROJECTIONS`)."""
        return PROJECTIONS[self.distortion_model]

    @property
    def is_ideal(self) -> bool:
        """True for a distortion-free pinhole with square pixels and centred principal point."""
        return (
            not self.is_fisheye
            and not np.any(self.d)
            and self.fx == self.fy
            and self.k[0, 1] == 0
            and self.cx == (self.width - 1) / 2
            and self.cy == (self.height - 1) / 2
        )

    def camera_info(
        self, *, stamp_ns: int, frame_id: str, baseline_tx: float = 0.0
    ) -> CameraInfo:
        """CameraInfo of this (unrectified) camera; ``baseline_tx`` is ``P[0, 3] = -fx * B``."""
        p = np.zeros((3, 4))
        p[:, :3] = self.k
        p[0, 3] = baseline_tx
        return CameraInfo(
            stamp_ns=stamp_ns, frame_id=frame_id, width=self.width, height=self.height,
            distortion_model=self.distortion_model, d=self.d.copy(), k=self.k.copy(),
            r=np.eye(3), p=p,
        )

    def project(self, points_in_camera: F64) -> F64:
        """Pixels ``(N, 2)`` of points ``(N, 3)`` in the optical frame (z > 0; a fisheye
        also projects points beside and behind it, at angles up to 180 degrees)."""
        pts = np.asarray(points_in_camera, dtype=np.float64).reshape(-1, 3)
        return self.projection.project(self.k, self.d, pts)

    def pixel_rays(self, uv: F64) -> F64:
        """Unit rays ``(N, 3)`` in the optical frame of observed pixels ``(N, 2)``; exact
        inverse of :meth:`project` where the model is invertible."""
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        return self.projection.pixel_rays(self.k, self.d, uv)

    def distort_normalized(self, xy: F64) -> F64:
        """Pixels ``(N, 2)`` of ideal normalized coordinates ``(N, 2)`` (``x = X / Z``)."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        return self.project(np.column_stack([xy, np.ones(len(xy))]))

    def undistort_pixels(self, uv: F64) -> F64:
        """Ideal normalized coordinates ``(N, 2)`` of observed pixels ``(N, 2)``.

        Iterates OpenCV's fixed-point undistortion to convergence; the result re-projects to
        ``uv`` within 1e-6 px for distortion that is invertible over the image. A fisheye's
        pixels whose rays are 90 degrees or more from the axis have no such coordinates (NaN).
        """
        return self.projection.undistort_pixels(self.k, self.d, uv)

    def rectify_points(self, uv: F64, r: F64, p: F64) -> F64:
        """Pixels ``(N, 2)`` in the rectified image of rotation ``r`` (3, 3) and projection
        ``p`` (3, 3) or (3, 4) of observed pixels ``uv`` (N, 2)."""
        xy = self.undistort_pixels(uv)
        rays = np.column_stack([xy, np.ones(len(xy))]) @ np.asarray(r, dtype=np.float64).T
        projected = rays @ np.asarray(p, dtype=np.float64)[:, :3].T
        return np.asarray(projected[:, :2] / projected[:, 2:], dtype=np.float64)

    def rectify_maps(self, r: F64, new_k: F64, map_type: int = cv2.CV_16SC2, *,
                     size: tuple[int, int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``cv2.remap`` maps (image_proc's rectification): output pixel ``(u, v)`` of the
        pinhole camera ``new_k`` (3, 3) turned by ``r`` samples the raw image where this
        model images that ray (OpenCV's fisheye maps for an equidistant lens). The output
        is ``size`` (width, height), by default the raw image's."""
        size = size or (self.width, self.height)
        r = np.asarray(r, dtype=np.float64)
        new_k = np.asarray(new_k, dtype=np.float64)[:, :3]
        map1, map2 = self.projection.rectify_map(self.k, self.d, r, new_k, size, map_type)
        return map1, map2


def rectify_maps(info: CameraInfo, map_type: int = cv2.CV_16SC2
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Rectification maps of a CameraInfo: ``R`` and ``P[:, :3]`` (``K`` when P is empty)."""
    new_k = info.p[:, :3] if np.any(info.p[:, :3]) else info.k
    return CameraModel.from_camera_info(info).rectify_maps(info.r, new_k, map_type)


def stereo_right_from_left(left: CameraInfo, right: CameraInfo) -> F64 | None:
    """``right_from_left`` (4, 4) a stereo pair's camera_infos imply, or None when the right
    camera's projection holds no baseline.

    ROS's convention: ``R`` of each camera rotates its optical frame into the pair's common
    rectified frame (``X_rect = R X``), and the right camera's ``P = K' [I | t]`` holds
    ``t = (P[0, 3] / P[0, 0], P[1, 3] / P[1, 1], 0)``, the left rectified frame's origin seen
    from the right one (``P[0, 3] = -fx' B`` for a horizontal pair). Hence
    ``right_from_left = R_right^T [I | t] R_left``.
    """
    p = right.p
    if p[0, 0] == 0 or p[1, 1] == 0 or (p[0, 3] == 0 and p[1, 3] == 0):
        return None
    t = np.array([p[0, 3] / p[0, 0], p[1, 3] / p[1, 1], 0.0])
    out = np.eye(4)
    out[:3, :3] = right.r.T @ left.r
    out[:3, 3] = right.r.T @ t
    return out

"""Pinhole camera with plumb_bob / rational_polynomial distortion, OpenCV conventions.

Optical frame: x right, y down, z forward. Pixel centres sit at integer coordinates, so an
ideal W x H camera has its principal point at ((W - 1) / 2, (H - 1) / 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .messages import F64, CameraInfo

#: distortion model -> number of coefficients OpenCV uses for it
DISTORTION_MODELS = {"plumb_bob": 5, "rational_polynomial": 8}
_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14)


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
        if self.distortion_model not in DISTORTION_MODELS:
            raise ValueError(
                f"unknown distortion model {self.distortion_model!r} "
                f"(use {' or '.join(DISTORTION_MODELS)})"
            )
        n = DISTORTION_MODELS[self.distortion_model]
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
        """The intrinsic model a CameraInfo describes (plumb_bob when it names none)."""
        model = info.distortion_model or "plumb_bob"
        return cls(info.width, info.height, info.k, model, info.d)

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
    def is_ideal(self) -> bool:
        """True for a distortion-free camera with square pixels and centred principal point."""
        return (
            not np.any(self.d)
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
        """Pixels ``(N, 2)`` of points ``(N, 3)`` in the optical frame (z > 0)."""
        pts = np.asarray(points_in_camera, dtype=np.float64).reshape(-1, 3)
        uv, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), self.k, self.d)
        return np.asarray(uv, dtype=np.float64).reshape(-1, 2)

    def distort_normalized(self, xy: F64) -> F64:
        """Pixels ``(N, 2)`` of ideal normalized coordinates ``(N, 2)`` (``x = X / Z``)."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        return self.project(np.column_stack([xy, np.ones(len(xy))]))

    def undistort_pixels(self, uv: F64) -> F64:
        """Ideal normalized coordinates ``(N, 2)`` of observed pixels ``(N, 2)``.

        Iterates OpenCV's fixed-point undistortion to convergence; the result re-projects to
        ``uv`` within 1e-6 px for distortion that is invertible over the image.
        """
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 1, 2)
        if not np.any(self.d):
            xy = cv2.undistortPoints(uv, self.k, None)
        else:
            xy = cv2.undistortPoints(uv, self.k, self.d, criteria=_UNDISTORT_CRITERIA)
        return np.asarray(xy, dtype=np.float64).reshape(-1, 2)

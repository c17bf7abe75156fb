"""Intrinsic calibration of one camera: OpenCV's solver, outlier rejection, uncertainty.

Options keep camera_calibration's meaning: ``fix_principal_point`` holds (cx, cy) at the
image centre, ``fix_aspect_ratio`` forces fx = fy, ``zero_tangent_dist`` holds p1 = p2 = 0,
and ``k_coefficients`` radial terms are estimated (<= 3: plumb_bob, > 3:
rational_polynomial, up to 6).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError

#: order of OpenCV's stdDeviationsIntrinsics
STD_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")
#: a view whose RMS exceeds max(OUTLIER_FACTOR * median, OUTLIER_FLOOR_PX) is rejected
OUTLIER_FACTOR = 3.0
OUTLIER_FLOOR_PX = 0.3
MIN_VIEWS = 5
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)


@dataclass(frozen=True)
class CalibrationOptions:
    fix_principal_point: bool = False
    fix_aspect_ratio: bool = False
    zero_tangent_dist: bool = False
    k_coefficients: int = 2

    def __post_init__(self) -> None:
        if not 0 <= self.k_coefficients <= 6:
            raise ProcessorError(f"--k-coefficients must be 0..6, got {self.k_coefficients}")

    @property
    def distortion_model(self) -> str:
        return "rational_polynomial" if self.k_coefficients > 3 else "plumb_bob"

    @property
    def flags(self) -> int:
        flags = 0
        if self.fix_principal_point:
            flags |= cv2.CALIB_FIX_PRINCIPAL_POINT
        if self.fix_aspect_ratio:
            flags |= cv2.CALIB_FIX_ASPECT_RATIO
        if self.zero_tangent_dist:
            flags |= cv2.CALIB_ZERO_TANGENT_DIST
        if self.k_coefficients > 3:
            flags |= cv2.CALIB_RATIONAL_MODEL
        for n, flag in enumerate((cv2.CALIB_FIX_K1, cv2.CALIB_FIX_K2, cv2.CALIB_FIX_K3,
                                  cv2.CALIB_FIX_K4, cv2.CALIB_FIX_K5, cv2.CALIB_FIX_K6), 1):
            if self.k_coefficients < n:
                flags |= flag
        return flags


@dataclass
class MonoResult:
    """A calibrated camera and the evidence for it."""

    model: CameraModel
    rms_px: float
    view_ids: list[int]  # indices (into the views given) that were used
    view_rms_px: dict[int, float]  # per used view
    rejected: dict[int, str]  # view index -> why it was left out
    std: dict[str, float]  # standard deviation of every estimated parameter
    camera_from_board: dict[int, F64]  # (4, 4) per used view
    residuals_px: dict[int, F64] = field(default_factory=dict)  # (N, 2) per used view

    def parameters(self) -> dict[str, float]:
        m = self.model
        names = ["fx", "fy", "cx", "cy", *_distortion_names(m.distortion_model)]
        values = [m.fx, m.fy, m.cx, m.cy, *m.d.tolist()]
        return dict(zip(names, values, strict=True))


def _distortion_names(model: str) -> list[str]:
    return (["k1", "k2", "p1", "p2", "k3"] if model == "plumb_bob"
            else ["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"])


def _pose(rvec: np.ndarray, tvec: np.ndarray) -> F64:
    pose = np.eye(4)
    pose[:3, :3] = cv2.Rodrigues(rvec)[0]
    pose[:3, 3] = np.asarray(tvec).reshape(3)
    return pose


_Solution = tuple[float, CameraModel, list[F64], F64, F64, list[F64]]


def _solve(points_in_board: F64, corners: list[F64], size: tuple[int, int],
           options: CalibrationOptions) -> _Solution:
    object_points = [points_in_board.astype(np.float32)] * len(corners)
    image_points = [c.reshape(-1, 1, 2).astype(np.float32) for c in corners]
    n_d = 8 if options.k_coefficients > 3 else 5
    k0 = np.eye(3)
    try:
        rms, k, d, rvecs, tvecs, std_in, _std_ex, per_view = cv2.calibrateCameraExtended(
            object_points, image_points, size, k0, np.zeros(n_d), flags=options.flags,
            criteria=CRITERIA,
        )
    except cv2.error as err:
        raise ProcessorError(f"calibration failed: {str(err).strip().splitlines()[-1]}") from None
    d = np.asarray(d, dtype=np.float64).reshape(-1)[:n_d]
    model = CameraModel(size[0], size[1], np.asarray(k, dtype=np.float64),
                        options.distortion_model, d)
    poses = [_pose(r, t) for r, t in zip(rvecs, tvecs, strict=True)]
    residuals = []
    for pose, c in zip(poses, corners, strict=True):
        projected = model.project(points_in_board @ pose[:3, :3].T + pose[:3, 3])
        residuals.append(c - projected)
    return float(rms), model, poses, np.asarray(std_in, dtype=np.float64).reshape(-1), \
        np.asarray(per_view, dtype=np.float64).reshape(-1), residuals


def calibrate_mono(points_in_board: F64, corners: list[F64], size: tuple[int, int],
                   options: CalibrationOptions, *, reject_outliers: bool = True) -> MonoResult:
    """Calibrate from views ``corners[i]`` ``(N, 2)`` of the board points ``(N, 3)``.

    Views whose RMS error lies far above the rest are removed and the camera re-solved,
    up to three rounds.
    """
    if len(corners) < MIN_VIEWS:
        raise ProcessorError(
            f"too few good views to calibrate: {len(corners)} (need at least {MIN_VIEWS}); "
            "record more board poses"
        )
    active = list(range(len(corners)))
    rejected: dict[int, str] = {}
    for _round in range(4):
        rms, model, poses, std, per_view, residuals = _solve(
            points_in_board, [corners[i] for i in active], size, options)
        if not reject_outliers:
            break
        median = float(np.median(per_view))
        limit = max(OUTLIER_FACTOR * median, OUTLIER_FLOOR_PX)
        bad = [(i, e) for i, e in zip(active, per_view, strict=True) if e > limit]
        if not bad or len(active) - len(bad) < MIN_VIEWS:
            break
        for i, e in bad:
            rejected[i] = (f"reprojection RMS {e:.3f} px > {limit:.3f} px "
                           f"({OUTLIER_FACTOR:g}x the median {median:.3f} px)")
        active = [i for i in active if i not in rejected]
    names = ["fx", "fy", "cx", "cy", *_distortion_names(model.distortion_model)]
    opencv_index = {n: STD_NAMES.index(n) for n in names}
    sigma = {n: float(std[opencv_index[n]]) for n in names}
    return MonoResult(
        model=model, rms_px=rms, view_ids=active,
        view_rms_px={i: float(e) for i, e in zip(active, per_view, strict=True)},
        rejected=rejected, std=sigma,
        camera_from_board=dict(zip(active, poses, strict=True)),
        residuals_px=dict(zip(active, residuals, strict=True)),
    )


def max_projection_difference(a: CameraModel, b: CameraModel, step_px: int = 8,
                              within: F64 | None = None) -> float:
    """Largest pixel distance between where ``a`` and ``b`` image the same ray.

    Over the whole image, or only inside the convex hull of the points ``within`` (N, 2),
    e.g. every corner the calibration saw: outside it a model only extrapolates.
    """
    us, vs = np.meshgrid(np.arange(0, a.width, step_px, dtype=np.float64),
                         np.arange(0, a.height, step_px, dtype=np.float64))
    pixels = np.column_stack([us.ravel(), vs.ravel()])
    if within is not None:
        hull = cv2.convexHull(np.asarray(within, dtype=np.float32).reshape(-1, 1, 2))
        inside = [cv2.pointPolygonTest(hull, (float(u), float(v)), False) >= 0
                  for u, v in pixels]
        pixels = pixels[np.asarray(inside, dtype=bool)]
    rays = a.undistort_pixels(pixels)
    return float(np.linalg.norm(b.distort_normalized(rays) - pixels, axis=1).max())


def cross_validate(points_in_board: F64, corners: list[F64], size: tuple[int, int],
                   options: CalibrationOptions, seed: int = 0) -> float | None:
    """Calibrate two disjoint halves separately; their max projection difference (px)."""
    if len(corners) < 2 * MIN_VIEWS:
        return None
    order = np.random.default_rng(seed).permutation(len(corners))
    halves = [order[: len(order) // 2], order[len(order) // 2:]]
    models = [
        calibrate_mono(points_in_board, [corners[i] for i in h], size, options,
                       reject_outliers=False).model
        for h in halves
    ]
    return max_projection_difference(models[0], models[1])

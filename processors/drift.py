"""Does a stereo calibration still fit its images? Vertical disparity of natural features.

A calibrated pair, rectified with its calibration, sees every scene point on the same image
row in both cameras. Once the right camera has turned by a small rotation ``w`` (rad, about
the axes of its rectified frame: x right, y down, z forward) the right image's point at
normalized coordinates ``(x, y)`` moves by

    dy = f (1 + y²) w_x - f x y w_y - f x w_z

pixels vertically (``f`` the rectified focal length). Pitch (``w_x``) shifts every row,
roll (``w_z``) tilts the rows; yaw (``w_y``) only enters through the small ``x y`` term —
it moves points along the rows, which a stereo pair cannot tell from depth — so it is left
out of the fit. Features are ORB corners matched across the pair (cross-checked, within a
band of rows and in front of the rig), refined to sub-pixel by Lucas-Kanade from the left
image into the right, and rectified as points with each camera's ``K, D, R, P``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64, CameraInfo

from .errors import ProcessorError

__all__ = ["PairMatches", "RotationFit", "StereoMatcher", "fit_rotation", "window_noise"]

#: a matched pair's rows may differ by this much before refinement (px): a drift of a
#: degree or two, not a feature mistaken for another one a row of texture away
BAND_PX = 12.0
#: Lucas-Kanade may move a match this far from where ORB put it (px)
REFINE_PX = 2.0
LK_WINDOW = (11, 11)
LK_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 0.01)
LK_MIN_EIGEN = 1e-3
#: least-squares rounds of the rotation fit, and the residual (robust sigmas) a match may
#: have to take part in the next one
REFITS, REJECT_SIGMAS = 3, 3.0
#: consistent with a normal distribution: sigma = MAD_TO_SIGMA * median absolute deviation
MAD_TO_SIGMA = 1.4826


@dataclass(frozen=True)
class PairMatches:
    """Features matched in one stereo pair: ``left_px`` and ``right_px`` ``(N, 2)`` in the
    rectified images (the calibration's ``P``); ``dy_px`` ``(N,)`` right minus left row."""

    left_px: F64
    right_px: F64

    @property
    def dy_px(self) -> F64:
        """Vertical disparity ``(N,)`` of each match (px)."""
        return np.asarray(self.right_px[:, 1] - self.left_px[:, 1])


class StereoMatcher:
    """Matches natural features of a calibrated pair's raw images (``(H, W)`` uint8),
    returning them rectified; one matcher per pair of camera models."""

    def __init__(self, left: CameraInfo, right: CameraInfo, *, features: int = 500) -> None:
        for name, info in (("left", left), ("right", right)):
            if not np.any(info.p[:, :3]):
                raise ProcessorError(f"the {name} camera_info has no projection matrix P: "
                                     "not a calibrated stereo pair")
        self.left, self.right = left, right
        self.left_model = CameraModel.from_camera_info(left)
        self.right_model = CameraModel.from_camera_info(right)
        self._orb = cv2.ORB.create(nfeatures=features, fastThreshold=10)
        self._matcher = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)

    def rectify(self, uv_left: F64, uv_right: F64) -> tuple[F64, F64]:
        """Raw pixels ``(N, 2)`` of each camera in its rectified image."""
        return (self.left_model.rectify_points(uv_left, self.left.r, self.left.p),
                self.right_model.rectify_points(uv_right, self.right.r, self.right.p))

    def match(self, left_gray: np.ndarray, right_gray: np.ndarray) -> PairMatches:
        """The pair's matched features, rectified (none when the images show no texture)."""
        empty = PairMatches(np.zeros((0, 2)), np.zeros((0, 2)))
        key_left, desc_left = self._orb.detectAndCompute(left_gray, None)
        key_right, desc_right = self._orb.detectAndCompute(right_gray, None)
        if desc_left is None or desc_right is None:
            return empty
        matches = self._matcher.match(desc_left, desc_right)
        if not matches:
            return empty
        raw_left = np.array([key_left[m.queryIdx].pt for m in matches], dtype=np.float64)
        raw_right = np.array([key_right[m.trainIdx].pt for m in matches], dtype=np.float64)
        rect_left, rect_right = self.rectify(raw_left, raw_right)
        near = (np.abs(rect_right[:, 1] - rect_left[:, 1]) < BAND_PX) \
            & (rect_left[:, 0] - rect_right[:, 0] > -1.0)
        if not near.any():
            return empty
        start = np.ascontiguousarray(raw_left[near], dtype=np.float32).reshape(-1, 1, 2)
        guess = np.ascontiguousarray(raw_right[near], dtype=np.float32).reshape(-1, 1, 2)
        refined, status, _ = cv2.calcOpticalFlowPyrLK(
            left_gray, right_gray, start, guess.copy(), winSize=LK_WINDOW, maxLevel=1,
            criteria=LK_CRITERIA, minEigThreshold=LK_MIN_EIGEN,
            flags=cv2.OPTFLOW_USE_INITIAL_FLOW | cv2.OPTFLOW_LK_GET_MIN_EIGENVALS)
        refined = refined.reshape(-1, 2).astype(np.float64)
        kept = (status.reshape(-1) == 1) \
            & (np.linalg.norm(refined - guess.reshape(-1, 2), axis=1) < REFINE_PX)
        if not kept.any():
            return empty
        left_px, right_px = self.rectify(raw_left[near][kept], refined[kept])
        return PairMatches(left_px, right_px)


@dataclass(frozen=True)
class RotationFit:
    """The small rotation of the right camera that explains a set of vertical disparities:
    ``pitch_rad`` about its x axis and ``roll_rad`` about its z axis (its optical frame as
    calibrated), the median absolute vertical disparity left after the fit (what the pair
    would show were it calibrated) and the matches used."""

    pitch_rad: float
    roll_rad: float
    clean_px: float
    matches: int

    @property
    def angle_deg(self) -> float:
        """The rotation's angle (degrees)."""
        return math.degrees(math.hypot(self.pitch_rad, self.roll_rad))


def fit_rotation(matches: PairMatches, *, p_rect: F64, rect_from_right: F64) -> RotationFit:
    """Least-squares pitch and roll of the right camera from its matches' vertical
    disparities (outliers beyond ``REJECT_SIGMAS`` robust sigmas left out).

    ``p_rect`` (3, 4) is the rectified right camera's projection (its ``P``),
    ``rect_from_right`` (3, 3) its rectification ``R``: the rotation is fitted about the
    rectified axes and turned back into the right camera's own frame."""
    if p_rect.shape != (3, 4) or rect_from_right.shape != (3, 3):
        raise ValueError(f"p_rect must be (3, 4) and rect_from_right (3, 3), got "
                         f"{p_rect.shape} and {rect_from_right.shape}")
    count = len(matches.dy_px)
    if count < 3:
        return RotationFit(math.nan, math.nan, math.nan, count)
    f_px, cx, cy = float(p_rect[1, 1]), float(p_rect[0, 2]), float(p_rect[1, 2])
    x = (matches.right_px[:, 0] - cx) / float(p_rect[0, 0])
    y = (matches.right_px[:, 1] - cy) / f_px
    design = f_px * np.column_stack([1.0 + y * y, -x])
    dy = matches.dy_px
    # a robust start, pitch alone (the median), then least squares on the matches within
    # REJECT_SIGMAS robust sigmas of the previous fit: features on occluding edges, seen
    # against different backgrounds by the two cameras, are not points of the scene
    solution = np.array([float(np.median(dy / design[:, 0])), 0.0])
    for _ in range(REFITS):
        residual = dy - design @ solution
        sigma = MAD_TO_SIGMA * float(np.median(np.abs(residual - np.median(residual))))
        used = np.abs(residual) <= max(REJECT_SIGMAS * sigma, 1e-6)
        if used.sum() < 3:
            return RotationFit(math.nan, math.nan, math.nan, count)
        solution = np.linalg.lstsq(design[used], dy[used], rcond=None)[0]
    residual = dy - design @ solution
    rotation_rect = np.array([solution[0], 0.0, solution[1]])
    rotation_right = rect_from_right.T @ rotation_rect
    return RotationFit(float(rotation_right[0]), float(rotation_right[2]),
                       float(np.median(np.abs(residual))), int(used.sum()))


def window_noise(values: F64) -> float:
    """Robust noise ``sigma`` of a metric's windows ``(N,)`` from the differences of
    successive windows (NaNs skipped): ``MAD_TO_SIGMA * median |v_i - v_i-1| / sqrt 2``.
    A drift is a step between two windows, so it moves one difference, not the estimate;
    0 when fewer than two windows have a value."""
    finite = np.asarray(values, dtype=np.float64)
    finite = finite[np.isfinite(finite)]
    if finite.size < 2:
        return 0.0
    return float(MAD_TO_SIGMA * np.median(np.abs(np.diff(finite))) / math.sqrt(2.0))

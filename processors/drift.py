"""Does a stereo calibration still fit its images? Vertical disparity of natural features.

A calibrated pair, rectified with its calibration, sees every scene point on the same image
row in both cameras. Once the right camera has turned by a small rotation ``w`` (rad, about
the axes of its rectified frame: x right, y down, z forward) the right image's point at
normalized coordinates ``(x, y)`` moves by

    dy = f (1 + y²) w_x - f x y w_y - f x w_z

pixels vertically (``f`` the rectified focal length). Pitch (``w_x``) shifts every row,
roll (``w_z``) tilts the rows; yaw (``w_y``) only enters through the small ``x y`` term —
it moves points along the rows, which a stereo pair cannot tell from depth — so it is left
out of the fit. When the rig moves, a point moving down the image at ``v`` px/s sits a
further ``v tau`` lower in a right frame exposed ``tau`` after its left one: matches that
carry their rows' speed and their frames' stamp gap ``s`` also give the offset ``d`` between
the cameras' stamps (``tau = s - d``, :mod:`processors.time_offset`), fitted beside the
rotation when most of them move. Features are ORB corners matched across the pair
(cross-checked, within a band of rows and in front of the rig), refined to sub-pixel by
Lucas-Kanade from the left image into the right, and rectified as points with each camera's
``K, D, R, P``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

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
#: the fit's start: rotations through two matches each (seeded, so a check repeats), and the
#: vertical disparity (px) within which a match agrees with one
HYPOTHESES, AGREE_PX = 400, 0.5
#: the least residual sigma a view is given (px): a few matches can agree by chance
MIN_SIGMA_PX = 0.02
#: consistent with a normal distribution: sigma = MAD_TO_SIGMA * median absolute deviation
MAD_TO_SIGMA = 1.4826
#: matches move across the rows when their median row speed reaches this (px per second):
#: a sixth of a pixel per frame at 30 Hz, far above what noise gives a still rig's features
MOVING_PX_S = 5.0
#: Gauss-Newton rounds of the offset, the model being quadratic in it
OFFSET_ITERATIONS = 3


@dataclass(frozen=True)
class PairMatches:
    """Features matched in one stereo pair: ``left_px`` and ``right_px`` ``(N, 2)`` in the
    rectified images (the calibration's ``P``); ``dy_px`` ``(N,)`` right minus left row.
    With the left frames around it: each feature's row speed ``row_speed_px_s`` ``(N,)``
    and acceleration ``row_acceleration_px_s2`` ``(N,)`` in the left image, and the right
    frame's stamp minus the left one's ``stamp_gap_s`` ``(N,)``."""

    left_px: F64
    right_px: F64
    row_speed_px_s: F64 | None = None
    stamp_gap_s: F64 | None = None
    row_acceleration_px_s2: F64 | None = None

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
        raw_left, raw_right = self.match_raw(left_gray, right_gray)
        if not len(raw_left):
            return PairMatches(np.zeros((0, 2)), np.zeros((0, 2)))
        left_px, right_px = self.rectify(raw_left, raw_right)
        return PairMatches(left_px, right_px)

    def match_raw(self, left_gray: np.ndarray, right_gray: np.ndarray) -> tuple[F64, F64]:
        """The pair's matched features ``(N, 2)`` in each raw image (the right ones refined
        by Lucas-Kanade; none when the images show no texture)."""
        empty = (np.zeros((0, 2)), np.zeros((0, 2)))
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
        return raw_left[near][kept], refined[kept]


@dataclass(frozen=True)
class RotationFit:
    """The small rotation of the right camera that explains a set of vertical disparities:
    ``pitch_rad`` about its x axis and ``roll_rad`` about its z axis (its optical frame as
    calibrated), their standard errors (from the residuals), the median absolute vertical
    disparity left after the fit (what the pair would show were it calibrated) and the
    matches used."""

    pitch_rad: float
    roll_rad: float
    clean_px: float
    matches: int
    pitch_std_rad: float = math.nan
    roll_std_rad: float = math.nan
    #: how much later the right camera stamps an instant than the left (s) and its standard
    #: error, when the matches moved (NaN otherwise)
    offset_s: float = math.nan
    offset_std_s: float = math.nan

    @property
    def angle_deg(self) -> float:
        """The rotation's angle (degrees)."""
        return math.degrees(math.hypot(self.pitch_rad, self.roll_rad))


def fit_rotation(matches: PairMatches, *, p_rect: F64, rect_from_right: F64,
                 views: npt.NDArray[np.int64] | None = None) -> RotationFit:
    """Weighted least-squares pitch and roll of the right camera from its matches' vertical
    disparities (outliers beyond ``REJECT_SIGMAS`` robust sigmas left out).

    ``p_rect`` (3, 4) is the rectified right camera's projection (its ``P``),
    ``rect_from_right`` (3, 3) its rectification ``R``: the rotation is fitted about the
    rectified axes and turned back into the right camera's own frame. ``views`` ``(N,)``
    names the pair of images each match comes from (default: one): each view's matches are
    weighted by ``1 / sigma_view²``, its own residuals' robust sigma, so that a view whose
    features are poorly placed (a board seen edge-on) counts for less than a sharp one."""
    if p_rect.shape != (3, 4) or rect_from_right.shape != (3, 3):
        raise ValueError(f"p_rect must be (3, 4) and rect_from_right (3, 3), got "
                         f"{p_rect.shape} and {rect_from_right.shape}")
    count = len(matches.dy_px)
    views = np.zeros(count, np.int64) if views is None else np.asarray(views, np.int64)
    if views.shape != (count,):
        raise ValueError(f"views must be ({count},), got {views.shape}")
    timed = _moving(matches)
    if count < (4 if timed else 3):
        return RotationFit(math.nan, math.nan, math.nan, count)
    f_px, cx, cy = float(p_rect[1, 1]), float(p_rect[0, 2]), float(p_rect[1, 2])
    x = (matches.right_px[:, 0] - cx) / float(p_rect[0, 0])
    y = (matches.right_px[:, 1] - cy) / f_px
    rotation = f_px * np.column_stack([1.0 + y * y, -x])
    design, dy, offset_s = rotation, matches.dy_px, 0.0
    for _ in range(OFFSET_ITERATIONS if timed else 1):
        if timed:  # dy = rotation + f(d), f linearized about the offset so far
            design, dy = _about_offset(matches, rotation, offset_s)
        solved = _robust_solution(design, dy, views)
        if solved is None:
            return RotationFit(math.nan, math.nan, math.nan, count)
        solution, residual, used, sigma_px = solved
        offset_s = float(solution[2]) if timed else 0.0
    weighted = design[used] / sigma_px[used, None]
    full = np.linalg.pinv(weighted.T @ weighted)
    covariance_rect = np.zeros((3, 3))
    covariance_rect[np.ix_([0, 2], [0, 2])] = full[:2, :2]
    covariance = rect_from_right.T @ covariance_rect @ rect_from_right
    rotation_right = rect_from_right.T @ np.array([solution[0], 0.0, solution[1]])
    offset = (offset_s, math.sqrt(max(float(full[2, 2]), 0.0))) if timed \
        else (math.nan, math.nan)
    return RotationFit(float(rotation_right[0]), float(rotation_right[2]),
                       float(np.median(np.abs(residual))), int(used.sum()),
                       math.sqrt(covariance[0, 0]), math.sqrt(covariance[2, 2]), *offset)


def _about_offset(matches: PairMatches, rotation: F64, offset_s: float) -> tuple[F64, F64]:
    """The design ``(N, 3)`` and right-hand side ``(N,)`` of the fit of the rotation and the
    offset ``d``, linearized about ``offset_s``: a feature of row speed ``v`` and
    acceleration ``a`` sits ``f(d) = v t + a t^2 / 2`` lower in the right frame exposed
    ``t = s - d`` after the left one (``s``: the frames' stamp gap)."""
    assert matches.row_speed_px_s is not None and matches.stamp_gap_s is not None
    speed = matches.row_speed_px_s
    acceleration = matches.row_acceleration_px_s2 if matches.row_acceleration_px_s2 \
        is not None else np.zeros_like(speed)
    lag = matches.stamp_gap_s - offset_s
    slope = -(speed + acceleration * lag)  # d f / d d
    moved = speed * lag + 0.5 * acceleration * lag ** 2
    return np.column_stack([rotation, slope]), matches.dy_px - moved + slope * offset_s


def _robust_solution(design: F64, dy: F64, views: npt.NDArray[np.int64]
                     ) -> tuple[F64, F64, npt.NDArray[np.bool_], F64] | None:
    """The unknowns ``(K,)`` fitted robustly to ``dy`` ``(N,)``, the residuals, the matches
    used and their views' sigmas; None when too few matches agree."""
    # the matches that agree with the unknowns through K of them, then least squares on
    # those within REJECT_SIGMAS robust sigmas (of their view's agreeing ones) of the
    # previous fit: features on occluding edges, seen against different backgrounds by the
    # two cameras, are not points of the scene, and the corners of a repeating pattern (a
    # checkerboard) matched one period off agree among themselves, frame by frame, enough
    # to pull a median
    residual = dy - design @ _consensus(design, dy)
    used = np.abs(residual) <= AGREE_PX
    solution: F64 = np.zeros(design.shape[1])
    sigma_px: F64 = np.zeros(len(dy))
    for _ in range(REFITS):
        if used.sum() < design.shape[1] + 1:
            return None
        sigma_px = _view_sigmas(residual, used, views)
        weight = np.sqrt(used / sigma_px**2)
        solution = np.asarray(np.linalg.lstsq(design * weight[:, None], dy * weight,
                                              rcond=None)[0], dtype=np.float64)
        residual = dy - design @ solution
        used = np.abs(residual) <= REJECT_SIGMAS * sigma_px
    return solution, residual, used, sigma_px


def _moving(matches: PairMatches) -> bool:
    """Whether most matches move across the rows (at least :data:`MOVING_PX_S`), so that
    the offset between the stamps is fitted with the rotation."""
    speed = matches.row_speed_px_s
    return speed is not None and matches.stamp_gap_s is not None and len(speed) > 0 \
        and bool(np.median(np.abs(np.nan_to_num(speed))) >= MOVING_PX_S)


def _view_sigmas(residual: F64, used: npt.NDArray[np.bool_], views: npt.NDArray[np.int64]
                 ) -> F64:
    """Each match's view's robust residual sigma ``(N,)`` (px) over its used matches; a
    view with fewer than three takes the sigma of all; at least ``MIN_SIGMA_PX``."""
    def robust(values: F64) -> float:
        return MAD_TO_SIGMA * float(np.median(np.abs(values - np.median(values))))

    every = robust(residual[used])
    sigma_px = np.full(len(residual), every)
    for view in np.unique(views):
        mine = views == view
        if (used & mine).sum() >= 3:
            sigma_px[mine] = robust(residual[used & mine])
    return np.asarray(np.maximum(sigma_px, MIN_SIGMA_PX), dtype=np.float64)


def _consensus(design: F64, dy: F64) -> F64:
    """The unknowns ``(K,)`` (rotation, and the offset when fitted) through ``K`` matches
    that most matches agree with (within ``AGREE_PX``); pitch alone through the median when
    no ``K`` matches determine them."""
    rng = np.random.default_rng(0)
    k = design.shape[1]
    picked = rng.integers(0, len(dy), (HYPOTHESES, k))
    systems = design[picked]  # (H, K, K)
    det = np.linalg.det(systems)
    usable = np.abs(det) > 1e-9 * np.abs(design).max(axis=0).prod()
    if not usable.any():
        return np.array([float(np.median(dy / design[:, 0])), *[0.0] * (k - 1)])
    solutions = np.linalg.solve(systems[usable], dy[picked[usable]][:, :, None])[:, :, 0]
    agree = (np.abs(dy[None, :] - solutions @ design.T) <= AGREE_PX).sum(axis=1)
    return np.asarray(solutions[int(np.argmax(agree))])


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

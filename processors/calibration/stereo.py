"""Stereo extrinsics and rectification from per-camera calibrations.

Each camera's intrinsics come from every frame it saw (``calibrate_mono``); the pair's
rotation and translation come from the joint views with those intrinsics held fixed
(``stereoCalibrate``), then ``stereoRectify`` gives R1, R2, P1, P2 with
``P2[0, 3] = -fx' * B``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError
from .joint import MIN_VIEWS

CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
#: a joint view whose RMS exceeds max(OUTLIER_FACTOR * median, OUTLIER_FLOOR_PX) is rejected
OUTLIER_FACTOR = 3.0
OUTLIER_FLOOR_PX = 0.3
#: rounds of removing joint views far above the rest, each followed by a fresh solve
REJECTION_ROUNDS = 3
#: stereo re-solves for the baseline's standard deviation, each on this many views at most
BOOTSTRAP_RESAMPLES = 30
BOOTSTRAP_VIEWS = 40
#: views whose rig rotation lies within this angle of another's support it
ORIENTATION_AGREEMENT_RAD = math.radians(10.0)


@dataclass
class StereoResult:
    """``right_from_left`` (4, 4): X_right = R X_left + T (metres)."""

    right_from_left: F64
    rms_px: float
    r1: F64
    r2: F64
    p1: F64
    p2: F64
    epipolar_rms_px: float
    baseline_m: float
    baseline_std_m: float
    square_m: float  # square size re-estimated by triangulating the joint views
    view_epipolar_px: list[float]  # per used joint view
    view_ids: list[int] = field(default_factory=list)  # indices of the joint views used
    rejected: dict[int, str] = field(default_factory=dict)  # joint view index -> why

    @property
    def rotation_deg(self) -> float:
        """Angle of the rig rotation ``right_from_left``, in degrees."""
        angle = math.acos(max(-1.0, min(1.0, (np.trace(self.right_from_left[:3, :3]) - 1) / 2)))
        return math.degrees(angle)


def far_above_the_rest(view_ids: list[int], view_rms_px: F64, what: str) -> dict[int, str]:
    """Views whose RMS error exceeds max(OUTLIER_FACTOR x the median, OUTLIER_FLOOR_PX),
    with why; none when removing them would leave fewer than MIN_VIEWS."""
    median = float(np.median(view_rms_px))
    limit = max(OUTLIER_FACTOR * median, OUTLIER_FLOOR_PX)
    bad = {i: (f"{what} RMS {e:.3f} px > {limit:.3f} px "
               f"({OUTLIER_FACTOR:g}x the median {median:.3f} px)")
           for i, e in zip(view_ids, view_rms_px, strict=True) if e > limit}
    return bad if len(view_ids) - len(bad) >= MIN_VIEWS else {}


def rectified_points(corners_px: F64, model: CameraModel, r: F64, p: F64) -> F64:
    """Corners ``(N, 2)`` in the rectified image given by rotation ``r`` and projection ``p``."""
    out = cv2.undistortPoints(corners_px.reshape(-1, 1, 2), model.k, model.d, R=r, P=p)
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


def epipolar_errors(left: list[F64], right: list[F64], *, left_model: CameraModel,
                    right_model: CameraModel, r1: F64, p1: F64, r2: F64, p2: F64) -> list[float]:
    """Per joint view, RMS of the row difference of matching rectified corners (px)."""
    errors = []
    for cl, cr in zip(left, right, strict=True):
        yl = rectified_points(cl, left_model, r1, p1)[:, 1]
        yr = rectified_points(cr, right_model, r2, p2)[:, 1]
        errors.append(float(np.sqrt(np.mean((yl - yr) ** 2))))
    return errors


def _board_rotation(points_in_board: F64, corners_px: F64, model: CameraModel) -> F64:
    """``camera_from_board`` rotation (3, 3) of one view."""
    _ok, rvec, _tvec = cv2.solvePnP(points_in_board.astype(np.float64),
                                    corners_px.astype(np.float64), model.k, model.d)
    return np.asarray(cv2.Rodrigues(rvec)[0], dtype=np.float64)


def _angle_rad(a: F64, b: F64) -> float:
    return math.acos(max(-1.0, min(1.0, (float(np.trace(a @ b.T)) - 1) / 2)))


def orient_right_views(points_in_board: F64, left: list[F64], right: list[F64], *,
                       left_model: CameraModel, right_model: CameraModel) -> list[F64]:
    """The right views ``(N, 2)`` numbered from the same board corner as the left ones.

    A chessboard turned by 180 degrees looks the same, so each camera's detection may start
    from either end of it; near the turn where the two choices meet, the two cameras of a
    pair can disagree. The rig's rotation (right from left) is the same in every view: each
    right view is kept or reversed, whichever gives the rotation that most views support.
    """
    candidates = []
    for cl, cr in zip(left, right, strict=True):
        left_from_board = _board_rotation(points_in_board, cl, left_model)
        candidates.append([_board_rotation(points_in_board, c, right_model) @ left_from_board.T
                           for c in (cr, cr[::-1])])
    if not candidates:
        return []
    flat = [rotation for pair in candidates for rotation in pair]
    support = [sum(min(_angle_rad(r, a), _angle_rad(r, b)) < ORIENTATION_AGREEMENT_RAD
                   for a, b in candidates) for r in flat]
    consensus = flat[int(np.argmax(support))]
    return [cr if _angle_rad(a, consensus) <= _angle_rad(b, consensus)
            else np.ascontiguousarray(cr[::-1])
            for cr, (a, b) in zip(right, candidates, strict=True)]


def _stereo_solve(points_in_board: F64, left: list[F64], right: list[F64], *,
                  left_model: CameraModel, right_model: CameraModel
                  ) -> tuple[float, F64, F64, F64]:
    """R, T of the rig with the intrinsics held; RMS and per-view RMS (px, worse camera)."""
    size = (left_model.width, left_model.height)
    objects = [points_in_board.astype(np.float32)] * len(left)
    try:
        out = cv2.stereoCalibrateExtended(
            objects, [c.reshape(-1, 1, 2).astype(np.float32) for c in left],
            [c.reshape(-1, 1, 2).astype(np.float32) for c in right],
            left_model.k, left_model.d, right_model.k, right_model.d, size, np.eye(3),
            np.zeros(3), flags=cv2.CALIB_FIX_INTRINSIC, criteria=CRITERIA,
        )
    except cv2.error as err:
        raise ProcessorError(f"stereo calibration failed: {str(err).strip().splitlines()[-1]}") \
            from None
    rms, rot, trans, per_view = out[0], out[5], out[6], out[11]
    return (float(rms), np.asarray(rot, dtype=np.float64),
            np.asarray(trans, dtype=np.float64).reshape(3),
            np.asarray(per_view, dtype=np.float64).reshape(len(left), 2).max(axis=1))


def calibrate_stereo(points_in_board: F64, left: list[F64], right: list[F64], *,
                     left_model: CameraModel, right_model: CameraModel,
                     square_m: float) -> StereoResult:
    """Extrinsics and rectification from joint views ``left[i]``, ``right[i]`` ``(N, 2)``.

    Joint views whose error lies far above the rest (e.g. two frames paired across a move
    of the board) are removed and the rig re-solved, up to three rounds.
    """
    if len(left) < MIN_VIEWS:
        raise ProcessorError(
            f"too few joint stereo views: {len(left)} (need at least {MIN_VIEWS}); "
            "both cameras must see the whole board at the same time"
        )
    active = list(range(len(left)))
    rejected: dict[int, str] = {}
    for round_ in range(REJECTION_ROUNDS + 1):
        rms, rot, trans, per_view = _stereo_solve(
            points_in_board, [left[i] for i in active], [right[i] for i in active],
            left_model=left_model, right_model=right_model)
        bad = far_above_the_rest(active, per_view, "stereo reprojection") \
            if round_ < REJECTION_ROUNDS else {}
        if not bad:
            break
        rejected |= {i: f"{why}: the two frames do not show the board at one pose"
                     for i, why in bad.items()}
        active = [i for i in active if i not in rejected]
    left, right = [left[i] for i in active], [right[i] for i in active]
    size = (left_model.width, left_model.height)
    try:
        r1_cv, r2_cv, p1_cv, p2_cv, _q, _roi1, _roi2 = cv2.stereoRectify(
            left_model.k, left_model.d, right_model.k, right_model.d, size, rot,
            trans.reshape(3, 1), flags=cv2.CALIB_ZERO_DISPARITY, alpha=0.0,
        )
    except cv2.error as err:
        raise ProcessorError(f"stereo rectification failed: "
                             f"{str(err).strip().splitlines()[-1]}") from None
    r1, r2 = np.asarray(r1_cv, dtype=np.float64), np.asarray(r2_cv, dtype=np.float64)
    p1, p2 = np.asarray(p1_cv, dtype=np.float64), np.asarray(p2_cv, dtype=np.float64)
    pose = np.eye(4)
    pose[:3, :3] = rot
    pose[:3, 3] = trans
    view_errors = epipolar_errors(left, right, left_model=left_model, right_model=right_model,
                                  r1=r1, p1=p1, r2=r2, p2=p2)
    squared = np.concatenate([
        (rectified_points(cl, left_model, r1, p1)[:, 1]
         - rectified_points(cr, right_model, r2, p2)[:, 1]) ** 2
        for cl, cr in zip(left, right, strict=True)
    ])
    return StereoResult(
        right_from_left=pose, rms_px=rms, r1=r1, r2=r2, p1=p1, p2=p2,
        epipolar_rms_px=float(np.sqrt(squared.mean())),
        baseline_m=float(np.linalg.norm(trans)),
        baseline_std_m=_baseline_std(points_in_board, left, right, left_model=left_model,
                                     right_model=right_model),
        square_m=_square_size(left, right, left_model=left_model, right_model=right_model,
                              r1=r1, p1=p1, r2=r2, p2=p2, points_in_board=points_in_board,
                              square_m=square_m),
        view_epipolar_px=view_errors, view_ids=active, rejected=rejected,
    )


def _baseline_std(points_in_board: F64, left: list[F64], right: list[F64], *,
                  left_model: CameraModel, right_model: CameraModel,
                  resamples: int = BOOTSTRAP_RESAMPLES) -> float:
    """Standard deviation of the baseline from an m-out-of-n bootstrap of the joint views.

    Each resample of ``m <= BOOTSTRAP_VIEWS`` views re-solves R, T with the intrinsics fixed
    (OpenCV's solver is dense in every view's pose, so small resamples keep this cheap); the
    spread scales to the full ``n`` views as ``sqrt(m / n)``. Seeded, so reproducible.
    """
    rng = np.random.default_rng(0)
    size = (left_model.width, left_model.height)
    objects = points_in_board.astype(np.float32)
    lefts = [c.reshape(-1, 1, 2).astype(np.float32) for c in left]
    rights = [c.reshape(-1, 1, 2).astype(np.float32) for c in right]
    flags = cv2.CALIB_FIX_INTRINSIC
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 1e-10)
    n = len(left)
    m = min(n, BOOTSTRAP_VIEWS)
    baselines = []
    for _ in range(resamples):
        pick = rng.integers(0, n, m)
        out = cv2.stereoCalibrate(
            [objects] * len(pick), [lefts[i] for i in pick], [rights[i] for i in pick],
            left_model.k, left_model.d, right_model.k, right_model.d, size,
            flags=flags, criteria=criteria)
        baselines.append(float(np.linalg.norm(out[6])))
    return float(np.std(baselines, ddof=1) * math.sqrt(m / n))


def _square_size(left: list[F64], right: list[F64], *, left_model: CameraModel,
                 right_model: CameraModel, r1: F64, p1: F64, r2: F64, p2: F64,
                 points_in_board: F64, square_m: float) -> float:
    """Mean distance between neighbouring corners triangulated from the rectified pair.

    Independent of the given square size except through the baseline's scale, so it checks
    that the stereo geometry and the board agree (camera_calibration's chessboard size).
    """
    grid = np.rint(points_in_board[:, :2] / square_m).astype(int)
    cols = int(grid[:, 0].max()) + 1
    distances = []
    for cl, cr in zip(left, right, strict=True):
        xl = rectified_points(cl, left_model, r1, p1)
        xr = rectified_points(cr, right_model, r2, p2)
        points = cv2.triangulatePoints(p1, p2, xl.T, xr.T)
        xyz = (points[:3] / points[3]).T.reshape(-1, cols, 3)
        distances.append(np.linalg.norm(np.diff(xyz, axis=1), axis=2).ravel())
        distances.append(np.linalg.norm(np.diff(xyz, axis=0), axis=2).ravel())
    return float(np.mean(np.concatenate(distances)))

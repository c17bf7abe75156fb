"""Stereo rectification and the rig's figures of merit, from a joint calibration.

Both cameras' intrinsics and the rig transform come out of one least-squares problem
(:mod:`.joint`). Here: rectification (``stereoRectify``, OpenCV's fisheye version for an
equidistant lens) with ``P2[0, 3] = -fx' * B``; the epipolar error of the joint views after
rectification; the board square re-estimated by triangulating them (independent of
``--square`` but for the baseline's scale); and the standard deviations of the baseline and
of the rig rotation from the joint covariance. A circle grid's views enter both figures as the
solver fitted them, at the circles' centres: each camera sees a disc's centroid off its
centre by its own perspective, so the detections themselves would not meet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError
from .holds import Seen
from .joint import JointResult
from .opencv_lens import opencv_lens
from .rig import relative_pose, rotation_std_deg, translation_std_m
from .rotation import support
from .seed import board_pose

#: views whose rig rotation lies within this angle of another's support it
ORIENTATION_AGREEMENT_RAD = math.radians(10.0)


@dataclass
class StereoResult:
    """``right_from_left`` (4, 4): X_right = R X_left + T (metres); rectification ``r1``,
    ``r2`` (3, 3) and ``p1``, ``p2`` (3, 4)."""

    right_from_left: F64
    rms_px: float
    r1: F64
    r2: F64
    p1: F64
    p2: F64
    epipolar_rms_px: float
    baseline_m: float
    baseline_std_m: float
    rotation_std_deg: float  # worst direction
    square_m: float  # square size re-estimated by triangulating the joint views
    view_epipolar_px: list[float]  # per joint view used
    #: joint views used: (left view, right view), the joint calibration's view indices
    pairs: list[tuple[int, int]] = field(default_factory=list)
    #: joint views left out (as numbered in ``pairs``) -> why
    rejected: dict[tuple[int, int], str] = field(default_factory=dict)

    @property
    def rotation_deg(self) -> float:
        """Angle of the rig rotation (degrees)."""
        angle = math.acos(max(-1.0, min(1.0, (np.trace(self.right_from_left[:3, :3]) - 1) / 2)))
        return math.degrees(angle)


def rectify(left: CameraModel, right: CameraModel, right_from_left: F64
            ) -> tuple[F64, F64, F64, F64]:
    """``R1, R2`` (3, 3) and ``P1, P2`` (3, 4) of the rectified pair (only valid pixels)."""
    rotation, translation = right_from_left[:3, :3], right_from_left[:3, 3].reshape(3, 1)
    family, other = opencv_lens(left.distortion_model), opencv_lens(right.distortion_model)
    if other is not family:
        raise ProcessorError(f"rectifying a {family.name} camera with a {other.name} camera "
                             "is not supported")
    try:
        return family.stereo_rectify(left, right, rotation, translation)
    except cv2.error as err:
        raise ProcessorError(f"stereo rectification failed: "
                             f"{str(err).strip().splitlines()[-1]}") from None


@dataclass(frozen=True)
class RectifiedPair:
    """Two cameras and their rectification (:func:`rectify`): rotations ``r1``, ``r2``
    (3, 3) and projections ``p1``, ``p2`` (3, 4)."""

    left_model: CameraModel
    right_model: CameraModel
    r1: F64
    p1: F64
    r2: F64
    p2: F64

    def rectified_px(self, left_px: F64, right_px: F64) -> tuple[F64, F64]:
        """Where the rectified images show observed pixels ``(M, 2)`` of each camera."""
        return (self.left_model.rectify_points(left_px, self.r1, self.p1),
                self.right_model.rectify_points(right_px, self.r2, self.p2))

    def epipolar_errors(self, left: list[F64], right: list[F64]) -> list[float]:
        """Per joint view (pixels ``(M, 2)`` of the same points in each camera), RMS of the
        row difference of the rectified points (px)."""
        return [float(np.sqrt(np.mean((xl[:, 1] - xr[:, 1]) ** 2)))
                for xl, xr in (self.rectified_px(cl, cr)
                               for cl, cr in zip(left, right, strict=True))]


def epipolar_errors(left: list[F64], right: list[F64], *, left_model: CameraModel,
                    right_model: CameraModel, r1: F64, p1: F64, r2: F64, p2: F64) -> list[float]:
    """Per joint view, RMS of the row difference of matching rectified corners (px)."""
    pair = RectifiedPair(left_model, right_model, r1, p1, r2, p2)
    return pair.epipolar_errors(left, right)


def _rotation_of(points: F64, seen: Seen, model: CameraModel) -> F64 | None:
    pose = board_pose(points[seen.point_ids], seen.corners_px, model)
    return None if pose is None else pose[:3, :3]


def turned(seen: Seen, point_count: int) -> Seen:
    """The same corners numbered from the other end of a board turned by 180 degrees."""
    return Seen(np.ascontiguousarray(point_count - 1 - seen.point_ids[::-1]),
                np.ascontiguousarray(seen.corners_px[::-1]))


def _angle_rad(a: F64, b: F64) -> float:
    return math.acos(max(-1.0, min(1.0, (float(np.trace(a @ b.T)) - 1) / 2)))


def orient_right_views(points_in_board: F64, left: list[Seen], right: list[Seen], *,
                       left_model: CameraModel, right_model: CameraModel) -> list[Seen]:
    """The right views numbered from the same board corner as the left ones.

    A chessboard turned by 180 degrees looks the same, so each camera's detection may start
    from either end of it; near the turn where the two choices meet, the two cameras of a
    pair can disagree. The rig's rotation (right from left) is the same in every view: each
    right view is kept or turned (:func:`turned`), whichever gives the rotation that most
    views support.
    """
    count = len(points_in_board)
    candidates = []
    for cl, cr in zip(left, right, strict=True):
        left_from_board = _rotation_of(points_in_board, cl, left_model)
        options = [_rotation_of(points_in_board, c, right_model) for c in (cr, turned(cr, count))]
        if left_from_board is None or options[0] is None or options[1] is None:
            candidates.append([np.eye(3), -np.eye(3)])
            continue
        candidates.append([t @ left_from_board.T for t in options])  # type: ignore[operator]
    if not candidates:
        return []
    flat = [rotation for pair in candidates for rotation in pair]
    consensus = flat[int(np.argmax(support(np.array(flat), ORIENTATION_AGREEMENT_RAD, group=2)))]
    return [cr if _angle_rad(a, consensus) <= _angle_rad(b, consensus) else turned(cr, count)
            for cr, (a, b) in zip(right, candidates, strict=True)]


def stereo_result(joint: JointResult, pairs: list[tuple[int, int]], *,
                  points_in_board: F64, square_m: float, cameras: tuple[int, int] = (0, 1),
                  global_covariance: F64 | None = None) -> StereoResult:
    """Rectification and figures of merit of two cameras (``cameras``: left, right; by
    default 0 and 1) of a joint calibration.

    ``pairs`` are the joint views: the views (indices into the joint calibration's views) of
    the left and right camera at one instant. Only corners that are inliers in both views
    count.
    ``global_covariance``: the joint problem's, when already computed (see
    :func:`.rig.relative_pose`).
    """
    left_model, right_model = joint.models[cameras[0]], joint.models[cameras[1]]
    right_from_left, covariance = relative_pose(joint, *cameras, global_covariance)
    r1, r2, p1, p2 = rectify(left_model, right_model, right_from_left)
    used: list[tuple[int, int]] = []
    rejected: dict[tuple[int, int], str] = {}
    left, right, common = [], [], []
    for lv, rv in pairs:
        lid, rid = joint.views[lv].point_ids, joint.views[rv].point_ids
        if lv in joint.rejected or rv in joint.rejected:
            rejected[lv, rv] = joint.rejected.get(lv) or joint.rejected[rv]
            continue
        if lv in joint.split or rv in joint.split:  # not one instant: no joint view
            rejected[lv, rv] = joint.split.get(rv) or joint.split[lv]
            continue
        ids, li, ri = np.intersect1d(lid, rid, return_indices=True)
        keep = joint.inliers[lv][li] & joint.inliers[rv][ri]
        if keep.sum() < 2:
            continue
        used.append((lv, rv))
        left.append(joint.centres_px(lv)[li[keep]])
        right.append(joint.centres_px(rv)[ri[keep]])
        common.append(ids[keep])
    if not used:
        apart = [why for why in rejected.values() if why.startswith("not simultaneous")]
        if apart:
            which = "every pair" if len(apart) == len(pairs) else \
                f"{len(apart)} pair{'s' if len(apart) > 1 else ''}"
            raise ProcessorError(
                f"no joint stereo view: {which} left the rig as {apart[0]} (the cameras' "
                "stamps are apart from their exposures: measure the offset, --time-offset "
                "auto)")
        raise ProcessorError("no joint stereo view: both cameras must see the board at the "
                             "same time")
    rectified = RectifiedPair(left_model, right_model, r1, p1, r2, p2)
    view_errors = rectified.epipolar_errors(left, right)
    translation = right_from_left[:3, 3]
    baseline = float(np.linalg.norm(translation))
    direction = translation / baseline
    rms = math.sqrt(float(np.mean(np.square(view_errors)))) if view_errors else float("nan")
    rms_px = math.sqrt(np.mean([joint.view_rms_px(v) ** 2 for pair in used for v in pair]))
    return StereoResult(
        right_from_left=right_from_left, rms_px=float(rms_px), r1=r1, r2=r2, p1=p1, p2=p2,
        epipolar_rms_px=rms, baseline_m=baseline,
        baseline_std_m=translation_std_m(covariance, direction),
        rotation_std_deg=rotation_std_deg(covariance),
        square_m=square_size(left, right, common, rectified, points_in_board=points_in_board,
                             square_m=square_m),
        view_epipolar_px=view_errors, pairs=used, rejected=rejected)


def square_size(left: list[F64], right: list[F64], ids: list[np.ndarray],
                rectified: RectifiedPair, *, points_in_board: F64, square_m: float) -> float:
    """The board's spacing from the ``rectified`` pair (views ``(M, 2)`` of the board points
    ``ids`` in each camera, per joint view): mean distance between triangulated
    nearest neighbours on the board, scaled from their distance to ``square_m`` (asymmetric
    circle grids have no neighbours one spacing apart)."""
    layout = np.linalg.norm(points_in_board[:, None, :] - points_in_board[None, :, :], axis=2)
    nearest = float(layout[layout > 0].min())
    distances = []
    for cl, cr, pid in zip(left, right, ids, strict=True):
        xl, xr = rectified.rectified_px(cl, cr)
        homogeneous = cv2.triangulatePoints(rectified.p1, rectified.p2, xl.T, xr.T)
        xyz = (homogeneous[:3] / homogeneous[3]).T
        board = points_in_board[pid]
        gap = np.linalg.norm(board[:, None, :] - board[None, :, :], axis=2)
        a, b = np.nonzero(np.triu(np.abs(gap - nearest) < 1e-6 * nearest))
        distances.append(np.linalg.norm(xyz[a] - xyz[b], axis=1))
    joined = np.concatenate(distances) if distances else np.zeros(0)
    return float(joined.mean()) * square_m / nearest if joined.size else float("nan")

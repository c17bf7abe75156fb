"""Solving: choose views, calibrate each camera, then the stereo pair, from detected corners.

Every step takes the views the detection pass returned and returns a new value; the solvers
themselves live in :mod:`processors.calibration` and know nothing of logs or frames. Their
view ids are positions in the lists they are given; here they are mapped back to frame
indices, which is what every later step (summary, evidence, report) speaks.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from processors.calibration.board import Board
from processors.calibration.selection import Coverage, coverage, select_views, view_parameters
from processors.calibration.solve import (
    OUTLIER_FACTOR,
    OUTLIER_FLOOR_PX,
    CalibrationOptions,
    MonoResult,
    calibrate_mono,
    cross_validate,
)
from processors.calibration.stereo import StereoResult, calibrate_stereo, orient_right_views
from processors.resync import pair_stamps
from replay.camera import CameraModel
from replay.messages import F64, CameraInfo
from replay.records import ScenarioCamera

from ..errors import CalibrationError
from .views import CameraViews, Frame, size_hint

#: most views given to the solver, chosen for coverage
MAX_VIEWS = 150
#: views closer than this in camera_calibration's (X, Y, size, skew) add nothing new
MIN_VIEW_DISTANCE = 0.02

__all__ = ["MAX_VIEWS", "CalibratedCamera", "CameraSolution", "StereoSolution",
           "calibrated_cameras", "solve_camera", "solve_stereo", "stereo_pairs"]


@dataclass(frozen=True)
class CameraSolution:
    """One camera calibrated from its views. ``result``'s view ids are frame indices."""

    views: CameraViews
    candidates: list[int]  # frames whose board passed every check
    selected: list[int]  # frames given to the solver
    result: MonoResult
    coverage: Coverage  # of the used views
    cross_validation_px: float | None

    def used_corners(self) -> list[F64]:
        """Corners ``(N, 2)`` of every used view, in ``result.view_ids`` order."""
        return [self.views.corners(i) for i in self.result.view_ids]

    def rejected_corners(self) -> list[F64]:
        """Corners of every distinct frame whose board was found but not used as a view."""
        return [f.detection.corners_px for f in self.views.distinct()
                if f.detection is not None and self.rejection(f) is not None]

    def rejection(self, frame: Frame) -> str | None:
        """Why a frame's board is not a view (None: it is one, or could have been)."""
        if frame.detection is not None and not frame.detection.accepted:
            return frame.detection.reason
        if frame.reason:
            return frame.reason
        return self.result.rejected.get(frame.index)

    def outlier_limit_px(self) -> float:
        """The per-view RMS above which a view counts as far above the rest."""
        errors = list(self.result.view_rms_px.values())
        return max(OUTLIER_FACTOR * float(np.median(errors)), OUTLIER_FLOOR_PX) \
            if errors else 0.0

    def status(self, frame: Frame) -> tuple[str, bool]:
        """Text drawn on an annotated frame, and whether the view was used."""
        if frame.detection is None:
            return "no board found", False
        why = self.rejection(frame)
        if why is not None:
            return f"rejected: {why}", False
        if frame.index in self.result.view_rms_px:
            return f"used: RMS {self.result.view_rms_px[frame.index]:.3f} px", True
        return "not used: adds no coverage", False


def _by_frame(result: MonoResult, frames: list[int]) -> MonoResult:
    """``result`` with its view ids (positions in ``frames``) replaced by frame indices."""
    at = dict(enumerate(frames))
    return MonoResult(
        model=result.model, rms_px=result.rms_px,
        view_ids=[at[i] for i in result.view_ids],
        view_rms_px={at[i]: e for i, e in result.view_rms_px.items()},
        rejected={at[i]: why for i, why in result.rejected.items()},
        std=result.std,
        camera_from_board={at[i]: p for i, p in result.camera_from_board.items()},
        residuals_px={at[i]: r for i, r in result.residuals_px.items()},
        inliers={at[i]: m for i, m in result.inliers.items()},
        options=result.options, tangential_test=result.tangential_test,
        sigma_px=result.sigma_px, joint=result.joint,
    )


def solve_camera(views: CameraViews, board: Board, options: CalibrationOptions, *,
                 max_views: int = MAX_VIEWS, topic_note: str = "") -> CameraSolution:
    """Select the most informative views and calibrate one camera."""
    found = [f for f in views.distinct() if f.detection is not None]
    topic = views.source.image_topic
    if not found:
        raise CalibrationError(
            f"no {board.cols}x{board.rows} board found in {len(views.frames)} frames of "
            f"{topic}{size_hint(views, board)}{topic_note}")
    candidates = [f.index for f in views.frames if f.candidate]
    if not candidates:
        reasons = sorted({f.reason or f.detection.reason for f in found if f.detection})
        raise CalibrationError(f"{topic}: every board found was rejected "
                               f"({'; '.join(reasons)}){size_hint(views, board)}")
    params = np.array([view_parameters(views.corners(i), board, views.size)
                       for i in candidates])
    chosen = select_views(params, max_views=max_views, min_distance=MIN_VIEW_DISTANCE)
    selected = [candidates[i] for i in chosen]
    solved = calibrate_mono(board.points_in_board(), [views.corners(i) for i in selected],
                            views.size, options)
    result = _by_frame(solved, selected)
    used = [views.corners(i) for i in result.view_ids]
    used_params = np.array([view_parameters(c, board, views.size) for c in used])
    return CameraSolution(
        views, candidates, selected, result, coverage(used_params, used, views.size),
        cross_validate(board.points_in_board(), used, views.size, solved.options))


def stereo_pairs(left: CameraViews, right: CameraViews,
                 approximate_s: float | None) -> list[tuple[int, int]]:
    """(left frame, right frame) indices shot at the same time (or within the slop)."""
    left_ns = np.array([f.stamp_ns for f in left.frames], dtype=np.int64)
    right_ns = np.array([f.stamp_ns for f in right.frames], dtype=np.int64)
    if approximate_s is None:
        _common, li, ri = np.intersect1d(left_ns, right_ns, return_indices=True)
        pairs = list(zip(li.tolist(), ri.tolist(), strict=True))
    else:
        pairing = pair_stamps(np.sort(left_ns), np.sort(right_ns),
                              slop_ns=round(approximate_s * 1e9))
        order_l, order_r = np.argsort(left_ns), np.argsort(right_ns)
        pairs = [(int(order_l[a]), int(order_r[b]))
                 for a, b in zip(pairing.left_index, pairing.right_index, strict=True)]
    if not pairs:
        gap = np.min(np.abs(left_ns[:, None] - right_ns[None, :])) / 1e6 \
            if len(left_ns) * len(right_ns) <= 4_000_000 else float("nan")
        how = "within the slop" if approximate_s is not None else "with identical stamps"
        raise CalibrationError(
            f"{left.source.image_topic} and {right.source.image_topic} never pair {how} "
            f"(closest stamps {gap:.3f} ms apart); use --approximate SEC or resync the log"
        )
    return pairs


@dataclass(frozen=True)
class StereoSolution:
    """The stereo solve and the joint views (left frame, right frame) it used or left out."""

    result: StereoResult
    pairs: list[tuple[int, int]]
    rejected: list[tuple[tuple[int, int], str]]


def solve_stereo(left: CameraSolution, right: CameraSolution, board: Board, *,
                 approximate_s: float | None, max_views: int = MAX_VIEWS) -> StereoSolution:
    """Calibrate the rig from the joint views, each camera's intrinsics held fixed."""
    lv, rv = left.views, right.views
    joint = [(li, ri) for li, ri in stereo_pairs(lv, rv, approximate_s)
             if _usable(lv.frames[li]) and _usable(rv.frames[ri])
             and not (lv.frames[li].duplicate and rv.frames[ri].duplicate)]
    params = np.array([view_parameters(lv.corners(li), board, lv.size) for li, _ in joint]) \
        if joint else np.zeros((0, 4))
    chosen = [joint[i] for i in select_views(params, max_views=max_views,
                                             min_distance=MIN_VIEW_DISTANCE)]
    left_views = [lv.corners(li) for li, _ in chosen]
    right_views = orient_right_views(
        board.points_in_board(), left_views, [rv.corners(ri) for _, ri in chosen],
        left_model=left.result.model, right_model=right.result.model)
    result = calibrate_stereo(board.points_in_board(), left_views, right_views,
                              left_model=left.result.model, right_model=right.result.model,
                              square_m=board.square_m)
    return StereoSolution(result, [chosen[i] for i in result.view_ids],
                          [(chosen[i], why) for i, why in sorted(result.rejected.items())])


def _usable(frame: Frame) -> bool:
    """A frame whose board passed every check (a repeated frame counts: held still)."""
    return frame.detection is not None and frame.detection.accepted and not frame.reason


@dataclass(frozen=True)
class CalibratedCamera:
    """A solved camera with the model to publish and, in simulated logs, its truth."""

    solution: CameraSolution
    camera_info: CameraInfo
    truth: ScenarioCamera | None

    @property
    def views(self) -> CameraViews:
        """The camera's views."""
        return self.solution.views


def mono_camera_info(model: CameraModel, frame_id: str) -> CameraInfo:
    """Calibrated CameraInfo; P is camera_calibration's (alpha 0: only valid pixels)."""
    size = (model.width, model.height)
    new_k, _roi = cv2.getOptimalNewCameraMatrix(model.k, model.d, size, 0.0)
    p = np.zeros((3, 4))
    p[:, :3] = new_k
    return CameraInfo(0, frame_id, model.width, model.height, model.distortion_model,
                      model.d, model.k, np.eye(3), p)


def calibrated_cameras(solutions: list[CameraSolution], stereo: StereoSolution | None,
                       truth: list[ScenarioCamera | None]) -> list[CalibratedCamera]:
    """Each camera's calibrated model: mono with camera_calibration's P; stereo with the
    rectification (R, P) of the rig."""
    out = []
    for index, (solution, camera_truth) in enumerate(zip(solutions, truth, strict=True)):
        m, frame_id = solution.result.model, solution.views.frame_id
        if stereo is None:
            info = mono_camera_info(m, frame_id)
        else:
            r, p = (stereo.result.r1, stereo.result.p1) if index == 0 else \
                (stereo.result.r2, stereo.result.p2)
            info = CameraInfo(0, frame_id, m.width, m.height, m.distortion_model, m.d, m.k,
                              r, p)
        out.append(CalibratedCamera(solution, info, camera_truth))
    return out

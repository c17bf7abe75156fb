"""Each camera's time offset against the rig's first camera, measured from the board's motion.

Drivers stamp late, by different amounts per camera: the frames of two cameras stamped as one
instant may have been exposed apart, and a moving board is at another pose in each. Before
the joint solve each camera's offset to camera 0 is measured from the board both see
(:func:`processors.time_offset.estimate_board_offset`: each camera's board posed through a
first calibration of its own views, the rig solved with the offset); a camera whose offset
is measured and not negligible joins camera 0's frames by time (:mod:`.instants`). After the
solve the offset is measured again through the solved cameras and rig, and the solve is
repeated with it when it moved. A held board, snapshots (frames far apart) or cameras that
never see the board together do not show the offset: the cameras then pair by their stamps,
and pairs that are not simultaneous leave the rig (:mod:`processors.calibration.robust`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from processors.calibration.board import Board
from processors.calibration.options import CalibrationOptions
from processors.calibration.seed import seed_model
from processors.time_offset import (
    BoardTrack,
    NotObservableError,
    OffsetEstimate,
    estimate_board_offset,
)
from processors.time_offset.board import MIN_MOVING_FRAMES
from replay.camera import CameraModel
from replay.messages import F64
from replay.records import Scenario, TimeOffset

from .views import SNAPSHOT_GAP_S, CameraViews

__all__ = ["APPLY_SIGMAS", "MIN_APPLIED_MS", "CameraOffset", "board_track",
           "first_calibrations", "measure_offsets", "offset_record", "true_offset_ms"]

#: an offset is applied when it is at least this many sigmas and this many ms from zero
APPLY_SIGMAS = 3.0
MIN_APPLIED_MS = 0.05


@dataclass(frozen=True)
class CameraOffset:
    """Camera ``camera``'s time offset against camera 0: the estimate (None: the log does
    not show it, ``why_not`` says why) and whether its views were paired by it."""

    camera: int
    measured: OffsetEstimate | None
    why_not: str = ""

    @property
    def applied(self) -> bool:
        """Whether the offset is large enough to pair the views by it."""
        m = self.measured
        return m is not None and abs(m.offset_s) >= max(APPLY_SIGMAS * m.std_s,
                                                        MIN_APPLIED_MS / 1000)

    @property
    def offset_ns(self) -> int | None:
        """The offset the views are paired by (ns; None: by their stamps)."""
        return round(self.measured.offset_s * 1e9) if self.measured is not None \
            and self.applied else None

    def moved_from(self, before: CameraOffset) -> bool:
        """Whether this estimate pairs the views otherwise than ``before`` did: applied or not
        where it was, or moved by more than its sigma (and :data:`MIN_APPLIED_MS`)."""
        if self.applied != before.applied:
            return True
        if self.measured is None or before.measured is None or not self.applied:
            return False
        return abs(self.measured.offset_s - before.measured.offset_s) > max(
            self.measured.std_s, MIN_APPLIED_MS / 1000)

    def describe(self) -> str:
        """One line: the offset and what was done with it, or why it was not measured."""
        if self.measured is None:
            return f"not observable: {self.why_not}"
        use = "views paired by it" if self.applied else "negligible: views paired by stamp"
        return f"{self.measured.describe()}; {use}"


def offset_record(estimate: OffsetEstimate, first: str, second: str) -> TimeOffset:
    """The record of an estimate between cameras ``first`` and ``second`` (namespaces)."""
    return TimeOffset(first=first, second=second, offset_ms=estimate.offset_ms,
                      std_ms=estimate.std_ms, frames=estimate.frames,
                      frames_fitted=estimate.frames_fitted, rms_px=estimate.rms_px,
                      method=estimate.method, second_from_first=estimate.second_from_first)


def board_track(views: CameraViews, model: CameraModel) -> BoardTrack:
    """A camera's board over time (its distinct frames whose board passed every check), seen
    through ``model``."""
    frames = [f for f in views.frames if f.candidate and f.detection is not None]
    detections = [f.detection for f in frames if f.detection is not None]
    return BoardTrack(np.array([f.stamp_ns for f in frames], dtype=np.int64),
                      [d.ids for d in detections], [d.corners_px for d in detections], model)


def first_calibrations(cameras: list[CameraViews], board: Board,
                       options: CalibrationOptions) -> list[CameraModel]:
    """A first calibration of each camera from its own views (OpenCV's, on a sample)."""
    points = board.points_in_board()
    out = []
    for views in cameras:
        detections = [f.detection for f in views.frames
                      if f.candidate and f.detection is not None]
        out.append(seed_model([points[d.ids] for d in detections if d is not None],
                              [d.corners_px for d in detections if d is not None],
                              views.size, options))
    return out


def _boards(views: CameraViews) -> int:
    """How many of a camera's distinct frames hold a board that passed every check."""
    return sum(f.candidate and f.detection is not None for f in views.frames)


def _snapshots(views: CameraViews) -> bool:
    """Whether a camera's frames are snapshots: most of them further apart than
    :data:`~.views.SNAPSHOT_GAP_S`."""
    stamps = np.sort([f.stamp_ns for f in views.frames if not f.duplicate])
    return len(stamps) < 2 or float(np.median(np.diff(stamps))) >= SNAPSHOT_GAP_S * 1e9


def measure_offsets(cameras: list[CameraViews], board: Board, options: CalibrationOptions, *,
                    models: list[CameraModel] | None = None,
                    rig: list[F64] | None = None) -> list[CameraOffset]:
    """Every camera's offset against camera 0 (cameras 1..N-1, in order), from the board seen
    through ``models`` (default: a first calibration of each camera's own views) with
    ``rig`` (each camera's ``camera_from_reference``; default: solved with the offset)."""
    if len(cameras) < 2:
        return []
    if any(_snapshots(c) for c in cameras):
        return [CameraOffset(c, None, "the frames are snapshots, too far apart for the "
                                      "board's motion between them to be seen")
                for c in range(1, len(cameras))]
    if min(_boards(c) for c in cameras) < MIN_MOVING_FRAMES:  # the solve says why
        few = f"a camera's board passed its checks in fewer than {MIN_MOVING_FRAMES} frames"
        return [CameraOffset(c, None, few) for c in range(1, len(cameras))]
    seen = models or first_calibrations(cameras, board, options)
    reference = board_track(cameras[0], seen[0])
    out = []
    for camera in range(1, len(cameras)):
        try:
            out.append(CameraOffset(camera, estimate_board_offset(
                reference, board_track(cameras[camera], seen[camera]),
                points_in_board=board.points_in_board(), half_turn=board.symmetric,
                second_from_first=None if rig is None else rig[camera])))
        except NotObservableError as err:
            out.append(CameraOffset(camera, None, str(err)))
    return out


def true_offset_ms(scenario: Scenario | None, cameras: list[CameraViews], camera: int
                   ) -> float | None:
    """The simulator's offset of a camera against camera 0 (ms): the difference of their
    latencies; None outside the simulator."""
    if scenario is None:
        return None
    truths = [scenario.camera_for(c.source.namespace, c.log_info.frame_id if c.log_info
                                  else None) for c in (cameras[0], cameras[camera])]
    if truths[0] is None or truths[1] is None:
        return None
    return (scenario.latency_ns(truths[1]) - scenario.latency_ns(truths[0])) / 1e6

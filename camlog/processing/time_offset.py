"""Measure the offset between two cameras' stamps in a log, from what they saw.

With a board in view (``--size``/``--square``) the board is detected in every frame of both
cameras (the calibration's detection pass) and the offset fitted to its motion
(:func:`processors.time_offset.estimate_board_offset`): each camera's board posed through
its camera_info (or, uncalibrated, a calibration of its own views), the rig solved with the
offset. Without one, features of the calibrated pair (its camera_info, or ``--calibration``)
matched from each right frame into the left frames around it are fitted instead
(:func:`processors.time_offset.estimate_feature_offset`); that needs a moving rig.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from processors.calibration.board import Board
from processors.calibration.options import CalibrationOptions
from processors.drift import StereoMatcher
from processors.time_offset import (
    BoardTrack,
    estimate_board_offset,
)
from processors.time_offset.features import (
    STENCIL,
    FeaturePair,
    estimate_feature_offset,
    track_rows,
)
from replay.calibration_yaml import load_calibration
from replay.camera import CameraModel
from replay.formats import LogReader
from replay.messages import CameraInfo
from replay.progress import progress_bar
from replay.records import TimeOffset

from ..calibrate.offsets import board_track, first_calibrations, offset_record
from ..calibrate.pixels import TopicFrames
from ..calibrate.views import CameraViews, detect_views
from ..errors import InputError
from .cameras import CameraSource, first_camera_info

__all__ = ["measure_offset"]

#: a stencil's gaps may vary by this factor (a larger one spans a dropped frame)
GAP_FACTOR = 1.5


def measure_offset(reader: LogReader, left: CameraSource, right: CameraSource, *,
                   board: Board | None, calibration: Path | None, max_offset_s: float,
                   workers: int, progress: bool | None) -> TimeOffset:
    """How much later ``right`` stamps an instant than ``left`` (see the module's text)."""
    if board is not None:
        found = detect_views(reader, [left, right], board, workers=workers, progress=progress)
        tracks = [_track(views, board) for views in found.cameras]
        estimate = estimate_board_offset(*tracks, points_in_board=board.points_in_board(),
                                         half_turn=board.symmetric, search_s=max_offset_s)
    else:
        infos = _calibration(reader, left, right, calibration)
        estimate = estimate_feature_offset(
            list(_feature_pairs(reader, left, right, infos, progress=progress)),
            p_rect=infos[1].p)
    return offset_record(estimate, left.namespace, right.namespace)


def _track(views: CameraViews, board: Board) -> BoardTrack:
    """A camera's board over time, posed through its camera_info, or a calibration of its
    own views when the log has none."""
    frames = [f for f in views.frames if f.candidate and f.detection is not None]
    if not frames:
        raise InputError(f"no {board.cols}x{board.rows} board found in "
                         f"{views.source.image_topic}")
    info = views.log_info
    if info is not None and info.k[0, 0] > 0 and (info.width, info.height) == views.size:
        return board_track(views, CameraModel.from_camera_info(info))
    (model,) = first_calibrations([views], board, CalibrationOptions())
    return board_track(views, model)


def _calibration(reader: LogReader, left: CameraSource, right: CameraSource,
                 calibration: Path | None) -> tuple[CameraInfo, CameraInfo]:
    """The pair's calibration: ``--calibration``'s left.yaml and right.yaml, or the log's
    first camera_info of each camera, which must describe a rectified pair."""
    if calibration is not None:
        files = [calibration / "left.yaml", calibration / "right.yaml"] \
            if calibration.is_dir() else []
        if not files or not all(f.is_file() for f in files):
            raise InputError(f"{calibration}: not a calibration folder with left.yaml and "
                             "right.yaml")
        left_info, right_info = (load_calibration(f).camera_info for f in files)
    else:
        found = [first_camera_info(reader, s) for s in (left, right)]
        if found[0] is None or found[1] is None:
            raise InputError(f"{reader.path}: natural features need the pair's calibration: "
                             "no camera_info for "
                             f"{(left if found[0] is None else right).namespace} (give "
                             "--calibration, or a board with --size and --square)")
        left_info, right_info = found[0], found[1]
    if not right_info.p[0, 3] or not np.any(left_info.p[:, :3]):
        raise InputError(f"{calibration or reader.path}: the cameras' calibration is not a "
                         "rectified stereo pair (the right camera's P has no baseline): give "
                         "--calibration, or a board with --size and --square")
    return left_info, right_info


@dataclass
class _Frame:
    stamp_ns: int
    gray: np.ndarray


def _feature_pairs(reader: LogReader, left: CameraSource, right: CameraSource,
                   infos: tuple[CameraInfo, CameraInfo], *,
                   progress: bool | None) -> Iterator[FeaturePair]:
    """Every right frame's features matched into the left frame nearest its stamp and
    tracked through the :data:`STENCIL` left frames around it (one pass over the log,
    holding a few frames of each camera)."""
    matcher = StereoMatcher(*infos)
    left_model, right_model = matcher.left_model, matcher.right_model
    frames = TopicFrames()
    recent: list[_Frame] = []  # left frames, in stamp order
    waiting: list[_Frame] = []  # right frames until the left frames after them arrive
    origin: int | None = None
    total = sum(reader.topics[s.image_topic].count for s in (left, right))
    with progress_bar(total=total, unit="frame", desc="features", progress=progress) as bar:
        for raw in reader.raw_messages([left.image_topic, right.image_topic]):
            bar.update()
            frame = frames(reader, raw)
            if frame is None:
                continue
            origin = frame.stamp_ns if origin is None else origin
            seen = _Frame(frame.stamp_ns, frame.mono8())
            if raw.topic == right.image_topic:
                waiting.append(seen)
                continue
            recent.append(seen)
            recent.sort(key=lambda f: f.stamp_ns)
            still: list[_Frame] = []
            for pending in waiting:
                centre = int(np.argmin([abs(f.stamp_ns - pending.stamp_ns) for f in recent]))
                if centre + STENCIL // 2 >= len(recent):
                    still.append(pending)  # the left frames after it are still to come
                    continue
                if centre >= STENCIL // 2:
                    stencil = recent[centre - STENCIL // 2:centre + STENCIL // 2 + 1]
                    pair = _pair(matcher, stencil, pending, origin=origin,
                                 models=(left_model, right_model), infos=infos)
                    if pair is not None:
                        yield pair
            waiting = still
            del recent[:max(0, len(recent) - 3 * STENCIL)]


def _pair(matcher: StereoMatcher, stencil: list[_Frame], right: _Frame, *, origin: int,
          models: tuple[CameraModel, CameraModel],
          infos: tuple[CameraInfo, CameraInfo]) -> FeaturePair | None:
    """One right frame's :class:`FeaturePair` (None: the stencil spans a dropped frame)."""
    stamps = np.array([f.stamp_ns for f in stencil], dtype=np.int64)
    gaps = np.diff(stamps)
    if gaps.min() <= 0 or gaps.max() > GAP_FACTOR * float(np.median(gaps)):
        return None
    centre = STENCIL // 2
    raw_left, raw_right = matcher.match_raw(stencil[centre].gray, right.gray)
    tracked, kept = track_rows([f.gray for f in stencil], centre, raw_left)
    tracked, raw_right = tracked[kept], raw_right[kept]
    left_info, right_info = infos
    rows = np.column_stack([
        models[0].rectify_points(tracked[:, k], left_info.r, left_info.p)[:, 1]
        if len(tracked) else np.zeros(0) for k in range(STENCIL)])
    right_px = models[1].rectify_points(raw_right, right_info.r, right_info.p) \
        if len(raw_right) else np.zeros((0, 2))
    good = np.all(np.isfinite(rows), axis=1) & np.all(np.isfinite(right_px), axis=1)
    return FeaturePair(np.asarray((stamps - origin) * 1e-9, dtype=np.float64), rows[good],
                       (right.stamp_ns - origin) * 1e-9, right_px[good])

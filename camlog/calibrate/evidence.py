"""The annotated log ``calibration.mcap``: the input log plus what the calibration saw.

This is the second pass over the log, and it cannot be folded into the first: a frame's
annotation (used, and with which error, or rejected, and why) is known only once every
camera is solved, and keeping the images until then would make memory grow with the log.
The pass copies every input message, and adds per camera frame the calibrated camera_info,
the frame with its corners drawn, the view's error and residuals and, for stereo, the
rectified image. It also hands back the rectified images of one joint view for the report.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from camlog.calibrate.figures import annotate_detection
from processors.calibration.board import Board
from replay.camera import rectify_maps
from replay.formats import LogReader, LogWriter
from replay.formats.background import BackgroundWriter
from replay.frames import encode_image
from replay.messages import CameraInfo, Image, PointStamped
from replay.progress import progress_bar
from replay.records import CalibrationSummary, ViewResiduals
from replay.topics import CALIBRATION_SUMMARY, CameraTopics

from .pixels import TopicFrames
from .solving import RigSolution
from .views import DetectedFrame

__all__ = ["EVIDENCE_ZSTD_LEVEL", "Evidence", "write_evidence", "write_summary"]

#: zstd level of calibration.mcap's chunks: camera frames are noise that compresses little,
#: and the default level 3 was most of the writer thread's work (the 12-pair 640x480
#: sample's 66 MB: 49 MB in 0.33 s of CPU at level 3, 57 MB in 0.09 s at level 1)
EVIDENCE_ZSTD_LEVEL = 1


@dataclass(frozen=True)
class Evidence:
    """What the pass hands back: the rectified BGR images of the joint view shown in the
    report (stereo only)."""

    rectified_pair: tuple[np.ndarray, np.ndarray] | None


def _rectify_maps(info: CameraInfo) -> tuple[np.ndarray, np.ndarray]:
    return rectify_maps(info, cv2.CV_16SC2)


def hold_ends(frames: Sequence[DetectedFrame], view_of: Mapping[int, int]) -> dict[int, int]:
    """Per view (``view_of``: frame index -> view), the stamp of the last frame it covers:
    the frames of its held pose and their byte-for-byte repeats."""
    ends: dict[int, int] = {}
    current: int | None = None
    for frame in frames:
        if not frame.duplicate:
            current = view_of.get(frame.index)
        if current is not None:
            ends[current] = frame.stamp_ns
    return ends


def write_evidence(reader: LogReader, writer: LogWriter | BackgroundWriter,
                   solved: RigSolution, *, board: Board, progress: bool | None) -> Evidence:
    """Write into ``writer`` the log of ``reader`` plus the calibration's annotated topics
    (a :class:`~replay.formats.background.BackgroundWriter` compresses and writes them while
    this pass draws the next frames)."""
    cameras, stereo, joint = solved.cameras, solved.stereo, solved.joint
    by_topic = {c.views.source.image_topic: c for c in cameras}
    counters = dict.fromkeys(by_topic, 0)
    ends = {c.views.source.namespace: hold_ends(c.views.frames, c.view_of) for c in cameras}
    maps = {c.views.source.namespace: _rectify_maps(c.camera_info) for c in cameras} \
        if stereo is not None else {}
    # frames of the joint views (their first), per camera, and the one the report shows
    pairs = [(solved.first_frame(lv), solved.first_frame(rv)) for lv, rv in stereo.pairs] \
        if stereo is not None else []
    rectified_frames = {cameras[0].views.source.namespace: {li for li, _ in pairs},
                        cameras[-1].views.source.namespace: {ri for _, ri in pairs}} \
        if stereo is not None else {}
    shown = pairs[len(pairs) // 2] if pairs else None
    rectified_shown: dict[int, np.ndarray] = {}
    bar = progress_bar(total=reader.message_count, unit="msg", desc="write",
                       progress=progress)
    to_frame = TopicFrames()
    with bar:
        for raw in reader.raw_messages():
            writer.write_raw(raw)
            bar.update()
            camera = by_topic.get(raw.topic)
            if camera is None:
                continue
            image = to_frame(reader, raw)
            if image is None:  # no frame in the views either (see TopicFrames)
                continue
            frame = camera.views.frames[counters[raw.topic]]
            counters[raw.topic] += 1
            ns, stamp, log_time = camera.views.source.namespace, image.stamp_ns, raw.log_time_ns
            topics = CameraTopics(ns)
            info = camera.camera_info
            writer.write(topics.calibrated_info, CameraInfo(
                stamp, image.frame_id, info.width, info.height, info.distortion_model,
                info.d, info.k, info.r, info.p), log_time_ns=log_time)
            # a joint view's frame may repeat the previous one on one side: rectify it anyway
            if frame.index in rectified_frames.get(ns, ()):
                rectified = image.with_pixels(cv2.remap(image.pixels, *maps[ns],
                                                        cv2.INTER_LINEAR))
                writer.write(topics.image_rect, encode_image(rectified), log_time_ns=log_time)
                side = 0 if camera is cameras[0] else 1
                if shown is not None and frame.index == shown[side]:
                    rectified_shown[side] = rectified.bgr8()
            # a held pose is one view: its first frame carries the annotation
            view = camera.view_of.get(frame.index)
            if frame.duplicate or (view is not None and solved.first_frame(view) != frame.index):
                continue
            status, used = solved.status(camera, frame)
            corners = frame.detection.corners_px if frame.detection is not None else None
            annotated = cv2.cvtColor(
                annotate_detection(image.bgr8(), corners, board.pattern_size, status, used),
                cv2.COLOR_BGR2RGB)
            writer.write(topics.detections, Image(stamp, image.frame_id, "rgb8", annotated),
                         log_time_ns=log_time)
            # a held pose's view is recorded at its first frame
            if used and corners is not None and view is not None:
                rms = joint.view_rms_px(view)
                writer.write(topics.view_error, PointStamped(
                    stamp, image.frame_id, np.array([rms, 0.0, 0.0], dtype=np.float64)),
                    log_time_ns=log_time)
                outliers = np.flatnonzero(~joint.inliers[view]).tolist()
                writer.write(topics.residuals, ViewResiduals(
                    stamp, image.frame_id, rms, np.round(corners, 4),
                    np.round(joint.residuals_px[view], 5), outliers,
                    until_ns=ends[ns].get(view)).to_message(),
                    log_time_ns=log_time)
    pair = (rectified_shown[0], rectified_shown[1]) if len(rectified_shown) == 2 else None
    return Evidence(pair)


def write_summary(writer: LogWriter | BackgroundWriter, summary: CalibrationSummary, *,
                  log_time_ns: int) -> None:
    """The calibration summary, at the end of the log (``log_time_ns``: its last time)."""
    writer.write(CALIBRATION_SUMMARY, summary.to_message(indent=1), log_time_ns=log_time_ns)

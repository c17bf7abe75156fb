"""Calibrate cameras from a log: detect, select, solve, and write the evidence.

Pass 1 streams the camera images, skips frames identical to the previous one (a board held
still), and detects the board on a thread pool (OpenCV releases the GIL); only corners are
kept, so memory does not grow with image count. The solvers in
:mod:`processors.calibration` run on those corners. Pass 2 copies the log into
``calibration.mcap`` and adds the annotated frames, residuals, calibrated camera_info and,
for stereo, rectified images. Every output is staged and moved into place only when all of
it succeeded.
"""

from __future__ import annotations

import json
import os
import time
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from tqdm import tqdm

from processors.calibration.board import Board
from processors.calibration.detect import Detection, find_chessboard
from processors.calibration.selection import Coverage, coverage, select_views, view_parameters
from processors.calibration.solve import (
    OUTLIER_FACTOR,
    OUTLIER_FLOOR_PX,
    CalibrationOptions,
    MonoResult,
    calibrate_mono,
    cross_validate,
    max_projection_difference,
)
from processors.calibration.stereo import StereoResult, calibrate_stereo, orient_right_views
from processors.errors import InputError
from processors.resync import pair_stamps
from replay.atomic import AtomicFolder
from replay.camera import CameraModel
from replay.codec import decode_compressed, to_bgr_or_mono, to_mono8
from replay.errors import ReplayError
from replay.formats import LogReader, open_reader, open_writer
from replay.messages import CameraInfo, CompressedImage, Image, PointStamped, Text

#: mean absolute difference (8-bit levels) of 80x60 thumbnails below which a frame repeats
#: the previous one; sensor noise averages out over the 64 pixels of a thumbnail cell
DUPLICATE_LEVELS = 1.0
MAX_VIEWS = 150
MIN_VIEW_DISTANCE = 0.02
HINT_SAMPLES = 12
SCENARIO_TOPIC = "/camlog/scenario"


@dataclass
class Frame:
    """One image of one camera, as pass 1 saw it."""

    index: int
    stamp_ns: int
    duplicate: bool  # same picture as the previous frame: shares its detection
    detection: Detection | None = None
    reason: str = ""  # why a found board is not a candidate view (beyond the detection's own)

    @property
    def candidate(self) -> bool:
        """A distinct frame whose board passed every check."""
        return (not self.duplicate and self.detection is not None and self.detection.accepted
                and not self.reason)


@dataclass
class CameraStream:
    namespace: str
    image_topic: str
    info_topic: str | None
    frames: list[Frame] = field(default_factory=list)
    size: tuple[int, int] | None = None
    log_info: CameraInfo | None = None
    samples: list[np.ndarray] = field(default_factory=list)  # a few frames for size hints
    result: MonoResult | None = None
    candidates: list[int] = field(default_factory=list)  # frame indices of candidate views
    selected: list[int] = field(default_factory=list)  # frame indices given to the solver
    coverage: Coverage | None = None
    cross_validation_px: float | None = None
    camera_info: CameraInfo | None = None  # the calibrated model to publish
    truth: dict[str, Any] | None = None

    @property
    def name(self) -> str:
        return self.namespace.strip("/").replace("/", "_") or "camera"


@dataclass
class CalibrationRun:
    """Everything :func:`calibrate_log` computed and where it wrote it."""

    cameras: list[CameraStream]
    stereo: StereoResult | None
    stereo_pairs: list[tuple[int, int]]  # (left frame, right frame) used for stereo
    output_dir: Path
    files: list[Path]
    wall_s: float
    summary: dict[str, Any]


def resolve_camera(reader: LogReader, namespace: str) -> CameraStream:
    """The image and camera_info topics of a camera namespace."""
    ns = namespace.rstrip("/") or "/"
    for topic in (f"{ns}/image_raw", f"{ns}/image_raw/compressed", f"{ns}/image_rect",
                  f"{ns}/image"):
        info = reader.topics.get(topic)
        if info is not None and info.count > 0:
            break
    else:
        images = sorted(t for t, i in reader.topics.items()
                        if i.msgtype.endswith(("/Image", "/CompressedImage")) and i.count)
        raise InputError(
            f"{reader.path}: no images under camera {ns} (expected {ns}/image_raw or "
            f"{ns}/image_raw/compressed; image topics: {', '.join(images) or 'none'})"
        )
    info_topic = f"{ns}/camera_info"
    has_info = info_topic in reader.topics and reader.topics[info_topic].count > 0
    return CameraStream(ns, topic, info_topic if has_info else None)


# --- pass 1: detections ----------------------------------------------------------------

def _thumbnail(gray: np.ndarray) -> np.ndarray:
    return cv2.resize(gray, (80, 60), interpolation=cv2.INTER_AREA).astype(np.int16)


def detect_views(reader: LogReader, cameras: list[CameraStream], board: Board, *,
                 workers: int, progress: bool | None) -> None:
    """Fill every camera's frames with detections (pass 1)."""
    by_image = {c.image_topic: c for c in cameras}
    by_info = {c.info_topic: c for c in cameras if c.info_topic}
    previous: dict[str, np.ndarray] = {}
    pending: deque[tuple[Frame, Future[Detection | None]]] = deque()
    total = sum(reader.topics[c.image_topic].count for c in cameras)
    stride = {c.namespace: max(1, reader.topics[c.image_topic].count // HINT_SAMPLES)
              for c in cameras}
    bar = tqdm(total=total, unit="frame", desc="detect", disable=None if progress is None
               else not progress, leave=False)
    with ThreadPoolExecutor(max_workers=workers) as pool:
        try:
            for raw in reader.raw_messages(list(by_image) + list(by_info)):
                message = reader.decode(raw)
                if raw.topic in by_info:
                    camera = by_info[raw.topic]
                    if camera.log_info is None and isinstance(message, CameraInfo):
                        camera.log_info = message
                    continue
                camera = by_image[raw.topic]
                image = _as_image(message, reader, raw.topic)
                gray = to_mono8(image)
                size = (gray.shape[1], gray.shape[0])
                if camera.size is None:
                    camera.size = size
                elif camera.size != size:
                    raise InputError(f"{reader.path}: {raw.topic} changes image size from "
                                     f"{camera.size[0]}x{camera.size[1]} to {size[0]}x{size[1]}")
                thumb = _thumbnail(gray)
                last = previous.get(camera.namespace)
                duplicate = last is not None and float(np.abs(thumb - last).mean()) < \
                    DUPLICATE_LEVELS
                previous[camera.namespace] = thumb
                frame = Frame(len(camera.frames), image.stamp_ns, duplicate)
                camera.frames.append(frame)
                if frame.index % stride[camera.namespace] == 0 and \
                        len(camera.samples) < HINT_SAMPLES:
                    camera.samples.append(gray)
                if not duplicate:
                    pending.append((frame, pool.submit(find_chessboard, gray, board)))
                while len(pending) > 2 * workers + 2:
                    done, future = pending.popleft()
                    done.detection = future.result()
                bar.update()
            while pending:
                done, future = pending.popleft()
                done.detection = future.result()
        finally:
            bar.close()
    for camera in cameras:
        _share_detections(camera)


def _as_image(message: object, reader: LogReader, topic: str) -> Image:
    if isinstance(message, CompressedImage):
        try:
            return decode_compressed(message)
        except ReplayError as err:
            raise InputError(f"{reader.path}: {topic}: {err}") from None
    if not isinstance(message, Image):
        raise InputError(f"{reader.path}: {topic} does not hold images")
    return message


def _share_detections(camera: CameraStream) -> None:
    """Duplicate frames show the board of the frame they repeat."""
    last: Detection | None = None
    for frame in camera.frames:
        if frame.duplicate:
            frame.detection = last
        else:
            last = frame.detection


def apply_speed_limit(camera: CameraStream, max_speed_px: float) -> None:
    """Reject views whose board moved more than ``max_speed_px`` per frame.

    A view's speed is its corners' mean displacement to the nearer of its neighbouring
    frames (zero when the next frame repeats it: the board was held still).
    """
    frames = camera.frames
    for i, frame in enumerate(frames):
        if frame.duplicate or frame.detection is None or not frame.detection.accepted:
            continue
        speeds = []
        for j in (i - 1, i + 1):
            if 0 <= j < len(frames):
                other = frames[j]
                if j == i + 1 and other.duplicate:
                    speeds.append(0.0)
                elif other.detection is not None:
                    delta = other.detection.corners_px - frame.detection.corners_px
                    speeds.append(float(np.linalg.norm(delta, axis=1).mean()))
        speed = min(speeds) if speeds else float("inf")
        if speed > max_speed_px:
            frame.reason = f"board moving {speed:.2f} px/frame > {max_speed_px:g}"


def size_hint(camera: CameraStream, board: Board) -> str:
    """A hint when another inner-corner count would have matched the frames."""
    c, r = board.cols, board.rows
    for cols, rows in ((r, c), (c + 1, r), (c, r + 1), (c + 1, r + 1), (c - 1, r), (c, r - 1),
                       (c - 1, r - 1)):
        if cols < 2 or rows < 2 or (cols, rows) == (c, r):
            continue
        other = Board(cols, rows, board.square_m)
        for gray in camera.samples:
            found = find_chessboard(gray, other)
            if found is not None and found.accepted:
                return (f"; the frames show a {cols}x{rows} board: --size counts inner "
                        "corners (squares minus one) per row x per column")
    return ""


# --- solving -----------------------------------------------------------------------------

def solve_camera(camera: CameraStream, board: Board, options: CalibrationOptions, *,
                 max_views: int, topic_note: str) -> None:
    """Select views and calibrate one camera."""
    if camera.size is None:
        raise InputError(f"no images on {camera.image_topic}")
    found = [f for f in camera.frames if not f.duplicate and f.detection is not None]
    if not found:
        raise InputError(
            f"no {board.cols}x{board.rows} board found in {len(camera.frames)} frames of "
            f"{camera.image_topic}{size_hint(camera, board)}{topic_note}"
        )
    camera.candidates = [f.index for f in camera.frames if f.candidate]
    corners = [camera.frames[i].detection.corners_px for i in camera.candidates]  # type: ignore[union-attr]
    if not corners:
        reasons = sorted({f.reason or f.detection.reason for f in found if f.detection})
        raise InputError(f"{camera.image_topic}: every board found was rejected "
                         f"({'; '.join(reasons)}){size_hint(camera, board)}")
    params = np.array([view_parameters(c, board, camera.size) for c in corners])
    chosen = select_views(params, max_views=max_views, min_distance=MIN_VIEW_DISTANCE)
    camera.selected = [camera.candidates[i] for i in chosen]
    views = [corners[i] for i in chosen]
    result = calibrate_mono(board.points_in_board(), views, camera.size, options)
    # map solver view ids (positions in ``views``) back to frame indices
    frame_of = dict(enumerate(camera.selected))
    camera.result = MonoResult(
        model=result.model, rms_px=result.rms_px,
        view_ids=[frame_of[i] for i in result.view_ids],
        view_rms_px={frame_of[i]: e for i, e in result.view_rms_px.items()},
        rejected={frame_of[i]: why for i, why in result.rejected.items()},
        std=result.std,
        camera_from_board={frame_of[i]: p for i, p in result.camera_from_board.items()},
        residuals_px={frame_of[i]: r for i, r in result.residuals_px.items()},
        options=result.options, tangential_test=result.tangential_test,
    )
    used = [camera.frames[i].detection.corners_px for i in camera.result.view_ids]  # type: ignore[union-attr]
    used_params = np.array([view_parameters(c, board, camera.size) for c in used])
    camera.coverage = coverage(used_params, used, camera.size)
    camera.cross_validation_px = cross_validate(board.points_in_board(), used, camera.size,
                                                result.options)


def mono_camera_info(model: CameraModel, frame_id: str) -> CameraInfo:
    """Calibrated CameraInfo; P is camera_calibration's (alpha 0: only valid pixels)."""
    size = (model.width, model.height)
    new_k, _roi = cv2.getOptimalNewCameraMatrix(model.k, model.d, size, 0.0)
    p = np.zeros((3, 4))
    p[:, :3] = new_k
    return CameraInfo(0, frame_id, model.width, model.height, model.distortion_model,
                      model.d, model.k, np.eye(3), p)


def stereo_pairs(left: CameraStream, right: CameraStream,
                 approximate_s: float | None) -> list[tuple[int, int]]:
    """(left frame, right frame) indices shot at the same time."""
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
        raise InputError(
            f"{left.image_topic} and {right.image_topic} never pair {how} "
            f"(closest stamps {gap:.3f} ms apart); use --approximate SEC or resync the log"
        )
    return pairs


def solve_stereo(left: CameraStream, right: CameraStream, board: Board,
                 approximate_s: float | None, max_views: int) -> tuple[StereoResult,
                                                                      list[tuple[int, int]]]:
    pairs = stereo_pairs(left, right, approximate_s)
    joint = [(li, ri) for li, ri in pairs
             if (dl := left.frames[li].detection) is not None
             and (dr := right.frames[ri].detection) is not None
             and dl.accepted and dr.accepted
             and not (left.frames[li].duplicate and right.frames[ri].duplicate)
             and not left.frames[li].reason and not right.frames[ri].reason]
    assert left.size is not None and left.result is not None and right.result is not None
    params = np.array([view_parameters(left.frames[li].detection.corners_px, board, left.size)  # type: ignore[union-attr]
                       for li, _ in joint]) if joint else np.zeros((0, 4))
    chosen = [joint[i] for i in select_views(params, max_views=max_views,
                                             min_distance=MIN_VIEW_DISTANCE)]
    left_views = [left.frames[li].detection.corners_px for li, _ in chosen]  # type: ignore[union-attr]
    right_views = orient_right_views(
        board.points_in_board(), left_views,
        [right.frames[ri].detection.corners_px for _, ri in chosen],  # type: ignore[union-attr]
        left_model=left.result.model, right_model=right.result.model)
    result = calibrate_stereo(board.points_in_board(), left_views, right_views,
                              left_model=left.result.model, right_model=right.result.model,
                              square_m=board.square_m)
    return result, chosen


# --- ground truth ------------------------------------------------------------------------

def read_truth(reader: LogReader) -> dict[str, Any] | None:
    """The simulator's scenario record, when the log has one."""
    if SCENARIO_TOPIC not in reader.topics:
        return None
    for record in reader.messages([SCENARIO_TOPIC]):
        if isinstance(record.message, Text):
            try:
                data = json.loads(record.message.data)
            except json.JSONDecodeError:
                return None
            return data if isinstance(data, dict) else None
    return None


def truth_for(truth: dict[str, Any] | None, namespace: str,
              frame_id: str | None = None) -> dict[str, Any] | None:
    """The simulated camera of a namespace, or of a frame id once topics were renamed
    (e.g. by resync, which keeps frame ids)."""
    if truth is None:
        return None
    cameras = truth.get("cameras", [])
    for camera in cameras:
        if camera.get("namespace") == namespace:
            return dict(camera)
    matches = [c for c in cameras if frame_id and c.get("frame_id") == frame_id]
    return dict(matches[0]) if len(matches) == 1 else None


def truth_model(camera: dict[str, Any]) -> CameraModel:
    return CameraModel(int(camera["width"]), int(camera["height"]), np.array(camera["k"]),
                       camera["distortion_model"], np.array(camera["d"]))


# --- outputs ------------------------------------------------------------------------------

def _bgr(image: Image) -> np.ndarray:
    array = to_bgr_or_mono(image)
    if array.ndim == 2:
        if array.dtype != np.uint8:
            array = (array >> 8).astype(np.uint8)
        return cv2.cvtColor(array, cv2.COLOR_GRAY2BGR)
    return array


def frame_status(camera: CameraStream, frame: Frame) -> tuple[str, bool]:
    """Text drawn on an annotated frame, and whether the view was used."""
    result = camera.result
    assert result is not None
    if frame.detection is None:
        return "no board found", False
    if not frame.detection.accepted:
        return f"rejected: {frame.detection.reason}", False
    if frame.reason:
        return f"rejected: {frame.reason}", False
    if frame.index in result.rejected:
        return f"rejected: {result.rejected[frame.index]}", False
    if frame.index in result.view_rms_px:
        return f"used: RMS {result.view_rms_px[frame.index]:.3f} px", True
    return "not used: adds no coverage", False


def write_calibrated_log(reader: LogReader, path: Path, cameras: list[CameraStream], *,
                         board: Board, stereo: StereoResult | None,
                         stereo_frames: set[tuple[str, int]], summary: dict[str, Any],
                         progress: bool | None) -> None:
    """Pass 2: the input log plus the calibration's annotated topics."""
    by_topic = {c.image_topic: c for c in cameras}
    counters = dict.fromkeys(by_topic, 0)
    rectify_maps: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if stereo is not None:
        for stream in cameras:
            info = stream.camera_info
            assert info is not None and stream.size is not None
            rectify_maps[stream.namespace] = cv2.initUndistortRectifyMap(
                info.k, info.d, info.r, info.p[:, :3], stream.size, cv2.CV_16SC2)
    bar = tqdm(total=reader.message_count, unit="msg", desc="write", leave=False,
               disable=None if progress is None else not progress)
    with open_writer(path) as writer:
        for raw in reader.raw_messages():
            writer.write_raw(raw)
            bar.update()
            camera = by_topic.get(raw.topic)
            if camera is None:
                continue
            frame = camera.frames[counters[raw.topic]]
            counters[raw.topic] += 1
            image = _as_image(reader.decode(raw), reader, raw.topic)
            ns, stamp = camera.namespace, image.stamp_ns
            assert camera.camera_info is not None
            info = camera.camera_info
            writer.write(f"{ns}/calibrated/camera_info", CameraInfo(
                stamp, image.frame_id, info.width, info.height, info.distortion_model,
                info.d, info.k, info.r, info.p), log_time_ns=raw.log_time_ns)
            # a joint view's frame may repeat the previous one on one side: rectify it anyway
            if ns in rectify_maps and (ns, frame.index) in stereo_frames:
                map1, map2 = rectify_maps[ns]
                rectified = cv2.remap(image.pixels, map1, map2, cv2.INTER_LINEAR)
                writer.write(f"{ns}/image_rect", Image(stamp, image.frame_id, image.encoding,
                                                       rectified), log_time_ns=raw.log_time_ns)
            if frame.duplicate:
                continue
            status, used = frame_status(camera, frame)
            corners = frame.detection.corners_px if frame.detection is not None else None
            annotated = cv2.cvtColor(
                _annotate(_bgr(image), corners, board, status, used), cv2.COLOR_BGR2RGB)
            writer.write(f"{ns}/calibration/detections",
                         Image(stamp, image.frame_id, "rgb8", annotated),
                         log_time_ns=raw.log_time_ns)
            result = camera.result
            assert result is not None
            if used and corners is not None:
                residual = result.residuals_px[frame.index]
                writer.write(f"{ns}/calibration/view_error", PointStamped(
                    stamp, image.frame_id,
                    np.array([result.view_rms_px[frame.index], 0.0, 0.0], dtype=np.float64)),
                    log_time_ns=raw.log_time_ns)
                writer.write(f"{ns}/calibration/residuals", Text(json.dumps({
                    "stamp_ns": stamp, "frame_id": image.frame_id,
                    "rms_px": result.view_rms_px[frame.index],
                    "corners_px": np.round(corners, 4).tolist(),
                    "residuals_px": np.round(residual, 5).tolist(),
                })), log_time_ns=raw.log_time_ns)
        end = reader.end_ns or 0
        writer.write("/calibration/summary", Text(json.dumps(summary, indent=1)),
                     log_time_ns=end)
    bar.close()


def _annotate(bgr: np.ndarray, corners: np.ndarray | None, board: Board, status: str,
              used: bool) -> np.ndarray:
    from processors.calibration.figures import annotate_detection

    return annotate_detection(bgr, corners, board.pattern_size, status, used)


def outlier_limit(camera: CameraStream) -> float:
    assert camera.result is not None
    errors = list(camera.result.view_rms_px.values())
    return max(OUTLIER_FACTOR * float(np.median(errors)), OUTLIER_FLOOR_PX) if errors else 0.0


def calibrate_log(
    log: Path,
    *,
    board: Board,
    cameras: list[str],
    output_dir: Path,
    options: CalibrationOptions,
    approximate_s: float | None = None,
    camera_name: str | None = None,
    max_speed_px: float | None = None,
    max_views: int = MAX_VIEWS,
    overwrite: bool = False,
    workers: int | None = None,
    progress: bool | None = None,
    recover: bool = False,
) -> CalibrationRun:
    """Calibrate one camera (``cameras=[ns]``) or a stereo pair (``[left_ns, right_ns]``)."""
    from .report import build_summary, write_files

    started = time.perf_counter()
    stereo_mode = len(cameras) == 2
    figures = ["coverage.png", "view_errors.png", "residuals.png"]
    names = (["left.yaml", "right.yaml", "rectified.png", *(f"{side}_{f}" for side in
                                                            ("left", "right") for f in figures)]
             if stereo_mode else ["ost.yaml", *figures]) + \
        ["ost.txt", "calibration.mcap", "report.md", "calibration.json"]
    staging = AtomicFolder(output_dir, names, overwrite=overwrite, inputs=[log])
    try:
        with open_reader(log, recover=recover) as reader:
            if reader.message_count == 0:
                raise InputError(f"{log} is empty (no messages)")
            streams = [resolve_camera(reader, ns) for ns in cameras]
            detect_views(reader, streams, board, workers=workers or os.cpu_count() or 2,
                         progress=progress)
            truth = read_truth(reader)
            for stream in streams:
                if stream.size is None:
                    raise InputError(f"no images on {stream.image_topic}")
                info = stream.log_info
                if info is not None and (info.width, info.height) != stream.size \
                        and info.width and info.height:
                    raise InputError(
                        f"{stream.image_topic} images are {stream.size[0]}x{stream.size[1]} but "
                        f"{stream.info_topic} says {info.width}x{info.height}"
                    )
                if max_speed_px is not None:
                    apply_speed_limit(stream, max_speed_px)
                note = "" if not stereo_mode else f" (camera {stream.namespace})"
                solve_camera(stream, board, options, max_views=max_views, topic_note=note)
                stream.truth = truth_for(truth, stream.namespace,
                                         stream.log_info.frame_id if stream.log_info else None)
            stereo: StereoResult | None = None
            pairs: list[tuple[int, int]] = []
            stereo_rejected: list[tuple[tuple[int, int], str]] = []
            frame_id = {s.namespace: (s.log_info.frame_id if s.log_info else s.name)
                        for s in streams}
            if stereo_mode:
                left, right = streams
                stereo, joint = solve_stereo(left, right, board, approximate_s, max_views)
                pairs = [joint[i] for i in stereo.view_ids]
                stereo_rejected = [(joint[i], why) for i, why in sorted(stereo.rejected.items())]
                for stream, r, p in ((left, stereo.r1, stereo.p1), (right, stereo.r2, stereo.p2)):
                    m = stream.result.model  # type: ignore[union-attr]
                    stream.camera_info = CameraInfo(0, frame_id[stream.namespace], m.width,
                                                    m.height, m.distortion_model, m.d, m.k, r, p)
            else:
                m = streams[0].result.model  # type: ignore[union-attr]
                streams[0].camera_info = mono_camera_info(m, frame_id[streams[0].namespace])
            summary = build_summary(streams, stereo, truth, board, options,
                                    stereo_rejected=stereo_rejected)
            stereo_frames = {(streams[0].namespace, li) for li, _ in pairs} | \
                {(streams[-1].namespace, ri) for _, ri in pairs} if stereo_mode else set()
            write_calibrated_log(reader, staging.path / "calibration.mcap", streams, board=board,
                                 stereo=stereo, stereo_frames=stereo_frames, summary=summary,
                                 progress=progress)
            write_files(staging.path, streams, stereo=stereo, pairs=pairs, summary=summary,
                        board=board, camera_name=camera_name, reader=reader)
        files = staging.commit()
    except BaseException:
        staging.discard()
        raise
    return CalibrationRun(streams, stereo, pairs, output_dir, files,
                          time.perf_counter() - started, summary)


__all__ = ["CalibrationRun", "calibrate_log", "max_projection_difference"]

"""What a log shows of each camera: its topics, and the board found in every frame.

This is the one pass over the log that calibration needs for solving: it streams the camera
images, skips frames whose pixels are byte for byte those of the previous frame (they share
its detection and count once), and detects the board on a thread pool (OpenCV releases the
GIL) in runs of consecutive frames: the first frame of a run is searched, the next ones
follow the board from frame to frame (a chessboard's corners refined where its motion says
they are, a twentieth of the cost) and are searched afresh only when that fails. Only corners
are kept, so memory does not grow with the number of images. The camera_info, the
simulator's scenario record and its true target poses are read in the same pass.
"""

from __future__ import annotations

import dataclasses
from array import array
from collections import deque
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from processors.calibration.board import Board
from processors.calibration.detect import Detection
from processors.calibration.targets import SEGMENT_FRAMES, detect_segment, find_board
from replay.camera import CameraModel
from replay.errors import RecordError
from replay.formats import LogReader
from replay.geometry import transform_from_pose
from replay.messages import F64, CameraInfo, PoseStamped
from replay.progress import progress_bar
from replay.records import Scenario
from replay.topics import SCENARIO, split_ground_truth

from ..errors import InputError
from ..processing.cameras import CameraSource
from .pixels import TopicFrames

#: frames kept per camera to suggest another board size when none is found
HINT_SAMPLES = 12
#: a frame this long or longer after the camera's previous distinct frame is a snapshot (a
#: photo in a folder, a triggered pair a second): no neighbouring frame shows its pose, so
#: it is searched with every detector and its motion is not observable
SNAPSHOT_GAP_S = 0.25
#: a camera with at most this many frames (a folder of photos, whatever its stamps) has
#: every frame searched with every detector: each may be a view no other frame replaces
THOROUGH_FRAMES = 200

__all__ = [
    "SNAPSHOT_GAP_S",
    "THOROUGH_FRAMES",
    "CameraSource",
    "CameraViews",
    "DetectedFrame",
    "LogViews",
    "board_speeds",
    "detect_views",
    "size_hint",
    "with_speed_limit",
]


@dataclass(frozen=True, slots=True)
class DetectedFrame:
    """One image of one camera, as the detection pass saw it. ``speed_px``: how far the
    board's corners moved to the nearer neighbouring frame (px; None without a neighbour
    showing the same corners)."""

    index: int
    stamp_ns: int
    duplicate: bool  # byte for byte the previous frame: shares its detection, counts once
    detection: Detection | None = None
    reason: str = ""  # why a found board is not a candidate view (beyond the detection's own)
    speed_px: float | None = None

    @property
    def candidate(self) -> bool:
        """A distinct frame whose board passed every check."""
        return (not self.duplicate and self.detection is not None and self.detection.accepted
                and not self.reason)


@dataclass(frozen=True)
class CameraViews:
    """Every frame of one camera with its detection, the image size, the log's own
    camera_info (the first one) and a few frames kept for size hints."""

    source: CameraSource
    frames: tuple[DetectedFrame, ...]
    size: tuple[int, int]  # (width, height)
    log_info: CameraInfo | None
    samples: tuple[np.ndarray, ...] = field(default=(), repr=False)
    #: simulated logs: target name -> image stamp (ns) -> true ``camera_from_target`` (4, 4),
    #: at the distinct frames with a board found (the only ones a view holds)
    true_camera_from_target: dict[str, dict[int, F64]] = field(default_factory=dict,
                                                               repr=False)

    @property
    def frame_id(self) -> str:
        """The camera's optical frame: from its camera_info, else its name."""
        return self.log_info.frame_id if self.log_info is not None else self.source.name

    def detection(self, index: int) -> Detection:
        """The board found in frame ``index`` (which must have one)."""
        detection = self.frames[index].detection
        if detection is None:
            raise ValueError(f"frame {index} of {self.source.image_topic} has no board")
        return detection

    def corners(self, index: int) -> np.ndarray:
        """Detected corners ``(M, 2)`` of frame ``index`` (which must have a detection)."""
        return self.detection(index).corners_px

    def distinct(self) -> Iterator[DetectedFrame]:
        """The frames that do not repeat the previous one."""
        return (f for f in self.frames if not f.duplicate)


@dataclass(frozen=True)
class LogViews:
    """What the detection pass found: every camera's views and the scenario record."""

    cameras: list[CameraViews]
    scenario: Scenario | None
    warnings: list[str] = field(default_factory=list)  # e.g. frames that did not decode


@dataclass
class _Seen:
    """What the pass has collected for one camera so far."""

    source: CameraSource
    hint_stride: int
    thorough: bool = False  # every frame searched with every detector (few frames)
    stamps: list[int] = field(default_factory=list)
    duplicates: list[bool] = field(default_factory=list)
    detections: dict[int, Detection | None] = field(default_factory=dict)
    size: tuple[int, int] | None = None
    log_info: CameraInfo | None = None
    samples: list[np.ndarray] = field(default_factory=list)
    #: true target poses: target name -> their stamps (ns), and 7 numbers per pose (position
    #: in m, quaternion xyzw): a few dozen bytes each, where a (4, 4) array takes 240
    truth_stamps: dict[str, list[int]] = field(default_factory=dict)
    truth_poses: dict[str, array[float]] = field(default_factory=dict)
    last: np.ndarray | None = None  # the previous frame's pixels
    last_distinct_ns: int | None = None
    #: frames to detect: index, pixels, whether a snapshot
    run: list[tuple[int, np.ndarray, bool]] = field(default_factory=list)

    def snapshot(self, stamp_ns: int) -> bool:
        """Whether a distinct frame at ``stamp_ns`` comes :data:`SNAPSHOT_GAP_S` or more
        after the previous one (the first frame does); remembers it as the previous one."""
        previous_ns = self.last_distinct_ns
        self.last_distinct_ns = stamp_ns
        return self.thorough or previous_ns is None \
            or abs(stamp_ns - previous_ns) >= SNAPSHOT_GAP_S * 1e9

    def add(self, gray: np.ndarray, stamp_ns: int, where: str) -> tuple[int, bool]:
        """Record a frame; its index and whether it repeats the previous one."""
        size = (gray.shape[1], gray.shape[0])
        if self.size is None:
            self.size = size
        elif self.size != size:
            raise InputError(
                f"{where} changes image size from {self.size[0]}x{self.size[1]} to "
                f"{size[0]}x{size[1]}")
        duplicate = self.last is not None and np.array_equal(gray, self.last)
        self.last = gray
        index = len(self.stamps)
        self.stamps.append(stamp_ns)
        self.duplicates.append(duplicate)
        if index % self.hint_stride == 0 and len(self.samples) < HINT_SAMPLES:
            # a copy: the frame's pixels may be a view of a whole decompressed chunk
            self.samples.append(gray.copy() if gray.base is not None else gray)
        return index, duplicate

    def add_truth(self, target: str, pose: PoseStamped) -> None:
        """Record a true pose of ``target`` in this camera."""
        self.truth_stamps.setdefault(target, []).append(pose.stamp_ns)
        self.truth_poses.setdefault(target, array("d")).extend(
            [*pose.position_m.tolist(), *pose.orientation_xyzw.tolist()])

    def _truth(self, frames: tuple[DetectedFrame, ...]) -> dict[str, dict[int, F64]]:
        """The true poses at the stamps of the distinct frames with a board found."""
        wanted = {f.stamp_ns for f in frames if not f.duplicate and f.detection is not None}
        out: dict[str, dict[int, F64]] = {}
        for target, stamps in self.truth_stamps.items():
            poses = np.frombuffer(self.truth_poses[target], dtype=np.float64).reshape(-1, 7)
            out[target] = {stamp: transform_from_pose(pose[:3], pose[3:])
                           for stamp, pose in zip(stamps, poses, strict=True) if stamp in wanted}
        return out

    def views(self) -> CameraViews:
        """The frames, duplicates sharing the detection of the frame they repeat, each with
        its board's speed."""
        if self.size is None:
            raise InputError(f"no images on {self.source.image_topic}")
        detections, last = [], None
        for index, duplicate in enumerate(self.duplicates):
            if not duplicate:
                last = self.detections.get(index)
            detections.append(last)
        speeds = board_speeds(detections, self.duplicates)
        frames = tuple(DetectedFrame(i, stamp, duplicate, detection, speed_px=speed)
                       for i, (stamp, duplicate, detection, speed) in enumerate(zip(
                           self.stamps, self.duplicates, detections, speeds, strict=True)))
        return CameraViews(self.source, frames, self.size, self.log_info, tuple(self.samples),
                           self._truth(frames))


def board_speeds(detections: list[Detection | None], duplicates: list[bool]) -> list[float | None]:
    """Per frame, the mean displacement of its corners to the nearer neighbouring frame that
    shows the same corners (0 next to a repeated frame: nothing moved)."""
    def moved(a: Detection | None, b: Detection | None) -> float | None:
        if a is None or b is None or not a.accepted or not b.accepted \
                or not np.array_equal(a.ids, b.ids):
            return None
        return float(np.linalg.norm(a.corners_px - b.corners_px, axis=1).mean())

    out: list[float | None] = []
    for i, detection in enumerate(detections):
        if (i + 1 < len(duplicates) and duplicates[i + 1]) or duplicates[i]:
            out.append(0.0 if detection is not None else None)
            continue
        near = [m for j in (i - 1, i + 1) if 0 <= j < len(detections)
                and (m := moved(detection, detections[j])) is not None]
        out.append(min(near) if near else None)
    return out


def detect_views(reader: LogReader, sources: list[CameraSource], board: Board, *,
                 workers: int, progress: bool | None,
                 models: dict[str, CameraModel] | None = None) -> LogViews:
    """Detect the board in every distinct frame of ``sources`` (one pass over the log);
    ``models`` (by namespace, from a first calibration) guide a ChArUco detection."""
    counts = {s.namespace: reader.topics[s.image_topic].count for s in sources}
    seen = {s.namespace: _Seen(s, max(1, counts[s.namespace] // HINT_SAMPLES),
                               thorough=counts[s.namespace] <= THOROUGH_FRAMES)
            for s in sources}
    by_image = {s.image_topic: seen[s.namespace] for s in sources}
    by_info = {s.info_topic: seen[s.namespace] for s in sources if s.info_topic}
    scenario: Scenario | None = None
    by_truth = {topic: (seen[named[0]], named[1]) for topic in reader.topics
                if (named := split_ground_truth(topic)) is not None and named[0] in seen}
    wanted = [*by_image, *by_info, *by_truth,
              *([SCENARIO] if SCENARIO in reader.topics else [])]
    pending: deque[tuple[_Seen, list[int], Future[list[Detection | None]]]] = deque()
    bar = progress_bar(total=sum(reader.topics[s.image_topic].count for s in sources),
                       unit="frame", desc="detect" if models is None else "detect again (guided)",
                       progress=progress)

    def submit(camera: _Seen) -> None:
        indices = [i for i, _, _ in camera.run]
        model = (models or {}).get(camera.source.namespace)
        pending.append((camera, indices, pool.submit(
            detect_segment, [g for _, g, _ in camera.run], board, model,
            [photo for _, _, photo in camera.run])))
        camera.run = []
        while len(pending) > 2 * workers + 2:
            done, at, future = pending.popleft()
            done.detections.update(zip(at, future.result(), strict=True))

    to_frame = TopicFrames()
    with ThreadPoolExecutor(max_workers=workers) as pool, bar:
        for raw in reader.raw_messages(wanted):
            if raw.topic == SCENARIO:
                scenario = scenario or _scenario(reader.decode(raw))
                continue
            if raw.topic in by_truth:
                camera, target = by_truth[raw.topic]
                pose = reader.decode(raw)
                if isinstance(pose, PoseStamped):
                    camera.add_truth(target, pose)
                continue
            if raw.topic in by_info:
                camera = by_info[raw.topic]
                if camera.log_info is None:
                    message = reader.decode(raw)
                    camera.log_info = message if isinstance(message, CameraInfo) else None
                continue
            camera = by_image[raw.topic]
            image = to_frame(reader, raw)
            if image is None:  # video before its first keyframe, or undecodable: no view
                bar.update()
                continue
            gray = image.mono8()
            index, duplicate = camera.add(gray, image.stamp_ns, f"{reader.path}: {raw.topic}")
            if not duplicate:
                # frames wait for detection in runs: a view of the log's chunk would keep
                # the whole chunk until then
                camera.run.append((index, gray if gray.base is None else gray.copy(),
                                   camera.snapshot(image.stamp_ns)))
                if len(camera.run) >= SEGMENT_FRAMES:
                    submit(camera)
            bar.update()
        for camera in seen.values():
            if camera.run:
                submit(camera)
        for done, at, future in pending:
            done.detections.update(zip(at, future.result(), strict=True))
    return LogViews([seen[s.namespace].views() for s in sources], scenario,
                    to_frame.warnings())


def _scenario(message: object) -> Scenario | None:
    """The scenario record; a log whose record is malformed is calibrated without truth."""
    try:
        return Scenario.from_message(message)
    except RecordError:
        return None


def with_speed_limit(views: CameraViews, max_speed_px: float) -> CameraViews:
    """The views with boards moving faster than ``max_speed_px`` per frame rejected
    (camera_calibration's --max-chessboard-speed; see :attr:`DetectedFrame.speed_px`)."""
    frames = tuple(
        dataclasses.replace(f, reason=f"board moving {f.speed_px:.2f} px/frame > "
                                      f"{max_speed_px:g}")
        if f.candidate and f.speed_px is not None and f.speed_px > max_speed_px else f
        for f in views.frames)
    return dataclasses.replace(views, frames=frames)


def size_hint(views: CameraViews, board: Board) -> str:
    """A hint when another point count (a ChArUco board: the other marker layout) would have
    matched the frames."""
    if board.pattern == "charuco":
        return _layout_hint(views, board)
    c, r = board.cols, board.rows
    for cols, rows in ((r, c), (c + 1, r), (c, r + 1), (c + 1, r + 1), (c - 1, r), (c, r - 1),
                       (c - 1, r - 1)):
        if cols < 2 or rows < 2 or (cols, rows) == (c, r):
            continue
        other = Board(cols, rows, board.square_m, board.pattern)
        for gray in views.samples:
            found = find_board(gray, other)
            if found is not None and found.accepted:
                return (f"; the frames show a {cols}x{rows} board: --size counts inner "
                        "corners (squares minus one) per row x per column")
    return ""


def _layout_hint(views: CameraViews, board: Board) -> str:
    """A hint when the ChArUco board's other marker layout (OpenCV's before 4.6 or today's;
    they differ with an even number of rows of squares) would have matched the frames."""
    if (board.rows + 1) % 2:
        return ""
    other = dataclasses.replace(board, legacy_pattern=not board.legacy_pattern)
    for gray in views.samples:
        found = find_board(gray, other)
        if found is not None and found.accepted:
            return ("; the frames show the board's markers laid out as OpenCV "
                    + ("today does: leave out --legacy-pattern" if board.legacy_pattern
                       else "before 4.6 did: add --legacy-pattern"))
    return ""

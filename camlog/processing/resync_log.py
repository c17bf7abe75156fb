"""Pair the images of two unsynchronised cameras in a log and write them re-stamped.

Pass 1 reads only the header stamps of both image and camera_info topics (images are not
decompressed; a raw image decodes to a view of its buffer). The stamps are paired with
:func:`processors.resync.pair_stamps`. Pass 2 copies every input message through and, as
the members of a pair arrive, writes both images and their camera_info (matched by identical
stamp) under ``OUT_PREFIX/{left,right}/...`` with the pair's common stamp. Only the members
of pairs not yet complete are held, so memory is bounded by the slop, not the log length.
A video camera's pictures are decoded in order and its paired ones encoded again as a video
stream of their own (a picture cannot be left out of a stream the next ones refer to).
"""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from processors.resync import default_slop_ns, pair_stamp_ns, pair_stamps, pairing_stats
from replay.atomic import check_not_input, write_text_atomic
from replay.errors import RecordError
from replay.formats import LogReader, LogWriter, open_reader, open_writer
from replay.frames import Frame, FrameStream, VideoEncoder
from replay.messages import (
    CameraInfo,
    CompressedImage,
    CompressedVideo,
    Image,
    Message,
    PointStamped,
)
from replay.progress import progress_bar
from replay.records import ResyncStats, TimeOffset
from replay.storage import local_paths
from replay.topics import ResyncTopics

from ..errors import InputError, SyncError, UsageError
from ..requests.processing import ResyncRequest
from ..requests.values import ESTIMATED
from .cameras import find_camera, image_suffix
from .checks import require_free_topics, require_messages
from .time_offset import measure_offset

SIDES = ("left", "right")


@dataclass(frozen=True)
class ResyncResult:
    """What :func:`resync_log` did; ``stats`` is the JSON stored on ``PREFIX/stats``;
    ``offset_file``: where a measured offset was written."""

    output: Path
    stats: ResyncStats
    wall_s: float
    offset_file: Path | None = None


@dataclass(frozen=True)
class OffsetResult:
    """What :func:`measure_log_offset` measured and where it wrote it."""

    offset: TimeOffset
    offset_file: Path
    wall_s: float


@dataclass
class _Side:
    """Input and output topics of one camera, and the stamps pass 1 found."""

    name: str
    image_topic: str
    info_topic: str | None
    out_image: str
    out_info: str
    image_stamps: list[int] = field(default_factory=list)
    info_stamps: set[int] = field(default_factory=set)
    video: FrameStream = field(default_factory=FrameStream)  # pictures need their past
    encoder: VideoEncoder | None = None  # the re-stamped video: its paired pictures only

    def encode(self, frame: Frame) -> CompressedVideo:
        """A paired picture of a video camera in a video stream of its own."""
        if self.encoder is None:
            self.encoder = VideoEncoder(frame.source)
        return self.encoder(frame)


def _side(reader: LogReader, name: str, camera: str, prefix: str) -> _Side:
    """One camera of the pair, named by its namespace or its image topic."""
    try:
        source = find_camera(reader, camera)
    except InputError as err:
        raise InputError(f"{name} camera: {err}") from None
    suffix = image_suffix(source, reader.topics[source.image_topic].msgtype)
    return _Side(name, source.image_topic, source.info_topic,
                 f"{prefix}/{name}/{suffix}", f"{prefix}/{name}/camera_info")


def _read_stamps(reader: LogReader, sides: list[_Side]) -> None:
    images = {s.image_topic: s for s in sides}
    infos = {s.info_topic: s for s in sides if s.info_topic}
    for raw in reader.raw_messages([*images, *infos]):
        stamp = _stamp(reader.decode(raw))
        if raw.topic in images:
            images[raw.topic].image_stamps.append(stamp)
        else:
            infos[raw.topic].info_stamps.add(stamp)


def _stamp(message: Message | Frame) -> int:
    stamp = getattr(message, "stamp_ns", None)
    assert stamp is not None, "image and camera_info messages have a header"
    return int(stamp)


def _keys(stamps: list[int]) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """Sorted stamps and, per sorted position, ``(stamp, occurrence)`` naming the message
    (repeated stamps are told apart by their order in the log)."""
    order = np.argsort(np.asarray(stamps, dtype=np.int64), kind="stable")
    sorted_ns = np.asarray(stamps, dtype=np.int64)[order]
    keys: list[tuple[int, int]] = []
    seen: dict[int, int] = {}
    for stamp in sorted_ns.tolist():
        seen[stamp] = seen.get(stamp, -1) + 1
        keys.append((stamp, seen[stamp]))
    return sorted_ns, keys


def _offset_file(request: ResyncRequest) -> Path:
    """Where a measured offset goes: ``--offset-file``, else beside the output log, else
    in the working folder named after the input log."""
    if request.offset_file is not None:
        return request.offset_file
    if request.output is not None:
        return request.output.with_name(f"{request.output.stem}_offset.json")
    return Path(f"{Path(str(request.log).rstrip('/')).stem}_offset.json")


def _measured(reader: LogReader, request: ResyncRequest) -> tuple[TimeOffset, Path]:
    """The offset measured from the log's images, written to its file (atomically)."""
    sources = [find_camera(reader, ns) for ns in (request.left, request.right)]
    offset = measure_offset(reader, *sources, board=request.board(),
                            calibration=request.calibration, max_offset_s=request.max_offset,
                            workers=request.workers or os.cpu_count() or 2,
                            progress=request.progress)
    path = _offset_file(request)
    check_not_input(path, local_paths(request.log))
    write_text_atomic(path, offset.to_json_text(indent=2) + "\n")
    return offset, path


def _given(request: ResyncRequest) -> TimeOffset | float | None:
    """The offset the request gives: milliseconds, an offset file's record, or none."""
    if request.offset is None or request.offset == ESTIMATED:
        return None
    if isinstance(request.offset, float):
        return request.offset
    path = Path(request.offset)
    try:
        return TimeOffset.from_json_text(path.read_text())
    except OSError as err:
        raise InputError(f"{path}: cannot read the offset file ({err.strerror})") from None
    except RecordError as err:
        raise InputError(f"{path}: not an offset file ({err})") from None


def measure_log_offset(request: ResyncRequest) -> OffsetResult:
    """Measure how much later the request's right camera stamps an instant than its left
    one (:mod:`.time_offset`) and write it to the offset file (``--estimate-offset``)."""
    started = time.perf_counter()
    with open_reader(request.log, recover=request.recover) as reader:
        require_messages(reader)
        offset, path = _measured(reader, request)
    return OffsetResult(offset, path, time.perf_counter() - started)


def resync_log(request: ResyncRequest) -> ResyncResult:
    """Pair ``left``/``right`` camera namespaces of the request's log and write its ``output``.

    ``slop`` (s) bounds ``|right - left|`` of a pair; default half the median frame period.
    With an ``offset`` (given, read from a file or measured from the images and written to
    the offset file) the right camera's stamps are moved back by it before pairing. Pairs
    are re-stamped with the later stamp. Every input message is kept; the output adds
    ``PREFIX/{left,right}/{image_raw,camera_info}``, ``PREFIX/offset_s``
    (``PointStamped``, x = right - left stamp in s, per pair, the offset taken off) and
    ``PREFIX/stats`` (JSON).
    """
    input_path, output, left, right = request.log, request.output, request.left, request.right
    out_prefix, slop_s, fmt = request.out_prefix, request.slop, request.format
    overwrite, recover = request.overwrite, request.recover
    if output is None:
        raise UsageError("resync needs an output log (-o/--output)")
    started = time.perf_counter()
    check_not_input(output, local_paths(input_path))
    prefix = "/" + out_prefix.strip("/")
    given = _given(request)
    with open_reader(input_path, recover=recover) as reader:
        require_messages(reader)
        sides = [_side(reader, name, ns, prefix) for name, ns in zip(SIDES, (left, right),
                                                                    strict=True)]
        offset_topic, stats_topic = ResyncTopics(prefix).offset, ResyncTopics(prefix).stats
        new_topics = [t for s in sides for t in (s.out_image, s.out_info)]
        require_free_topics(reader, [*new_topics, offset_topic, stats_topic],
                            hint="choose another --out-prefix")
        offset_file = None
        if request.measures:
            record, offset_file = _measured(reader, request)
            given = record
        moved_ns = 0 if given is None else round(
            (given.offset_ms if isinstance(given, TimeOffset) else given) * 1e6)
        _read_stamps(reader, sides)
        (left_ns, left_keys), (right_ns, right_keys) = (_keys(s.image_stamps) for s in sides)
        right_ns = right_ns - moved_ns
        slop_ns = default_slop_ns(left_ns, right_ns) if slop_s is None else round(slop_s * 1e9)
        pairing = pair_stamps(left_ns, right_ns, slop_ns=slop_ns)
        stats = dataclasses.replace(
            pairing_stats(left_ns, right_ns, pairing), left_topic=sides[0].image_topic,
            right_topic=sides[1].image_topic,
            slop_source="default: half the median frame period" if slop_s is None else "given",
            right_stamps_moved_ns=-moved_ns if given is not None else None,
            time_offset=given if isinstance(given, TimeOffset) else None)
        if not len(pairing):
            raise SyncError(
                f"{reader.path}: no {sides[0].image_topic} frame has a {sides[1].image_topic} "
                f"partner within {slop_ns / 1e6:.3f} ms ({len(left_ns)} left, "
                f"{len(right_ns)} right frames); try a larger --slop"
            )
        common_ns = pair_stamp_ns(left_ns[pairing.left_index], right_ns[pairing.right_index])
        pair_of, needed = _plan(sides, [left_keys, right_keys],
                                [pairing.left_index, pairing.right_index])
        with open_writer(output, fmt=fmt, overwrite=overwrite,
                         inputs=local_paths(input_path)) as writer:
            with progress_bar(total=reader.message_count, unit="msg", desc="resync",
                              progress=request.progress) as bar:
                stats = dataclasses.replace(stats, peak_buffered_messages=_write_pairs(
                    reader, writer=writer, sides=sides, pair_of=pair_of, needed=needed,
                    common_ns=common_ns.tolist(), offset_topic=offset_topic, bar=bar,
                    moved_ns=moved_ns))
            writer.write(stats_topic, stats.to_message(),
                         log_time_ns=reader.end_ns or int(common_ns[-1]))
    return ResyncResult(output, stats, time.perf_counter() - started, offset_file)


def _plan(
    sides: list[_Side], keys: list[list[tuple[int, int]]], picked: list[np.ndarray]
) -> tuple[list[dict[tuple[int, int], int]], list[set[tuple[int, str]]]]:
    """Per side, message key -> pair number; per pair, the ``(side, kind)`` it waits for
    (its images, and the camera_info of the first image with that stamp when one exists)."""
    pair_of: list[dict[tuple[int, int], int]] = [{}, {}]
    needed: list[set[tuple[int, str]]] = [set() for _ in picked[0]]
    for index, side in enumerate(sides):
        for k, i in enumerate(picked[index].tolist()):
            stamp, occurrence = keys[index][i]
            pair_of[index][(stamp, occurrence)] = k
            needed[k].add((index, "image"))
            if occurrence == 0 and stamp in side.info_stamps:
                needed[k].add((index, "info"))
    return pair_of, needed


def _write_pairs(
    reader: LogReader,
    *,
    writer: LogWriter,
    sides: list[_Side],
    pair_of: list[dict[tuple[int, int], int]],
    needed: list[set[tuple[int, str]]],
    common_ns: list[int],
    offset_topic: str,
    bar: Any,
    moved_ns: int,
) -> int:
    """Pass 2: copy everything, write each pair once complete; returns the peak buffer
    (``moved_ns``: the offset taken off the right camera's stamps)."""
    roles = {}
    for index, side in enumerate(sides):
        roles[side.image_topic] = (index, "image")
        if side.info_topic:
            roles[side.info_topic] = (index, "info")
    occurrences: list[dict[int, int]] = [{}, {}]
    pending: dict[int, dict[tuple[int, str], tuple[int, Message | Frame]]] = {}
    info_used: list[set[int]] = [set(), set()]
    buffered = peak = 0
    for raw in reader.raw_messages():
        bar.update()
        writer.write_raw(raw)
        role = roles.get(raw.topic)
        if role is None:
            continue
        index, kind = role
        decoded = reader.decode(raw)
        stamp = _stamp(decoded)
        if kind == "image":
            seen = occurrences[index][stamp] = occurrences[index].get(stamp, -1) + 1
            pair = pair_of[index].get((stamp, seen))
        else:
            if stamp in info_used[index]:
                continue  # a second camera_info with the same stamp: the first one is used
            info_used[index].add(stamp)
            pair = pair_of[index].get((stamp, 0))
        message: Message | Frame | None = decoded
        if isinstance(decoded, CompressedVideo):  # every picture decoded, in order
            message = sides[index].video.decode(decoded)  # None before the first keyframe
        if pair is None or message is None:
            continue
        members = pending.setdefault(pair, {})
        members[(index, kind)] = (raw.log_time_ns, message)
        buffered += 1
        peak = max(peak, buffered)
        if needed[pair] <= members.keys():
            _write_pair(writer, sides, members, common_ns[pair], offset_topic,
                        moved_ns=moved_ns)
            buffered -= len(members)
            del pending[pair]
    return peak


def _write_pair(
    writer: LogWriter,
    sides: list[_Side],
    members: dict[tuple[int, str], tuple[int, Message | Frame]],
    stamp_ns: int,
    offset_topic: str,
    *,
    moved_ns: int,
) -> None:
    log_time = max(t for t, _ in members.values())
    for (index, kind), (_, message) in sorted(members.items()):
        topic = sides[index].out_image if kind == "image" else sides[index].out_info
        if isinstance(message, Frame):  # video: re-encoded (its pictures need their past)
            out: Message = sides[index].encode(dataclasses.replace(message, stamp_ns=stamp_ns))
        else:
            assert isinstance(message, Image | CompressedImage | CameraInfo)
            out = dataclasses.replace(message, stamp_ns=stamp_ns)
        writer.write(topic, out, log_time_ns=log_time)
    left, right = (members[(i, "image")][1] for i in range(2))
    offset_s = (_stamp(right) - moved_ns - _stamp(left)) / 1e9
    frame_id = getattr(left, "frame_id", "")
    writer.write(offset_topic, PointStamped(stamp_ns, frame_id, np.array([offset_s, 0.0, 0.0])),
                 log_time_ns=log_time)

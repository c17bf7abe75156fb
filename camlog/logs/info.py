"""What a log holds, like ``ros2 bag info``: format, size, time span, topics and rates.

:func:`summarize` takes counts and each topic's first and last log time (for its rate) from
the log's index where it has them (an indexed MCAP file, a ROS1 bag), else streams the raw
messages once, and decodes only the first message of image and camera-info topics to report
their encoding and size. :func:`format_summary` renders the result as text.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

from replay import storage
from replay.buffer_layout import check_buffer
from replay.errors import ReplayError
from replay.formats.base import ROS_SERIALIZATIONS, LogReader, RawMessage
from replay.msgtypes import CAMERA_INFO, CAMERA_INFO_TYPES, CDR, DECODABLE, FRAME_TYPES, IMAGE
from replay.progress import progress_bar
from replay.sizes import bytes_on_disk, format_size

if TYPE_CHECKING:
    from replay.frames import FrameStream

    from ..requests.logs import InfoRequest

__all__ = ["FrameCheck", "InfoReport", "LogSummary", "TopicSummary", "describe_log",
           "format_size", "format_summary", "size_on_disk", "summarize"]

#: topics whose first messages lie this close in log time are read together
FIRST_MESSAGES_WINDOW_NS = 1_000_000_000
#: topics whose first message is decoded to describe the stream (ROS and Foxglove types)
DESCRIBED_TYPES = FRAME_TYPES | CAMERA_INFO_TYPES


@dataclass(frozen=True, slots=True)
class TopicSummary:
    """One topic: type, message count, first/last log time and a short stream description.

    ``detail`` is e.g. ``mono8 848x800`` for images, ``jpeg 640x480`` for compressed images
    (format string, decoded size) and ``640x480 plumb_bob`` for camera info; empty otherwise.
    """

    name: str
    msgtype: str
    count: int
    first_ns: int | None
    last_ns: int | None
    detail: str = ""

    @property
    def rate_hz(self) -> float | None:
        """``(count - 1) / (last - first)``; None with fewer than two distinct times."""
        if self.count < 2 or self.first_ns is None or self.last_ns is None:
            return None
        span_ns = self.last_ns - self.first_ns
        return (self.count - 1) * 1e9 / span_ns if span_ns > 0 else None


@dataclass(frozen=True, slots=True)
class FrameCheck:
    """Every image frame of a log decoded (``info --verify``): how many were read, and per
    topic how many did not decode (a cut JPEG, a buffer too small, video before its first
    keyframe, an encoding camlog does not read)."""

    frames: int
    undecodable: dict[str, int]

    @property
    def warnings(self) -> tuple[str, ...]:
        """One line per topic with frames that did not decode."""
        return tuple(f"{topic}: {count} frames did not decode"
                     for topic, count in sorted(self.undecodable.items()))


@dataclass(frozen=True, slots=True)
class LogSummary:
    """Everything ``camlog info`` prints about one log."""

    path: Path | str
    format_name: str
    size_bytes: int
    start_ns: int | None
    end_ns: int | None
    message_count: int
    topics: tuple[TopicSummary, ...]
    warnings: tuple[str, ...] = ()
    frames: FrameCheck | None = None  # None: frames not decoded (only ``verify`` does)

    @property
    def duration_s(self) -> float:
        """Log time from the first to the last message (0 for an empty log)."""
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / 1e9


def summarize(reader: LogReader, *, verify: bool = False,
              progress: bool | None = False) -> LogSummary:
    """Summary of an open log; reads the index, or (``verify``, or a log without one) every
    raw message once, which finds damage anywhere in the log (the bar counts them);
    ``verify`` also decodes every image frame and counts those that do not decode, else few
    messages are decoded."""
    counts: dict[str, int] = {}
    first_ns: dict[str, int] = {}
    last_ns: dict[str, int] = {}
    details: dict[str, str] = {}
    spans = None if verify else reader.topic_spans()
    check = _FrameChecker() if verify else None
    if spans is not None:
        counts = {name: info.count for name, info in reader.topics.items() if name in spans}
        first_ns = {name: first for name, (first, _last) in spans.items()}
        last_ns = {name: last for name, (_first, last) in spans.items()}
        described = {}  # only these need their first message
        for name, info in reader.topics.items():
            if name not in spans:
                continue
            if info.msgtype in DESCRIBED_TYPES:
                described[name] = first_ns[name]
            elif info.serialization not in ROS_SERIALIZATIONS or info.msgtype not in DECODABLE:
                details[name] = f"({info.serialization or 'no encoding'}; copied, not decoded)"
        for raw in first_messages(reader, described):
            details[raw.topic] = describe(reader, raw)
    else:
        with progress_bar(total=reader.message_count, unit="msg", desc="read",
                          progress=progress) as bar:
            for raw in reader.raw_messages():
                bar.update()
                topic = raw.topic
                counts[topic] = counts.get(topic, 0) + 1
                if topic not in first_ns:
                    first_ns[topic] = raw.log_time_ns
                    detail = _detail(reader, raw)
                    if detail is not None:
                        details[topic] = detail
                last_ns[topic] = raw.log_time_ns
                if check is not None and raw.msgtype in FRAME_TYPES:
                    check(reader, raw)
    msgtypes = {name: info.msgtype for name, info in reader.topics.items()}
    topics = tuple(
        TopicSummary(
            name=name,
            msgtype=msgtype,
            count=counts.get(name, 0),
            first_ns=first_ns.get(name),
            last_ns=last_ns.get(name),
            detail=details.get(name, ""),
        )
        for name, msgtype in sorted(msgtypes.items())
    )
    return LogSummary(
        path=reader.path,
        format_name=reader.format_name,
        size_bytes=size_on_disk(reader.path),
        start_ns=min(first_ns.values(), default=None),
        end_ns=max(last_ns.values(), default=None),
        message_count=sum(counts.values()),
        topics=topics,
        warnings=tuple(reader.warnings) + (() if check is None else check.result.warnings),
        frames=None if check is None else check.result,
    )


def first_messages(reader: LogReader, first_ns: dict[str, int]) -> Iterator[RawMessage]:
    """The first message of each topic of ``first_ns`` (topic -> its first log time, from
    the index). Topics that begin within :data:`FIRST_MESSAGES_WINDOW_NS` of each other are
    read in one pass over that stretch of the log, so that a chunk holding the first
    messages of several topics (the cameras of a rig) is read once."""
    pending = sorted(first_ns, key=lambda topic: first_ns[topic])
    while pending:
        start_ns = first_ns[pending[0]]
        group = [t for t in pending if first_ns[t] - start_ns <= FIRST_MESSAGES_WINDOW_NS]
        pending = pending[len(group):]
        wanted = set(group)
        end_ns = first_ns[group[-1]] + 1
        for raw in reader.raw_messages(group, start_ns, end_ns):
            if raw.topic in wanted:
                wanted.discard(raw.topic)
                yield raw
                if not wanted:
                    break


class _FrameChecker:
    """Decodes the image messages of a log in order, one stream per topic, counting the
    frames that do not decode."""

    def __init__(self) -> None:
        self._streams: dict[str, FrameStream] = {}
        self.frames = 0
        self.undecodable: dict[str, int] = {}

    def __call__(self, reader: LogReader, raw: RawMessage) -> None:
        from replay.frames import FrameStream

        self.frames += 1
        stream = self._streams.setdefault(raw.topic, FrameStream())
        try:
            frame = stream.decode(reader.decode(raw))
        except ReplayError:
            frame = None
        if frame is None:  # video: a picture before the stream's first keyframe
            self.undecodable[raw.topic] = self.undecodable.get(raw.topic, 0) + 1

    @property
    def result(self) -> FrameCheck:
        """What was found so far."""
        return FrameCheck(self.frames, dict(self.undecodable))


def _detail(reader: LogReader, raw: RawMessage) -> str | None:
    """The detail column of a topic from its first message (None: nothing to say)."""
    if raw.msgtype in DESCRIBED_TYPES:
        return describe(reader, raw)
    if raw.serialization not in ROS_SERIALIZATIONS or raw.msgtype not in DECODABLE:
        return f"({raw.serialization or 'no encoding'}; copied, not decoded)"
    return None


def describe(reader: LogReader, raw: RawMessage) -> str:
    """Encoding and size of an image / video / camera-info message, or why it cannot be
    decoded (Foxglove channels name their message encoding too)."""
    return _describe_by_schema(raw) or _describe_decoded(reader, raw)


def _describe_decoded(reader: LogReader, raw: RawMessage) -> str:
    """:func:`describe` through the reader's own decode (every format and schema)."""
    from replay.frames import FrameStream
    from replay.messages import CameraInfo, CompressedImage, CompressedVideo, Image

    where = "" if raw.serialization in ROS_SERIALIZATIONS else f" ({raw.serialization})"
    try:
        message = reader.decode(raw)
        match message:
            case Image():
                return f"{message.encoding} {message.width}x{message.height}{where}"
            case CompressedImage():
                frame = FrameStream().decode(message)
                assert frame is not None
                return f"{message.format} {frame.width}x{frame.height}{where}"
            case CompressedVideo():
                frame = FrameStream().decode(message)
                size = "" if frame is None else f" {frame.width}x{frame.height}"
                return f"{message.format}{size}{where}"
            case CameraInfo():
                return f"{message.width}x{message.height} {message.distortion_model}{where}"
    except ReplayError as err:
        return f"(cannot decode: {err})"
    return ""


def _describe_by_schema(raw: RawMessage) -> str | None:
    """The description of a CDR image or camera info decoded with the ``ros2msg`` definition
    its MCAP schema carries (``mcap_ros2``), which spares building rosbags' whole ROS 2
    typestore for one message; None where there is no such schema or that decode fails (the
    reader's own decode then says why)."""
    schema = raw.schema
    if (raw.serialization != CDR or schema is None or schema.encoding != "ros2msg"
            or raw.msgtype not in (IMAGE, CAMERA_INFO)):
        return None
    from mcap_ros2.decoder import DecoderFactory

    try:
        # its parser prints a damaged definition's line on stderr before raising
        with contextlib.redirect_stderr(io.StringIO()):
            decode = DecoderFactory().decoder_for(CDR, schema)
        msg = decode(bytes(raw.data)) if decode is not None else None
        if msg is None:
            return None
        if raw.msgtype == CAMERA_INFO:
            return f"{int(msg.width)}x{int(msg.height)} {msg.distortion_model}"
        encoding, width, height = str(msg.encoding), int(msg.width), int(msg.height)
        check_buffer(encoding, width=width, height=height, step=int(msg.step),
                     size=len(msg.data))
    except Exception:  # any failure of this shortcut: the full decode reports it
        return None
    return f"{encoding} {width}x{height}"


def size_on_disk(path: Path | str) -> int:
    """Bytes of a file, or of all files below a directory (local or a URI)."""
    if isinstance(path, str):
        return storage.size(path)
    return bytes_on_disk(path)


def _frames_line(check: FrameCheck | None) -> str:
    """What the summary says about the image frames' decoding."""
    if check is None:
        return "not decoded (--verify decodes every one)"
    bad = sum(check.undecodable.values())
    if not bad:
        return f"all {check.frames} decoded"
    return f"{check.frames - bad} of {check.frames} decoded, {bad} did not (see the warnings)"


def format_stamp(stamp_ns: int | None) -> str:
    """``2019-03-21T14:57:04.368061647Z (1553180224368061647 ns)``; ``-`` for None."""
    if stamp_ns is None:
        return "-"
    sec, nsec = divmod(stamp_ns, 1_000_000_000)
    iso = datetime.fromtimestamp(sec, tz=UTC).strftime("%Y-%m-%dT%H:%M:%S")
    return f"{iso}.{nsec:09d}Z ({stamp_ns} ns)"


def format_summary(summary: LogSummary) -> str:
    """Human-readable multi-line text of a summary (no trailing newline)."""
    lines = [
        f"path:      {summary.path}",
        f"format:    {summary.format_name}",
        f"size:      {format_size(summary.size_bytes)}",
        f"start:     {format_stamp(summary.start_ns)}",
        f"end:       {format_stamp(summary.end_ns)}",
        f"duration:  {summary.duration_s:.3f} s",
        f"messages:  {summary.message_count}",
        f"topics:    {len(summary.topics)}",
    ]
    if any(topic.msgtype in FRAME_TYPES for topic in summary.topics):
        lines.append(f"frames:    {_frames_line(summary.frames)}")
    rows = [("topic", "type", "count", "rate_hz", "detail")]
    for topic in summary.topics:
        rate = "" if topic.rate_hz is None else f"{topic.rate_hz:.2f}"
        rows.append((topic.name, topic.msgtype or "(no schema)", str(topic.count), rate,
                     topic.detail))
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    for row in rows:
        cells = [
            row[0].ljust(widths[0]),
            row[1].ljust(widths[1]),
            row[2].rjust(widths[2]),
            row[3].rjust(widths[3]),
            row[4],
        ]
        lines.append(("  " + "  ".join(cells)).rstrip())
    lines.extend(f"warning: {warning}" for warning in summary.warnings)
    return "\n".join(lines)


@dataclass(frozen=True)
class InfoReport:
    """What ``camlog info`` says: its text (the summary, or a folder's unfinished outputs)
    and what is wrong with the log (damage, recovery, unfinished outputs beside it)."""

    text: str
    warnings: tuple[str, ...] = ()


def describe_log(request: InfoRequest) -> InfoReport:
    """The summary of the request's log; for a folder that is not a log, the temporary
    outputs unfinished camlog runs left in it."""
    from replay.errors import LogFormatError
    from replay.formats import detect_format, open_reader
    from replay.leftovers import describe_leftovers, format_leftovers, leftovers_in, leftovers_of

    log = Path(request.log)
    if log.is_dir():
        try:
            detect_format(log)
        except LogFormatError as err:
            leftovers = leftovers_in(log)
            if not leftovers:
                raise LogFormatError(f"{err}, and holds no output an unfinished camlog run "
                                     "left") from None
            return InfoReport(format_leftovers(log, leftovers))
    with open_reader(log, recover=request.recover) as reader:
        summary = summarize(reader, verify=request.verify, progress=request.progress)
    inside = leftovers_in(log) if log.is_dir() else []
    return InfoReport(format_summary(dataclasses.replace(summary, warnings=())),
                      (*summary.warnings, *describe_leftovers(inside + leftovers_of(log))))

"""The interface every log format implements."""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Self

from ..atomic import AtomicOutput
from ..errors import LogWriteError, ReplayError, TopicError
from ..msgtypes import CDR, FRAME_TYPES, PROTOBUF, ROS1

if TYPE_CHECKING:
    from mcap.records import Schema

    from ..frames import Frame
    from ..messages import Message
    from ..wire import Decoder

# The typed records, their pixels and their serialization (numpy, rosbags) are imported by
# the methods that decode or encode, so that opening a log and reading its index does not
# load them.

#: serializations every format can hold (others, e.g. protobuf or JSON, only MCAP)
ROS_SERIALIZATIONS = frozenset({CDR, ROS1})


@dataclass(frozen=True, slots=True)
class TopicInfo:
    """One topic of a log: ROS 2 type name, message count, wire serialization."""

    name: str
    msgtype: str
    count: int
    serialization: str
    msgdef: str = ""


@dataclass(frozen=True, slots=True)
class RawMessage:
    """A serialized message as stored: ``serialization`` is the channel's message encoding
    (``cdr``, ``ros1``, ``protobuf``, ``json``...), ``schema`` its schema record where the
    format keeps one (MCAP)."""

    topic: str
    msgtype: str
    log_time_ns: int
    data: bytes | memoryview
    serialization: str
    schema: Schema | None = None


@dataclass(frozen=True, slots=True)
class Record:
    """A decoded message with the topic and log time it was stored under."""

    topic: str
    log_time_ns: int
    message: Message


@dataclass(frozen=True, slots=True)
class FrameRecord:
    """A decoded camera frame with the topic and log time its message was stored under."""

    topic: str
    log_time_ns: int
    message: Frame


class LogReader:
    """Streaming reader; subclasses implement :meth:`raw_messages` and fill the fields.

    Time ranges are half-open: ``start_ns <= log_time < end_ns``.
    """

    format_name: str = ""

    def __init__(self, path: Path | str) -> None:
        self.path = path  # a string only for a URI (object storage)
        self.topics: dict[str, TopicInfo] = {}
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self.message_count = 0
        self.metadata: dict[str, dict[str, str]] = {}
        self.warnings: list[str] = []
        self._decoders: dict[tuple[str, str, str], Decoder] = {}

    def raw_messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[RawMessage]:
        """Serialized messages in log-time order, filtered by topic and time."""
        raise NotImplementedError

    def topic_spans(self) -> dict[str, tuple[int, int]] | None:
        """Topic -> (first, last) log time in ns, when the log's index tells them without
        reading the messages (None: it does not)."""
        return None

    def schema(self, raw: RawMessage) -> Schema | None:
        """The schema record a raw message's channel was written with (formats without
        schema records: the ROS type's name, whose definition the typestore knows)."""
        if raw.schema is not None:
            return raw.schema
        from ..wire import ros_schema

        return ros_schema(raw.msgtype, raw.serialization)

    def decode(self, raw: RawMessage) -> Message:
        """Typed record of a raw message; errors name the log and topic."""
        key = (raw.topic, raw.msgtype, raw.serialization)
        try:
            decoder = self._decoders.get(key)
            if decoder is None:
                from ..wire import decoder_for

                decoder = self._decoders[key] = decoder_for(raw.serialization, self.schema(raw))
            return decoder(raw.data)
        except ReplayError as err:
            raise type(err)(f"{self.path}: topic {raw.topic}: {err}") from None

    def messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[Record]:
        """Decoded messages in log-time order (topics must have camlog record types)."""
        for raw in self.raw_messages(topics, start_ns, end_ns):
            yield Record(raw.topic, raw.log_time_ns, self.decode(raw))

    def frames(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
        *,
        skipped: dict[str, int] | None = None,
    ) -> Iterator[FrameRecord]:
        """Decoded camera frames of ``topics`` (default: every image and video topic).

        With ``skipped``, a frame that does not decode is counted there (topic -> count)
        instead of raising."""
        from ..frames import FrameStream
        from ..messages import CompressedImage, CompressedVideo, Image

        if topics is None:
            topics = [t.name for t in self.topics.values() if t.msgtype in FRAME_TYPES]
        streams: dict[str, FrameStream] = {}
        for raw in self.raw_messages(topics, start_ns, end_ns):
            stream = streams.get(raw.topic)
            if stream is None:
                stream = streams[raw.topic] = FrameStream()
            message = self.decode(raw)
            if not isinstance(message, Image | CompressedImage | CompressedVideo):
                raise TopicError(f"{self.path}: topic {raw.topic} holds {raw.msgtype}, "
                                 "not images")
            try:
                frame = stream.decode(message)
            except ReplayError as err:
                if skipped is None:
                    raise type(err)(f"{self.path}: topic {raw.topic}: {err}") from None
                skipped[raw.topic] = skipped.get(raw.topic, 0) + 1
                continue
            if frame is not None:
                yield FrameRecord(raw.topic, raw.log_time_ns, frame)

    def close(self) -> None:
        """Release file handles."""

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, et: type[BaseException] | None, ev: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


def is_rosbag2_dir(path: Path) -> bool:
    """Whether a directory is a rosbag2 log (holds ``metadata.yaml``)."""
    return (path / "metadata.yaml").is_file()


#: a live writer (``live=True``: recording, playing) hands what it holds to the OS at least
#: this often while messages arrive, so a process killed mid-way loses at most the last
#: second of messages
FLUSH_INTERVAL_S = 0.5


class KeptOnSuccess:
    """An output as a context manager: :meth:`close` (finish and keep it) when the block
    ends without an exception, :meth:`abort` (drop it) otherwise."""

    def close(self) -> None:
        """Finish the output and move it to its final name."""
        raise NotImplementedError

    def abort(self) -> None:
        """Drop the partial output."""
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, et: type[BaseException] | None, ev: BaseException | None, tb: TracebackType | None
    ) -> None:
        if et is None:
            self.close()
        else:
            self.abort()


class LogWriter(KeptOnSuccess):
    """Writer base: typed messages are serialized here, formats store raw bytes.

    Use as a context manager: the output appears under its final name only when the block
    ends without an exception; otherwise the temporary output is removed. ``inputs`` are the
    logs the output is made from: an output that is one of them (or lies inside one) is
    refused.
    Chunks (SQLite transactions) are completed by size, so the same messages always give
    the same bytes. A live writer (:attr:`live`: messages arrive as they happen, as in a
    recording) also completes one at least every :data:`FLUSH_INTERVAL_S`, so the temporary
    output of a killed process holds all but its last moments.
    """

    format_name: str = ""
    serialization: str = ""
    #: message encodings the format can store besides CDR and ROS1
    other_serializations: frozenset[str] = frozenset()
    #: ``ros2``, or ``foxglove``: camera records in Foxglove's schemas (MCAP)
    profile: str = "ros2"
    #: what the output is compressed with, for reports (e.g. "zstd chunks")
    compression: str = "none"
    #: flush at least every :data:`FLUSH_INTERVAL_S` (see the class docstring)
    live: bool = False

    def __init__(self, path: Path, *, overwrite: bool = False,
                 inputs: Iterable[Path] = ()) -> None:
        self.path = path
        # a rosbag2 storage file stands for its directory: the output may not enter it
        inputs = [*(given := [Path(p) for p in inputs]),
                  *(p.parent for p in given if p.is_file() and is_rosbag2_dir(p.parent))]
        self._atomic = AtomicOutput(path, overwrite=overwrite, inputs=inputs,
                                    replaceable_dir=is_rosbag2_dir, what="a rosbag2 log")
        self._types: dict[str, str] = {}
        self.closed = False
        self.warnings: list[str] = []  # channels the format cannot hold, left out
        self._left_out: set[str] = set()
        self._flushed_at = time.monotonic()

    @property
    def temp_path(self) -> Path:
        """Where the output is written until it is committed."""
        return self._atomic.temp

    def write(self, topic: str, message: Message, *, log_time_ns: int | None = None) -> None:
        """Serialize and store a typed record; log time defaults to its header stamp."""
        if log_time_ns is None:
            stamp = getattr(message, "stamp_ns", None)
            if stamp is None:
                raise LogWriteError(f"{topic}: {type(message).__name__} needs log_time_ns")
            log_time_ns = stamp
        from ..wire import foxglove_schema, msgtype_of, serialize, to_foxglove

        if self.writes_foxglove(message):
            proto = to_foxglove(message)
            schema = foxglove_schema(proto)
            self.write_raw(RawMessage(topic, schema.name, log_time_ns, proto.SerializeToString(),
                                      PROTOBUF, schema))
            return
        msgtype = msgtype_of(message)
        self._check_type(topic, msgtype)
        self._store(RawMessage(topic, msgtype, log_time_ns,
                               serialize(message, self.serialization), self.serialization), "")

    def writes_foxglove(self, message: Message) -> bool:
        """Whether a record is stored with its Foxglove schema: video (it has no ROS type),
        and every camera record under the ``foxglove`` profile (MCAP)."""
        from ..messages import CameraInfo, CompressedImage, CompressedVideo, Image
        from ..wire import msgtype_of

        if self.profile == "foxglove" and isinstance(
                message, Image | CompressedImage | CompressedVideo | CameraInfo):
            return True
        return msgtype_of(message).startswith("foxglove.")

    def write_raw(self, raw: RawMessage, *, msgdef: str = "") -> None:
        """Store a raw message, converting between CDR and ROS1 when the formats differ.

        A channel in a serialization the format cannot hold (protobuf or JSON outside MCAP)
        is left out, with one warning per topic."""
        if raw.serialization not in ROS_SERIALIZATIONS:
            if raw.serialization not in self.other_serializations:
                if raw.topic not in self._left_out:
                    self._left_out.add(raw.topic)
                    self.warnings.append(f"{raw.topic} ({raw.msgtype or 'no schema'}, "
                                         f"{raw.serialization}) left out: {self.format_name} "
                                         "holds ROS messages only; write MCAP to keep it")
                return
            self._check_type(raw.topic, raw.msgtype)
            self._store(raw, "")
            return
        self._check_type(raw.topic, raw.msgtype)
        if raw.serialization != self.serialization:
            from ..wire import convert_serialization

            data = convert_serialization(raw.data, raw.msgtype, raw.serialization,
                                         self.serialization)
            raw = RawMessage(raw.topic, raw.msgtype, raw.log_time_ns, data, self.serialization)
            msgdef = ""
        self._store(raw, msgdef)

    def _store(self, raw: RawMessage, msgdef: str) -> None:
        """Hand one message to the format, flushing when due; OS errors name the output."""
        if self.closed:
            raise LogWriteError(f"{self.path} is closed")
        try:
            self._write(raw, msgdef)
            if self.live:
                now = time.monotonic()
                if now - self._flushed_at >= FLUSH_INTERVAL_S:
                    self._flush()
                    self._flushed_at = now
        except OSError as err:
            raise LogWriteError(f"cannot write {self.path}: {err.strerror or err}") from None

    def flush(self) -> None:
        """Complete the chunk in progress and hand everything written so far to the OS."""
        try:
            self._flush()
        except OSError as err:
            raise LogWriteError(f"cannot write {self.path}: {err.strerror or err}") from None
        self._flushed_at = time.monotonic()

    def set_metadata(self, name: str, values: dict[str, str]) -> None:
        """Attach named string metadata where the format can hold it."""

    def _check_type(self, topic: str, msgtype: str) -> None:
        known = self._types.setdefault(topic, msgtype)
        if known != msgtype:
            raise LogWriteError(f"{self.path}: topic {topic} has type {known}, not {msgtype}")

    def _write(self, raw: RawMessage, msgdef: str) -> None:
        """Store one message of the writer's serialization (or one it holds besides)."""
        raise NotImplementedError

    def _flush(self) -> None:
        """Complete the open chunk (or transaction) and write it through to the OS."""
        raise NotImplementedError

    def _finish(self) -> None:
        raise NotImplementedError

    def _commit(self) -> None:
        """Move the finished output to its final name."""
        self._atomic.commit()

    def _abort(self) -> None:
        """Release handles without finishing the file."""

    def close(self) -> None:
        """Finish the file and move it to its final name."""
        if self.closed:
            return
        self.closed = True
        try:
            self._finish()
            self._commit()
        except OSError as err:
            self._atomic.discard()
            raise LogWriteError(f"cannot write {self.path}: {err.strerror or err}") from None
        except BaseException:  # e.g. SQLite's disk I/O error: nothing half-written stays
            self._atomic.discard()
            raise

    def abort(self) -> None:
        """Drop the partial output."""
        if self.closed:
            return
        self.closed = True
        try:
            self._abort()
        except OSError:
            pass  # e.g. flushing a buffer to a full disk: the output is dropped anyway
        finally:
            self._atomic.discard()



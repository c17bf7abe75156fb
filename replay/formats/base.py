"""The interface every log format implements."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Self

from ..atomic import AtomicOutput
from ..codec import decode_compressed, deserialize, msgtype_of, serialize
from ..errors import LogWriteError, ReplayError, TopicError
from ..messages import MSGTYPES, CompressedImage, Image, Message

IMAGE_TYPES = frozenset({MSGTYPES[Image], MSGTYPES[CompressedImage]})


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
    """A serialized message as stored: bytes are CDR or ROS1 per ``serialization``."""

    topic: str
    msgtype: str
    log_time_ns: int
    data: bytes | memoryview
    serialization: str


@dataclass(frozen=True, slots=True)
class Record:
    """A decoded message with the topic and log time it was stored under."""

    topic: str
    log_time_ns: int
    message: Message


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

    def decode(self, raw: RawMessage) -> Message:
        """Typed record of a raw message; errors name the log and topic."""
        try:
            return deserialize(raw.data, raw.msgtype, raw.serialization)
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

    def images(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[Record]:
        """Image records of ``topics`` (default: every image topic), JPEG/PNG decoded."""
        if topics is None:
            topics = [t.name for t in self.topics.values() if t.msgtype in IMAGE_TYPES]
        for raw in self.raw_messages(topics, start_ns, end_ns):
            message = self.decode(raw)
            if isinstance(message, CompressedImage):
                try:
                    message = decode_compressed(message)
                except ReplayError as err:
                    raise type(err)(f"{self.path}: topic {raw.topic}: {err}") from None
            if not isinstance(message, Image):
                raise TopicError(f"{self.path}: topic {raw.topic} holds {raw.msgtype}, not images")
            yield Record(raw.topic, raw.log_time_ns, message)

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


class LogWriter:
    """Writer base: typed messages are serialized here, formats store raw bytes.

    Use as a context manager: the output appears under its final name only when the block
    ends without an exception; otherwise the temporary output is removed. ``inputs`` are the
    logs the output is made from: an output that is one of them (or lies inside one) is
    refused.
    """

    format_name: str = ""
    serialization: str = ""

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
        msgtype = msgtype_of(message)
        self._check_type(topic, msgtype)
        self._write(topic, msgtype, log_time_ns, serialize(message, self.serialization), "")

    def write_raw(self, raw: RawMessage, *, msgdef: str = "") -> None:
        """Store a raw message, converting between CDR and ROS1 when the formats differ."""
        from ..codec import convert_serialization

        self._check_type(raw.topic, raw.msgtype)
        data = raw.data
        if raw.serialization != self.serialization:
            data = convert_serialization(data, raw.msgtype, raw.serialization, self.serialization)
            msgdef = ""
        self._write(raw.topic, raw.msgtype, raw.log_time_ns, data, msgdef)

    def set_metadata(self, name: str, values: dict[str, str]) -> None:
        """Attach named string metadata where the format can hold it."""

    def _check_type(self, topic: str, msgtype: str) -> None:
        known = self._types.setdefault(topic, msgtype)
        if known != msgtype:
            raise LogWriteError(f"{self.path}: topic {topic} has type {known}, not {msgtype}")

    def _write(
        self, topic: str, msgtype: str, log_time_ns: int, data: bytes | memoryview, msgdef: str
    ) -> None:
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

    def abort(self) -> None:
        """Drop the partial output."""
        if self.closed:
            return
        self.closed = True
        try:
            self._abort()
        finally:
            self._atomic.discard()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, et: type[BaseException] | None, ev: BaseException | None, tb: TracebackType | None
    ) -> None:
        if et is None:
            self.close()
        else:
            self.abort()


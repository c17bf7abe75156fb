"""Reading through a ``rosbags`` reader object, shared by the rosbag2 and ROS1 readers.

Everything ``rosbags`` raises while opening or reading — its ReaderError, OS and SQLite
errors, and TypeError or KeyError on a metadata.yaml whose values have the wrong types —
becomes one :class:`~replay.errors.LogReadError` line here.
"""

from __future__ import annotations

import contextlib
import traceback
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import zstandard

from ..errors import LogReadError
from ..wire import CDR
from .base import LogReader, RawMessage, TopicInfo

__all__ = ["MAX_MESSAGE_BYTES", "RosbagsReader", "as_count", "check_connection", "first_line"]

#: a compressed message may state at most this size (a damaged frame header claims anything)
MAX_MESSAGE_BYTES = 1 << 30


class RosbagsReader(LogReader):
    """Shared reading over a rosbags reader object."""

    serialization = CDR
    #: appended to read errors: how ``--recover`` would help (empty when it would not)
    recover_hint = ""

    def __init__(self, path: Path, reader: Any) -> None:
        super().__init__(path)
        self._reader = reader
        self._decompress = False  # zstd per message that rosbags does not know about
        try:
            reader.open()
            self._load(reader)
        except Exception as err:
            # rosbags raises ReaderError, OSError, sqlite errors, and TypeError or KeyError
            # on a metadata.yaml whose values have the wrong types: one place maps them all
            with contextlib.suppress(Exception):
                reader.close()
            raise LogReadError(f"cannot read {path}: {first_line(err)}{self.recover_hint}") \
                from None

    def _load(self, reader: Any) -> None:
        """Topics, counts and times from the opened rosbags reader."""
        counts: dict[str, int] = {}
        self._by_topic: dict[str, list[Any]] = {}
        for conn in reader.connections:
            check_connection(conn)
            counts[conn.topic] = counts.get(conn.topic, 0) + conn.msgcount
            self._by_topic.setdefault(conn.topic, []).append(conn)
        for topic, conns in self._by_topic.items():
            msgdef = getattr(conns[0].msgdef, "data", "") or ""
            self.topics[topic] = TopicInfo(
                topic, conns[0].msgtype, counts[topic], self.serialization, str(msgdef)
            )
        self.message_count = as_count(reader.message_count, "message count")
        if self.message_count:
            self.start_ns = as_count(reader.start_time, "start time")
            # rosbags' end_time lies one nanosecond after the last message
            self.end_ns = max(as_count(reader.end_time, "end time") - 1, self.start_ns)

    def raw_messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[RawMessage]:
        conns = (
            list(self._reader.connections)
            if topics is None
            else [c for t in topics for c in self._by_topic.get(t, [])]
        )
        if not conns:
            return
        try:
            for conn, timestamp, data in self._reader.messages(
                connections=conns, start=start_ns, stop=end_ns
            ):
                payload = _decompressed(data) if self._decompress else data
                yield RawMessage(conn.topic, conn.msgtype, timestamp, payload, self.serialization)
        except Exception as err:
            raise LogReadError(f"cannot read {self.path}: {first_line(err)}"
                               f"{self.recover_hint}") from None

    def close(self) -> None:
        self._reader.close()


def check_connection(conn: Any) -> None:
    """Raise TypeError when a connection's fields (from metadata.yaml or a bag's index) do
    not have the types the format gives them."""
    if not isinstance(conn.topic, str) or not conn.topic:
        raise TypeError(f"a topic name is {conn.topic!r}, not a name")
    if not isinstance(conn.msgtype, str):
        raise TypeError(f"topic {conn.topic}: its type is {conn.msgtype!r}, not a type name")
    as_count(conn.msgcount, f"topic {conn.topic}: message count")


def as_count(value: Any, what: str) -> int:
    """A count or time the format stores as a non-negative integer (TypeError if not)."""
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        raise TypeError(f"{what} is {value!r}, not a non-negative integer")
    return value


def _decompressed(data: bytes) -> bytes:
    """A message of rosbag2's per-message zstd compression, decompressed; a frame that
    states more than :data:`MAX_MESSAGE_BYTES` is damage, not allocated."""
    stated = zstandard.frame_content_size(data)
    if stated > MAX_MESSAGE_BYTES:
        raise ValueError(f"a compressed message states {stated} bytes")
    return zstandard.ZstdDecompressor().decompress(data)


def first_line(err: BaseException) -> str:
    """The first line of an error's message; for a bare one (rosbags' ``assert`` checks of
    a damaged index or record), what kind of check failed and where."""
    text = str(err).strip()
    if text:
        return text.splitlines()[0]
    frames = traceback.extract_tb(err.__traceback__)
    where = f" in {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else ""
    return f"malformed data ({type(err).__name__}{where})"

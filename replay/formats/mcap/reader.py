"""MCAP files with ROS 2 (CDR) or ROS1 messages, through the ``mcap`` package.

Files are written chunked and zstd-compressed with a summary section so that rerun,
Foxglove and ``ros2 bag`` open them (:mod:`.writer`). A file without summary (a
recording that was killed) is read by streaming through its records up to the last complete
chunk; with ``recover``, past damaged chunks too. A chunk written twice is read once.
"""

from __future__ import annotations

import heapq
import inspect
import struct
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any, cast

import zstandard
from mcap.exceptions import McapError
from mcap.reader import SeekingReader
from mcap.records import Channel, Chunk, DataEnd, Footer, Message, MessageIndex, Schema
from mcap.stream_reader import StreamReader, breakup_chunk

from ...errors import LogReadError
from ...msgtypes import CDR, ROS1, normalize_msgtype
from ..base import LogReader, RawMessage, TopicInfo
from ..bounded_file import BoundedFile
from .checks import check_chunk_size, summary_problem
from .index import channel_spans
from .ordered import chunk_messages, ordered_chunks

MAGIC = b"\x89MCAP0\r\n"
ENCODINGS = {"cdr": CDR, "ros1": ROS1}
#: names of mcap's half-open time bounds (newer mcap deprecates start_time / end_time)
_TIME_BOUNDS = (
    ("starting_at", "ending_before")
    if "starting_at" in inspect.signature(SeekingReader.iter_messages).parameters
    else ("start_time", "end_time")
)
#: exceptions that mean "the bytes ran out or are not MCAP" while streaming
_DAMAGE = (
    McapError,
    zstandard.ZstdError,
    EOFError,
    struct.error,
    ValueError,
    MemoryError,
    OverflowError,
    RuntimeError,  # lz4
    IndexError,
    KeyError,
)


def is_mcap(path: Path) -> bool:
    """True if ``path`` is a file starting with the MCAP magic."""
    try:
        with path.open("rb") as f:
            return f.read(len(MAGIC)) == MAGIC
    except OSError:
        return False


class McapLogReader(LogReader):
    """Reader for one MCAP file; ``recover`` reads everything before damage."""

    format_name = "mcap"

    def __init__(
        self, path: Path | str, *, file: IO[bytes] | None = None, recover: bool = False
    ) -> None:
        """Open ``path``; or read ``file`` — any seekable binary file, such as an fsspec file
        on object storage read with range requests — which ``path`` then only names. The
        reader closes the file."""
        super().__init__(path)
        if file is None:
            try:
                file = Path(path).open("rb")  # noqa: SIM115 (the reader owns it)
            except OSError as err:
                raise LogReadError(f"cannot open {path}: {err.strerror}") from None
        try:
            # a damaged length field cannot make the mcap library allocate past the file
            bounded = BoundedFile(file)
        except OSError as err:
            file.close()
            raise LogReadError(f"cannot read {path}: {err.strerror or err}") from None
        self._file = cast(IO[bytes], bounded)  # it has what the mcap library uses of IO
        self._file_size = bounded.size
        self._recover = recover
        self._summary: Any = None
        self._valid_until: int | None = None  # streaming: stop before this byte offset
        # id -> topic, msgtype, encoding, schema
        self._channels: dict[int, tuple[str, str, str, Schema | None]] = {}
        self._seeker: SeekingReader | None = None
        try:
            self._open()
        except BaseException:
            self._file.close()
            raise

    def _open(self) -> None:
        if self._file.read(len(MAGIC)) != MAGIC:
            raise LogReadError(f"{self.path} is not an MCAP file (bad magic)")
        summary = None
        if not self._recover:
            try:
                summary = self._seeking_reader().get_summary()
            except (*_DAMAGE, OSError):  # OSError: too short to seek to a footer
                summary = self._seeker = None
        problem = None if summary is None else summary_problem(summary, self._file_size)
        if problem is not None:
            self.warnings.append(f"{self.path}: its summary {problem}; reading the whole file "
                                 "instead")
            summary = self._seeker = None
        if summary is not None and summary.chunk_indexes and summary.statistics is not None:
            self._summary = summary
            self._load_summary(summary)
        else:
            self._scan()
        for name, meta in self._iter_metadata():
            self.metadata[name] = meta

    def _iter_metadata(self) -> Iterator[tuple[str, dict[str, str]]]:
        if self._summary is None:
            return iter(())
        try:
            reader = self._seeking_reader()
            return iter([(m.name, dict(m.metadata)) for m in reader.iter_metadata()])
        except _DAMAGE:
            return iter(())

    def _seeking_reader(self) -> SeekingReader:
        # one instance: it caches the summary, which each new instance would read again
        if self._seeker is None:
            self._file.seek(0)  # SeekingReader checks the magic at the current position
            self._seeker = SeekingReader(self._file, validate_crcs=True)
        return self._seeker

    def _add_channel(self, channel: Channel, schemas: dict[int, Schema]) -> None:
        schema = schemas.get(channel.schema_id)
        msgtype = normalize_msgtype(schema.name) if schema else ""
        encoding = ENCODINGS.get(channel.message_encoding, channel.message_encoding)
        self._channels[channel.id] = (channel.topic, msgtype, encoding, schema)
        msgdef = schema.data.decode(errors="replace") if schema else ""
        if channel.topic not in self.topics:
            self.topics[channel.topic] = TopicInfo(channel.topic, msgtype, 0, encoding, msgdef)

    def _load_summary(self, summary: Any) -> None:
        for channel in summary.channels.values():
            self._add_channel(channel, summary.schemas)
        counts: dict[str, int] = {}
        for cid, count in summary.statistics.channel_message_counts.items():
            topic = self._channels[cid][0]
            counts[topic] = counts.get(topic, 0) + count
        for topic, info in self.topics.items():
            self.topics[topic] = _with_count(info, counts.get(topic, 0))
        self.message_count = summary.statistics.message_count
        if self.message_count:
            self.start_ns = summary.statistics.message_start_time
            self.end_ns = summary.statistics.message_end_time

    def _scan(self) -> None:
        """Stream the whole file once to learn topics, counts and where damage begins."""
        counts: dict[str, int] = {}
        start = end = None
        for message in self._stream_messages(learn=True):
            topic = self._channels[message.channel_id][0]
            counts[topic] = counts.get(topic, 0) + 1
            start = message.log_time if start is None else min(start, message.log_time)
            end = message.log_time if end is None else max(end, message.log_time)
        for topic, info in self.topics.items():
            self.topics[topic] = _with_count(info, counts.get(topic, 0))
        self.message_count = sum(counts.values())
        self.start_ns, self.end_ns = start, end

    def _stream_messages(self, *, learn: bool = False) -> Iterator[Message]:
        """Messages in file order (sorted within each chunk), stopping at damage."""
        self._file.seek(0)
        # emit_chunks: whole chunks, so that damage is found per chunk and offsets are exact
        stream = StreamReader(self._file, skip_magic=False, emit_chunks=True, validate_crcs=True)
        schemas: dict[int, Schema] = {}
        records = stream.records
        offset = len(MAGIC)
        seen: set[tuple[int, int, int, int, int]] = set()  # chunks read: a repeat is skipped
        lost: list[int] | None = None  # [messages] of a damaged chunk, from its indexes
        orphans = 0  # messages of channels no channel record declared
        while True:
            if self._valid_until is not None and not learn and offset >= self._valid_until:
                return
            try:
                record = next(records)
            except StopIteration:
                if learn:
                    self._note_damage(offset, "file ends before its footer", truncated=True)
                    self._note_orphans(orphans)
                return
            except _DAMAGE as err:
                if learn:
                    # a record that runs into the end of the file was cut, not corrupted
                    size = self._size()
                    at_end = self._file.tell() >= size
                    why = _describe(err)
                    if at_end:
                        cut = offset < size
                        why = "file ends inside a record" if cut else "file ends before its footer"
                    self._note_damage(offset, why, truncated=at_end)
                    self._note_orphans(orphans)
                return
            start, offset = offset, self._file.tell()
            if isinstance(record, MessageIndex):
                if lost is not None:
                    lost[0] += len(record.records)
                continue
            if lost is not None and learn:
                self.warnings[-1] = self.warnings[-1].replace("? messages", f"{lost[0]} messages")
            lost = None
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                if learn:
                    self._add_channel(record, schemas)
            elif isinstance(record, Chunk):
                key = (record.message_start_time, record.message_end_time,
                       record.uncompressed_size, record.uncompressed_crc, len(record.data))
                if key in seen:
                    if learn:
                        self.warnings.append(f"{self.path}: the chunk at byte {start} repeats "
                                             "an earlier one; read once")
                    continue
                seen.add(key)
                try:
                    check_chunk_size(record)
                    inner = list(breakup_chunk(record, validate_crc=True))
                except _DAMAGE as err:
                    if not self._recover:
                        if learn:
                            self._note_damage(offset, _describe(err), truncated=False)
                        return
                    lost = [0]  # resynchronise: the next record starts after this chunk
                    if learn:
                        self.warnings.append(
                            f"{self.path}: skipped the damaged chunk at byte {start} "
                            f"({_describe(err)}): ? messages lost, log times "
                            f"{record.message_start_time} to {record.message_end_time} ns")
                    continue
                for sub in inner:
                    if isinstance(sub, Schema):
                        schemas[sub.id] = sub
                    elif isinstance(sub, Channel) and learn:
                        self._add_channel(sub, schemas)
                messages = [m for m in inner if isinstance(m, Message)]
                known = [m for m in messages if m.channel_id in self._channels]
                orphans += len(messages) - len(known)
                yield from sorted(known, key=lambda m: m.log_time)
            elif isinstance(record, Message):
                if record.channel_id in self._channels:
                    yield record
                else:
                    orphans += 1
            elif isinstance(record, DataEnd | Footer):
                if learn:
                    self._note_orphans(orphans)
                return

    def _note_orphans(self, count: int) -> None:
        if count:
            self.warnings.append(f"{self.path}: skipped {count} messages of channels the file "
                                 "does not declare (damaged records?)")

    def _size(self) -> int:
        return self._file_size

    def _note_damage(self, offset: int, why: str, *, truncated: bool) -> None:
        self._valid_until = offset
        size = self._size()
        if truncated or offset >= size or self._recover:
            self.warnings.append(
                f"{self.path} is incomplete ({why} at byte {offset} of {size}); "
                "reading the messages before it"
            )
            return
        raise LogReadError(
            f"{self.path} is corrupt at byte {offset} of {size} ({why}); "
            "use --recover to read the intact messages around the damage"
        )

    def raw_messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[RawMessage]:
        wanted = None if topics is None else set(topics)
        if self._summary is not None:
            try:
                for log_time, cid, data in self._indexed_messages(wanted, start_ns, end_ns):
                    topic, msgtype, encoding, schema = self._channels[cid]
                    yield RawMessage(topic, msgtype, log_time, data, encoding, schema)
            except _DAMAGE as err:
                raise LogReadError(
                    f"{self.path} is corrupt ({_describe(err)}); "
                    "use --recover to read the intact messages around the damage"
                ) from None
            return
        for message in self._merge_in_time(self._stream_messages()):
            topic, msgtype, encoding, schema = self._channels[message.channel_id]
            if wanted is not None and topic not in wanted:
                continue
            if start_ns is not None and message.log_time < start_ns:
                continue
            if end_ns is not None and message.log_time >= end_ns:
                continue
            yield RawMessage(topic, msgtype, message.log_time, message.data, encoding, schema)

    def _indexed_messages(self, wanted: set[str] | None, start_ns: int | None,
                          end_ns: int | None) -> Iterator[tuple[int, int, bytes | memoryview]]:
        """(log time, channel id, data) in log-time order, through the summary: chunk by chunk
        when the chunks follow each other in time, else by the mcap library's reader."""
        chunks = ordered_chunks(self._summary)
        if chunks is not None:
            ids = None if wanted is None else {
                cid for cid, (topic, *_) in self._channels.items() if topic in wanted}
            yield from chunk_messages(self._file, chunks, channels=ids, start_ns=start_ns,
                                      end_ns=end_ns)
            return
        start_name, end_name = _TIME_BOUNDS
        bounds: dict[str, Any] = {start_name: start_ns, end_name: end_ns}
        for _schema, channel, message in self._seeking_reader().iter_messages(
                topics=None if wanted is None else sorted(wanted), log_time_order=True,
                **bounds):
            yield message.log_time, channel.id, message.data

    def topic_spans(self) -> dict[str, tuple[int, int]] | None:
        """From the message indexes of an MCAP file with a summary (see
        :mod:`replay.formats.mcap.index`)."""
        if self._summary is None:
            return None
        try:
            by_channel = channel_spans(self._file, self._summary)
        except (*_DAMAGE, OSError):
            return None
        if by_channel is None:
            return None
        spans: dict[str, tuple[int, int]] = {}
        for channel_id, (first, last) in by_channel.items():
            if channel_id not in self._channels:
                return None
            topic = self._channels[channel_id][0]
            known = spans.get(topic, (first, last))
            spans[topic] = (min(known[0], first), max(known[1], last))
        return spans

    @staticmethod
    def _merge_in_time(messages: Iterator[Message], window: int = 64) -> Iterator[Message]:
        """Restore log-time order across nearby chunks with a bounded buffer."""
        heap: list[tuple[int, int, Message]] = []
        for index, message in enumerate(messages):
            heapq.heappush(heap, (message.log_time, index, message))
            if len(heap) > window:
                yield heapq.heappop(heap)[2]
        while heap:
            yield heapq.heappop(heap)[2]

    def close(self) -> None:
        self._file.close()


def _with_count(info: TopicInfo, count: int) -> TopicInfo:
    return TopicInfo(info.name, info.msgtype, count, info.serialization, info.msgdef)


def _describe(err: BaseException) -> str:
    text = str(err).strip().splitlines()[0] if str(err).strip() else ""
    return f"{type(err).__name__}: {text}" if text else type(err).__name__

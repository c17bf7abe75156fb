"""ROS1 bags whose recording was cut short: the chunks are there, the index is not.

A ROS1 bag writer appends its index (connection and chunk-info records) when it closes, and
only then fills in the header's ``index_pos``; rosbags reads through that index. A killed
recording leaves the chunks without it. :func:`reindexed_copy` walks the chunks in file order
with rosbags' own record readers, stops at the first incomplete record, and writes the
messages to an indexed copy with rosbags' writer — what ``rosbag reindex`` does, without
touching the input.
"""

from __future__ import annotations

import io
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO, cast

from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag1.reader import (
    Header,
    ReaderError,
    RecordType,
    decompressors,
    read_bytes,
    read_uint32,
)
from rosbags.typesys.msg import normalize_msgtype

from ..bounded_file import BoundedFile


@dataclass(frozen=True)
class Skipped:
    """A damaged stretch of a bag that ``recover`` read past."""

    start: int  # byte offsets: the damaged record, the next chunk read (or the end)
    end: int
    reason: str
    messages: int | None  # lost, from the bag's index (None: the index does not say)
    first_ns: int | None  # log times the lost messages lie between
    last_ns: int | None


@dataclass(frozen=True)
class Reindexed:
    """What the copy holds: messages, where and why the walk stopped, what it skipped."""

    messages: int
    stopped_at: int  # byte offset of the first record not read
    reason: str  # "end of file" or what was incomplete
    skipped: tuple[Skipped, ...] = ()


def _record(src: BinaryIO) -> tuple[Header, bytes]:
    """One record (header fields, data) from the current position."""
    header = Header.read(src)
    return header, read_bytes(src, read_uint32(src))


def _connection(header: Header, data: bytes) -> dict[str, Any]:
    fields = Header.read(io.BytesIO(struct.pack("<L", len(data)) + data))
    latching = fields.get_string("latching") if "latching" in fields else ""
    return {
        "topic": header.get_string("topic"),
        "msgtype": normalize_msgtype(fields.get_string("type")),
        "msgdef": fields.get_string("message_definition"),
        "md5sum": fields.get_string("md5sum"),
        "callerid": fields.get_string("callerid") if "callerid" in fields else None,
        "latching": int(latching) if latching else None,
    }


def reindexed_copy(path: Path, output: Path, *, resync: bool = False) -> Reindexed:
    """Write the complete chunks of the bag ``path`` to a new indexed bag ``output``.

    The walk stops at the first damaged or incomplete record; with ``resync`` it goes on at
    the next chunk record after it, and reports each skipped stretch with the messages the
    bag's index says it held (or the log times around it). Raises rosbags' ``ReaderError``
    when ``path`` does not start like a ROS1 v2.0 bag.
    """
    writer = Writer1(output)
    writer.set_compression(Writer1.CompressionFormat.LZ4)
    writer.open()
    walk = _Walk(writer)
    try:
        # lengths read from a damaged bag cannot allocate past its end
        with BoundedFile(path.open("rb")) as bounded:
            src = cast(BinaryIO, bounded)
            if src.readline() != b"#ROSBAG V2.0\n":
                raise ReaderError("not a ROS1 v2.0 bag")
            bag_header, _padding = _record(src)
            size = bounded.size
            walk.declared = _indexed_connections(src, bag_header, size)
            while True:
                offset = src.tell()
                if offset >= size:
                    return walk.result(offset, "end of file")
                try:
                    header, data = _record(src)
                    op = header.get_uint8("op")
                    if op == RecordType.CHUNK_INFO:
                        walk.note_chunk_info(header, data)
                    if op != RecordType.CHUNK:
                        continue  # index data after a chunk; a complete bag's index
                    chunk = decompressors[header.get_string("compression")](data)
                    if len(chunk) != header.get_uint32("size"):
                        raise ReaderError("chunk shorter than its declared size")
                    walk.read_chunk(offset, chunk)
                except (ReaderError, KeyError, OSError, RuntimeError, ValueError,
                        struct.error) as err:
                    why = f"damaged record ({str(err).strip() or type(err).__name__})"
                    following = _next_chunk(src, offset + 1, size) if resync else None
                    if following is None:
                        if resync:
                            walk.skip(offset, size, why)
                        return walk.result(offset, why)
                    walk.skip(offset, following, why)
                    src.seek(following)
    finally:
        writer.close()


class _Walk:
    """The messages written so far, the chunk infos seen and the stretches skipped."""

    def __init__(self, writer: Writer1) -> None:
        self.writer = writer
        self.connections: dict[int, Any] = {}
        #: connections the bag's index declares (a chunk that declared one may be lost)
        self.declared: dict[int, dict[str, Any]] = {}
        self.count = 0
        self.last_ns: int | None = None
        self.infos: dict[int, tuple[int, int, int]] = {}  # chunk position -> times, count
        # start, end, reason, log times of the messages read before and after, messages
        # read from a chunk damaged inside (end == start: the chunk at start)
        self.skipped: list[list[Any]] = []

    def read_chunk(self, offset: int, chunk: bytes) -> None:
        """Write the messages of one decompressed chunk (up to a damaged inner record)."""
        inner = io.BytesIO(chunk)
        read = self.count
        while inner.tell() < len(chunk):
            at = inner.tell()
            try:
                header, data = _record(cast(BinaryIO, inner))
                op = header.get_uint8("op")
                conn_id = header.get_uint32("conn")
                if op == RecordType.CONNECTION and conn_id not in self.connections:
                    self.connections[conn_id] = self.writer.add_connection(
                        **_connection(header, data))
                elif op == RecordType.MSGDATA and conn_id not in self.connections \
                        and conn_id in self.declared:
                    self.connections[conn_id] = self.writer.add_connection(
                        **self.declared[conn_id])
                if op == RecordType.MSGDATA and conn_id in self.connections:
                    time_ns = header.get_time("time")
                    self.writer.write(self.connections[conn_id], time_ns, data)
                    self.count += 1
                    self.last_ns = time_ns
                    for stretch in self.skipped:
                        if stretch[4] is None:
                            stretch[4] = time_ns
            except (ReaderError, KeyError, ValueError, struct.error) as err:
                self.skip(offset, offset, f"damaged record {at} bytes into the chunk "
                          f"({str(err).strip() or type(err).__name__})", self.count - read)
                return

    def note_chunk_info(self, header: Header, data: bytes) -> None:
        """Remember what the index says one chunk holds."""
        pairs = len(data) // 8
        count = sum(struct.unpack_from("<I", data, 8 * i + 4)[0] for i in range(pairs))
        self.infos[header.get_uint64("chunk_pos")] = (
            header.get_time("start_time"), header.get_time("end_time"), count)

    def skip(self, start: int, end: int, reason: str, read: int = 0) -> None:
        """Note a damaged stretch (``end == start``: inside the chunk at ``start``, of which
        ``read`` messages were read), with the log time of the messages around it."""
        self.skipped.append([start, end, reason, self.last_ns, None, read])

    def result(self, offset: int, reason: str) -> Reindexed:
        """What the walk did, each skipped stretch with what the index says it held."""
        skipped = []
        for start, end, why, before_ns, after_ns, read in self.skipped:
            infos = [info for position, info in self.infos.items()
                     if start <= position < end or position == start == end]
            if infos:  # the index tells what the skipped chunks held
                skipped.append(Skipped(start, end, why, sum(i[2] for i in infos) - read,
                                       min(i[0] for i in infos), max(i[1] for i in infos)))
            else:
                skipped.append(Skipped(start, end, why, None, before_ns, after_ns))
        return Reindexed(self.count, offset, reason, tuple(skipped))


def _indexed_connections(src: BinaryIO, bag_header: Header, size: int,
                         ) -> dict[int, dict[str, Any]]:
    """The connection records at the start of the bag's index (empty when it has none or
    they do not read); the walk's position is kept."""
    found: dict[int, dict[str, Any]] = {}
    position = src.tell()
    try:
        index_pos = bag_header.get_uint64("index_pos")
        if not 0 < index_pos < size:
            return found
        src.seek(index_pos)
        for _ in range(bag_header.get_uint32("conn_count")):
            header, data = _record(src)
            if header.get_uint8("op") != RecordType.CONNECTION:
                break
            found[header.get_uint32("conn")] = _connection(header, data)
    except (ReaderError, KeyError, ValueError, struct.error):
        pass
    finally:
        src.seek(position)
    return found


def _next_chunk(src: BinaryIO, start: int, size: int) -> int | None:
    """Offset of the first record at or after ``start`` that parses as a chunk header whose
    data fits in the file (the next place to read on at), or None."""
    marker = b"op=" + bytes([RecordType.CHUNK])
    block = 1 << 20
    position = start
    while position < size:
        src.seek(position)
        data = src.read(block + 4096)
        found = data.find(marker)
        while found >= 0 and found < block:
            hit = position + found
            for candidate in range(max(start, hit - 256), hit - 4 + 1):
                if _chunk_starts_at(src, candidate, hit, size):
                    return candidate
            found = data.find(marker, found + 1)
        position += block
    return None


def _chunk_starts_at(src: BinaryIO, offset: int, marker_at: int, size: int) -> bool:
    src.seek(offset)
    try:
        (header_size,) = struct.unpack("<I", src.read(4))
        if not offset + 4 < marker_at < offset + 4 + header_size <= size - 4:
            return False
        src.seek(offset)
        header = Header.read(src, RecordType.CHUNK)
        data_size = read_uint32(src)
        header.get_string("compression")
        header.get_uint32("size")
    except (ReaderError, KeyError, ValueError, struct.error):
        return False
    return bool(offset + 8 + header_size + data_size <= size)

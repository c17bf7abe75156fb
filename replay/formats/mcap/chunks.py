"""MCAP writing with each chunk finished (compressed, checksummed, written with its message
indexes) on a worker thread while the next one is filled.

The file is the one ``mcap.writer.Writer`` writes for the same calls, byte for byte: the same
records in the same order, schemas and channels inside the chunk open when they are
registered, a chunk completed once it holds more than ``chunk_size`` bytes, chunk CRCs, a
summary with schemas, channels, statistics, chunk and metadata indexes and summary offsets.
Messages, chunks and message indexes are packed here (they are written per message or per
chunk); the other records by the ``mcap`` library's own record classes.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from functools import partial
from typing import IO, Any

from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Channel,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    McapRecord,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.stream_reader import MAGIC_SIZE

from ..chunk_worker import OrderedWorker

__all__ = ["CHUNK_COMPRESSIONS", "McapChunkWriter"]

MAGIC = b"\x89MCAP0\r\n"
assert len(MAGIC) == MAGIC_SIZE
#: opcode, record length, channel id, sequence, log time, publish time
_MESSAGE = struct.Struct("<BQHIQQ")
#: opcode, record length, start, end, uncompressed size, uncompressed CRC
_CHUNK = struct.Struct("<BQQQQI")
#: opcode, record length, channel id, byte length of the (time, offset) pairs
_MESSAGE_INDEX = struct.Struct("<BQHI")
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
_OP_MESSAGE = int(Opcode.MESSAGE)


def _zstd(level: int | None) -> Callable[[bytes | bytearray], bytes]:
    import zstandard

    # one compressor for every chunk: creating one per chunk costs as much as compressing
    compressor = zstandard.ZstdCompressor() if level is None else \
        zstandard.ZstdCompressor(level=level)
    return compressor.compress


def _lz4(level: int | None) -> Callable[[bytes | bytearray], bytes]:
    import lz4.frame

    if level is None:
        return lz4.frame.compress  # type: ignore[no-any-return]
    return partial(lz4.frame.compress, compression_level=level)


#: compression name in the chunk record -> factory of the compressing function, given the
#: level (None: the library's default, as ``mcap.writer.Writer`` compresses)
CHUNK_COMPRESSIONS: dict[str, Callable[[int | None], Callable[[bytes | bytearray], bytes]]
                         | None] = {"zstd": _zstd, "lz4": _lz4, "": None}


class McapChunkWriter:
    """An MCAP file written to ``file`` in chunks of about ``chunk_size`` bytes, compressed
    with ``compression`` (``zstd``, ``lz4`` or ``""``) at ``level`` (None: the library's
    default), finished on a worker thread.

    The calls are those of ``mcap.writer.Writer``; :meth:`abort` stops the worker without
    finishing the file. Errors of the worker (a full disk) are raised by a later call.
    ``close_file``: :meth:`finish` and :meth:`abort` close ``file``, whatever they raise.
    """

    def __init__(self, file: IO[bytes], *, chunk_size: int = 1024 * 1024,
                 compression: str = "zstd", level: int | None = None,
                 close_file: bool = False) -> None:
        factory = CHUNK_COMPRESSIONS[compression]
        self._compress = None if factory is None else factory(level)
        self._compression = compression
        self._compression_field = _U32.pack(len(compression)) + compression.encode()
        self._file = file
        self._close_file = close_file
        self._position = 0  # bytes written so far, counted by whoever writes (one at a time)
        self._chunk_size = chunk_size
        self._worker = OrderedWorker()
        # the open chunk: its records, and per channel its messages' (log time, offset) pairs
        self._chunk = bytearray()
        self._indexes: dict[int, list[int]] = {}
        self._schemas: dict[int, Schema] = {}
        self._channels: dict[int, Channel] = {}
        self._counts: dict[int, int] = {}  # channel id -> messages, in order of first message
        self._start_ns = self._end_ns = 0
        self._chunk_indexes: list[ChunkIndex] = []
        self._metadata_indexes: list[MetadataIndex] = []

    def start(self, profile: str = "", library: str = "") -> None:
        """Write the magic and the header record."""
        self._out(MAGIC + _record(Header(profile, library)))

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        """Add a schema record to the open chunk; its id."""
        schema_id = len(self._schemas) + 1
        schema = Schema(id=schema_id, data=data, encoding=encoding, name=name)
        self._schemas[schema_id] = schema
        self._chunk += _record(schema)
        self._maybe_finish_chunk()
        return schema_id

    def register_channel(self, topic: str, message_encoding: str, schema_id: int,
                         metadata: dict[str, str] | None = None) -> int:
        """Add a channel record to the open chunk; its id."""
        channel_id = len(self._channels) + 1
        channel = Channel(id=channel_id, topic=topic, message_encoding=message_encoding,
                          schema_id=schema_id, metadata=dict(metadata or {}))
        self._channels[channel_id] = channel
        self._chunk += _record(channel)
        self._maybe_finish_chunk()
        return channel_id

    def add_message(self, channel_id: int, log_time: int, data: bytes | memoryview,
                    publish_time: int, sequence: int = 0) -> None:
        """Add a message record to the open chunk (its bytes are copied there)."""
        chunk = self._chunk
        index = self._indexes.get(channel_id)
        if index is None:
            index = self._indexes[channel_id] = []
        index.append(log_time)
        index.append(len(chunk))
        chunk += _MESSAGE.pack(_OP_MESSAGE, 22 + len(data), channel_id, sequence, log_time,
                               publish_time)
        chunk += data
        if len(chunk) > self._chunk_size:
            self._finish_chunk()

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        """Write a metadata record (outside chunks) and index it."""
        record = _record(Metadata(name=name, metadata=data))
        self._worker.drain()
        self._metadata_indexes.append(
            MetadataIndex(offset=self._position, length=len(record), name=name))
        self._out(record)

    def flush(self) -> None:
        """Complete the open chunk (if it holds messages) and hand the file's bytes to the OS."""
        self._finish_chunk()
        self._worker.drain()
        self._file.flush()

    def finish(self, metadata: Mapping[str, dict[str, str]] | None = None) -> None:
        """Write the ``metadata`` records (name -> values), complete the last chunk, write the
        summary and the footer; stop the worker."""
        with self._closing():
            for name, values in (metadata or {}).items():
                self.add_metadata(name, values)
            self._finish_chunk()
            self._worker.close()
            self._out(_record(DataEnd(0)))
            self._out(self._summary())

    def abort(self) -> None:
        """Stop the worker; the file stays unfinished."""
        with self._closing():
            self._worker.abort()

    @contextmanager
    def _closing(self) -> Iterator[None]:
        try:
            yield
        finally:
            if self._close_file:
                self._file.close()

    def _out(self, data: bytes | bytearray) -> None:
        self._file.write(data)
        self._position += len(data)

    def _maybe_finish_chunk(self) -> None:
        if len(self._chunk) > self._chunk_size:
            self._finish_chunk()

    def _finish_chunk(self) -> None:
        indexes = self._indexes
        if not indexes:  # schemas and channels alone stay for the next chunk
            return
        records = self._chunk
        self._chunk, self._indexes = bytearray(), {}
        start_ns = min(min(pairs[0::2]) for pairs in indexes.values())
        end_ns = max(max(pairs[0::2]) for pairs in indexes.values())
        if not self._counts:
            self._start_ns = start_ns
        self._start_ns = min(self._start_ns, start_ns)
        self._end_ns = max(self._end_ns, end_ns)
        for channel_id, pairs in indexes.items():
            self._counts[channel_id] = self._counts.get(channel_id, 0) + len(pairs) // 2
        self._worker.submit(lambda: self._write_chunk(records, indexes, start_ns, end_ns))

    def _write_chunk(self, records: bytearray, indexes: dict[int, list[int]], start_ns: int,
                     end_ns: int) -> None:
        """On the worker: the chunk record, then its channels' message indexes."""
        data = records if self._compress is None else self._compress(records)
        tail = self._compression_field + _U64.pack(len(data))
        head = _CHUNK.pack(Opcode.CHUNK, 8 + 8 + 8 + 4 + len(tail) + len(data), start_ns,
                           end_ns, len(records), zlib.crc32(records)) + tail
        chunk_start = self._position
        self._out(head)
        self._out(data)
        index_start = self._position
        offsets: dict[int, int] = {}
        parts: list[bytes] = []
        length = 0
        for channel_id, pairs in indexes.items():
            offsets[channel_id] = index_start + length
            body = struct.pack(f"<{len(pairs)}Q", *pairs)
            part = _MESSAGE_INDEX.pack(Opcode.MESSAGE_INDEX, 6 + len(body), channel_id,
                                       len(body)) + body
            parts.append(part)
            length += len(part)
        self._out(b"".join(parts))
        self._chunk_indexes.append(ChunkIndex(
            message_start_time=start_ns, message_end_time=end_ns, chunk_start_offset=chunk_start,
            chunk_length=index_start - chunk_start, message_index_offsets=offsets,
            message_index_length=length, compression=self._compression,
            compressed_size=len(data), uncompressed_size=len(records)))

    def _summary(self) -> bytes:
        """Summary section, summary offsets, footer and closing magic, as the mcap writer
        lays them out."""
        summary_start = self._position
        builder = RecordBuilder()
        offsets: list[SummaryOffset] = []
        statistics = Statistics(
            message_count=sum(self._counts.values()), schema_count=len(self._schemas),
            channel_count=len(self._channels), attachment_count=0,
            metadata_count=len(self._metadata_indexes), chunk_count=len(self._chunk_indexes),
            message_start_time=self._start_ns, message_end_time=self._end_ns,
            channel_message_counts=self._counts)
        groups: list[tuple[Opcode, list[Any]]] = [
            (Opcode.SCHEMA, list(self._schemas.values())),
            (Opcode.CHANNEL, list(self._channels.values())),
            (Opcode.STATISTICS, [statistics]),
            (Opcode.CHUNK_INDEX, self._chunk_indexes),
            (Opcode.ATTACHMENT_INDEX, []),
            (Opcode.METADATA_INDEX, self._metadata_indexes),
        ]
        for opcode, records in groups:
            group_start = builder.count
            for record in records:
                record.write(builder)
            offsets.append(SummaryOffset(group_opcode=opcode,
                                         group_start=summary_start + group_start,
                                         group_length=builder.count - group_start))
        offsets_start = summary_start + builder.count
        for offset in offsets:
            offset.write(builder)
        summary: bytes = builder.end()  # type: ignore[no-untyped-call]
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 8 + 8 + 4, summary_start,
                                     offsets_start), zlib.crc32(summary))
        return summary + _record(Footer(summary_start=summary_start,
                                        summary_offset_start=offsets_start,
                                        summary_crc=crc)) + MAGIC


def _record(record: McapRecord) -> bytes:
    builder = RecordBuilder()
    record.write(builder)
    data: bytes = builder.end()  # type: ignore[no-untyped-call]
    return data

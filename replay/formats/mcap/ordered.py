"""Messages of an MCAP file whose chunks follow each other in time, read chunk by chunk.

A log written as it was recorded has chunks in file order whose time ranges do not overlap;
its messages in log-time order are then each chunk's messages, stably sorted by log time,
one chunk after the other: the order the ``mcap`` library's reader gives with
``log_time_order=True`` (it breaks ties by file position), without its priority queue and a
Python object per record. Each chunk is checked as that reader does (CRC, declared size).
The next chunk is decompressed and checked on a worker thread while the messages of the
current one are used.
"""

from __future__ import annotations

import io
import struct
import zlib
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from itertools import pairwise
from typing import IO, Any

from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.records import Chunk, ChunkIndex
from mcap.stream_reader import CRCValidationError

from .checks import check_chunk_size

__all__ = ["chunk_messages", "ordered_chunks"]

#: opcode and length of a record
_RECORD = struct.Struct("<BQ")
#: channel id, sequence, log time, publish time
_MESSAGE = struct.Struct("<HIQQ")
_OP_MESSAGE = 0x05
_OP_CHUNK = 0x06

#: (log time, channel id, data)
Entry = tuple[int, int, memoryview]


def ordered_chunks(summary: Any) -> list[ChunkIndex] | None:
    """The chunk indexes in file order when each chunk's messages come no earlier than the
    previous chunk's; None when they overlap in time, or when the summary indexes no chunk
    (an unchunked file, whose messages only a scan finds)."""
    chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    if not chunks:
        return None
    for before, after in pairwise(chunks):
        if before.message_end_time > after.message_start_time:
            return None
    return chunks


def chunk_messages(
    file: IO[bytes], chunks: list[ChunkIndex], *, channels: set[int] | None,
    start_ns: int | None, end_ns: int | None,
) -> Iterator[Entry]:
    """``(log time, channel id, data)`` of the messages in ``chunks`` (from
    :func:`ordered_chunks`) in log-time order, of ``channels`` (None: all) with
    ``start_ns <= log time < end_ns``. Damage raises McapError, ValueError or a
    decompressor's error."""
    # a chunk without message indexes may hold any channel: only reading it tells
    wanted = [c for c in chunks
              if (channels is None or not c.message_index_offsets
                  or not channels.isdisjoint(c.message_index_offsets))
              and (start_ns is None or c.message_end_time >= start_ns)
              and (end_ns is None or c.message_start_time < end_ns)]
    if not wanted:
        return
    read, unpack = _read_chunk(file), _unpacker()
    with ThreadPoolExecutor(1, thread_name_prefix="camlog-mcap-chunk") as pool:

        def ahead(index: ChunkIndex) -> Future[memoryview]:
            """The chunk's records, being unpacked; its damage is raised when they are
            wanted, after the messages before it."""
            try:
                return pool.submit(unpack, read(index))
            except Exception as err:
                failed: Future[memoryview] = Future()
                failed.set_exception(err)
                return failed

        pending = ahead(wanted[0])
        try:
            for following in [*wanted[1:], None]:
                records = pending.result()
                if following is not None:  # unpacked while these messages are used
                    pending = ahead(following)
                yield from _messages(records, channels, start_ns, end_ns)
        finally:
            pending.cancel()


def _read_chunk(file: IO[bytes]) -> Callable[[ChunkIndex], Chunk]:
    """A function reading one chunk record (its data still compressed)."""
    def read(index: ChunkIndex) -> Chunk:
        file.seek(index.chunk_start_offset)
        opcode, length = _RECORD.unpack(file.read(_RECORD.size))
        if opcode != _OP_CHUNK or length + 9 != index.chunk_length:
            raise McapError(f"no chunk record at byte {index.chunk_start_offset}")
        chunk: Chunk = Chunk.read(ReadDataStream(io.BytesIO(file.read(length))))
        check_chunk_size(chunk)
        return chunk

    return read


def _unpacker() -> Callable[[Chunk], memoryview]:
    """A function decompressing a chunk's records and checking them against its CRC (zstd,
    lz4 and the CRC release the GIL: a worker thread does this beside the caller)."""
    import zstandard

    decompressor = zstandard.ZstdDecompressor()

    def unpack(chunk: Chunk) -> memoryview:
        if chunk.compression == "zstd":
            data = decompressor.decompress(chunk.data, max_output_size=chunk.uncompressed_size)
        elif chunk.compression == "lz4":
            import lz4.frame

            data = lz4.frame.decompress(chunk.data)
        elif chunk.compression == "":
            data = chunk.data
        else:
            raise McapError(f"unknown chunk compression {chunk.compression!r}")
        if len(data) != chunk.uncompressed_size:
            raise ValueError(f"a chunk holds {len(data)} bytes, not {chunk.uncompressed_size}")
        crc = zlib.crc32(data) if chunk.uncompressed_crc else 0
        if crc != chunk.uncompressed_crc:  # the mcap library's error, as its reader raises it
            raise CRCValidationError(expected=chunk.uncompressed_crc, actual=crc, record=chunk)
        return memoryview(data)

    return unpack


def _messages(records: memoryview, channels: set[int] | None, start_ns: int | None,
              end_ns: int | None) -> list[Entry]:
    """The chunk's messages that are wanted, stably sorted by log time."""
    found: list[Entry] = []
    position, size = 0, len(records)
    unpack_record, unpack_message = _RECORD.unpack_from, _MESSAGE.unpack_from
    while position < size:
        opcode, length = unpack_record(records, position)
        body = position + 9
        position = body + length
        if position > size:
            raise ValueError("a record runs past the end of its chunk")
        if opcode != _OP_MESSAGE:
            continue  # schemas and channels: the summary has them
        if length < 22:
            raise ValueError("a message record shorter than its fields")
        channel, _, log_time, _ = unpack_message(records, body)
        if (channels is None or channel in channels) and \
                (start_ns is None or log_time >= start_ns) and \
                (end_ns is None or log_time < end_ns):
            found.append((log_time, channel, records[body + 22:position]))
    if any(a[0] > b[0] for a, b in pairwise(found)):
        found.sort(key=lambda entry: entry[0])
    return found

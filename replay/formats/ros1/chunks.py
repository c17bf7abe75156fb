"""ROS1 bags written by ``rosbags``' writer, with each chunk compressed and written (with
its index records) on a worker thread while the next one is filled.

The bytes are those ``rosbags.rosbag1.Writer`` writes for the same calls; a message record's
header, the same for every message of a connection but its time, is packed once.
"""

from __future__ import annotations

import struct
from collections import defaultdict
from io import BytesIO
from typing import Any

from rosbags.interfaces import Connection
from rosbags.rosbag1 import Writer
from rosbags.rosbag1.reader import RecordType
from rosbags.rosbag1.writer import MAXSIZE, Header, WriteChunk

from ..chunk_worker import OrderedWorker

__all__ = ["ThreadedRos1Writer"]

_U32 = struct.Struct("<I")
#: a message's time (seconds, nanoseconds) and data length
_TIME_SIZE = struct.Struct("<III")


def _field(name: bytes, value: bytes) -> bytes:
    return _U32.pack(len(name) + 1 + len(value)) + name + b"=" + value


class ThreadedRos1Writer(Writer):
    """``rosbags``' ROS1 writer, its chunks finished by a worker thread."""

    def __init__(self, path: Any) -> None:
        super().__init__(path)
        self._worker = OrderedWorker()
        self._heads: dict[int, bytes] = {}  # connection id -> a message record's start

    def add_connection(self, *args: Any, **kwargs: Any) -> Connection:
        """As rosbags' ``add_connection``."""
        connection = super().add_connection(*args, **kwargs)
        fields = (_field(b"op", bytes([RecordType.MSGDATA])) +
                  _field(b"conn", _U32.pack(connection.id)) + _U32.pack(13) + b"time=")
        self._heads[connection.id] = _U32.pack(len(fields) + 8) + fields
        return connection

    def write(self, connection: Connection, timestamp: int, data: bytes | memoryview) -> None:
        """Add a message record to the open chunk (its bytes are copied there)."""
        chunk = self.chunks[-1]
        records = chunk.data
        chunk.connections[connection.id].append((timestamp, records.tell()))
        chunk.start = min(timestamp, chunk.start)
        chunk.end = max(timestamp, chunk.end)
        seconds, nanoseconds = divmod(timestamp, 1_000_000_000)
        records.write(self._heads[connection.id] + _TIME_SIZE.pack(seconds, nanoseconds,
                                                                   len(data)))
        records.write(data)
        if records.tell() > self.chunk_threshold:
            self.write_chunk(chunk)

    def write_chunk(self, chunk: WriteChunk) -> None:
        """Hand the open chunk to the worker and open the next."""
        if chunk.data.tell() == 0:
            return
        self.chunks.append(WriteChunk(BytesIO(), -1, MAXSIZE, 0, defaultdict(list)))
        self._worker.submit(lambda: self._finish_chunk(chunk))

    def _finish_chunk(self, chunk: WriteChunk) -> None:
        """On the worker: the chunk record, then an index record per connection."""
        assert self.bio is not None
        bio = self.bio
        chunk.pos = bio.tell()
        records = chunk.data.getvalue()
        chunk.data.close()
        header = Header()
        header.set_string("compression", self.compression_format)
        header.set_uint32("size", len(records))
        header.write(bio, RecordType.CHUNK)
        data = self.compressor(records)
        bio.write(_U32.pack(len(data)))
        bio.write(data)
        for connection_id, items in chunk.connections.items():
            header = Header()
            header.set_uint32("ver", 1)
            header.set_uint32("conn", connection_id)
            header.set_uint32("count", len(items))
            header.write(bio, RecordType.IDXDATA)
            bio.write(_U32.pack(len(items) * 12) + b"".join(
                _TIME_SIZE.pack(*divmod(time, 1_000_000_000), offset) for time, offset in items))

    def flush(self) -> None:
        """Complete the open chunk and hand the file's bytes to the OS."""
        assert self.bio is not None
        self.write_chunk(self.chunks[-1])
        self._worker.drain()
        self.bio.flush()

    def close(self) -> None:
        """Complete the last chunk, wait for the worker, write the index."""
        try:
            self.write_chunk(self.chunks[-1])
            self._worker.close()
        except BaseException:
            self.abort()
            raise
        super().close()

    def abort(self) -> None:
        """Stop the worker and close the file unfinished."""
        self._worker.abort()
        if self.bio is not None:
            self.bio.close()

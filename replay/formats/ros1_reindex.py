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

from .bounded import BoundedFile


@dataclass(frozen=True)
class Reindexed:
    """What the copy holds: messages, and where and why the walk stopped."""

    messages: int
    stopped_at: int  # byte offset of the first record not read
    reason: str  # "end of file" or what was incomplete


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


def reindexed_copy(path: Path, output: Path) -> Reindexed:
    """Write the complete chunks of the unindexed bag ``path`` to a new bag ``output``.

    Raises rosbags' ``ReaderError`` when ``path`` does not start like a ROS1 v2.0 bag.
    """
    writer = Writer1(output)
    writer.set_compression(Writer1.CompressionFormat.LZ4)
    writer.open()
    connections: dict[int, Any] = {}
    count = 0
    try:
        # lengths read from a damaged bag cannot allocate past its end
        with BoundedFile(path.open("rb")) as bounded:
            src = cast(BinaryIO, bounded)
            if src.readline() != b"#ROSBAG V2.0\n":
                raise ReaderError("not a ROS1 v2.0 bag")
            _record(src)  # the bag header, padded
            while True:
                offset = src.tell()
                try:
                    header, data = _record(src)
                    op = header.get_uint8("op")
                    if op != RecordType.CHUNK:
                        continue  # index data after a chunk; a complete bag's index
                    chunk = decompressors[header.get_string("compression")](data)
                    if len(chunk) != header.get_uint32("size"):
                        raise ReaderError("chunk shorter than its declared size")
                except (ReaderError, KeyError, OSError, RuntimeError, ValueError) as err:
                    at_end = src.seek(0, io.SEEK_END) <= offset
                    return Reindexed(count, offset, "end of file" if at_end else
                                     f"incomplete record ({str(err).strip() or 'unreadable'})")
                inner = io.BytesIO(chunk)
                while inner.tell() < len(chunk):
                    header, data = _record(inner)
                    op = header.get_uint8("op")
                    if op == RecordType.CONNECTION:
                        conn_id = header.get_uint32("conn")
                        if conn_id not in connections:
                            connections[conn_id] = writer.add_connection(
                                **_connection(header, data))
                    elif op == RecordType.MSGDATA:
                        conn_id = header.get_uint32("conn")
                        if conn_id in connections:
                            writer.write(connections[conn_id], header.get_time("time"), data)
                            count += 1
    finally:
        writer.close()

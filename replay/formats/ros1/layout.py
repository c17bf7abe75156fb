"""Where a ROS1 bag's records lie, checked before ``rosbags`` trusts its lengths and offsets.

A ROS1 v2.0 bag is a magic line and a sequence of records, each a length-prefixed header and
a length-prefixed data block; the bag header points at the index (connection and chunk-info
records), whose chunk infos point at chunk records. ``rosbags`` reads a length and then asks
for that many bytes, and seeks where an offset says, so a damaged length allocates whatever
it claims and a damaged offset reads lengths out of the middle of a record.
:func:`layout_problem` walks the top-level records once (headers only; data blocks are
skipped by seeking) and checks that every length stays inside the file and every offset the
index holds lands on a record of the right kind.
"""

from __future__ import annotations

import io
import struct
from pathlib import Path

from rosbags.rosbag1.reader import Header, ReaderError, RecordType

__all__ = ["MAGIC_LINE", "layout_problem"]

MAGIC_LINE = b"#ROSBAG V2.0\n"


def layout_problem(path: Path) -> str | None:
    """What is wrong with the record layout of the bag ``path`` (with the byte offset), or
    None when every length and offset is consistent."""
    with path.open("rb") as src:
        size = src.seek(0, io.SEEK_END)
        src.seek(0)
        if src.read(len(MAGIC_LINE)) != MAGIC_LINE:
            return "it does not start like a ROS1 v2.0 bag"
        ops: dict[int, int] = {}  # record offset -> op
        index_pos: int | None = None
        chunk_positions: list[int] = []
        offset = len(MAGIC_LINE)
        while offset < size:
            try:
                header, end = _record_header(src, offset, size)
                op = header.get_uint8("op")
                if op == RecordType.BAGHEADER and index_pos is None:
                    index_pos = header.get_uint64("index_pos")
                elif op == RecordType.CHUNK_INFO:
                    chunk_positions.append(header.get_uint64("chunk_pos"))
            except (ReaderError, struct.error, ValueError) as err:
                return f"record at byte {offset} of {size} is damaged ({_reason(err)})"
            ops[offset] = op
            offset = end
    if index_pos is None:
        return "it has no bag header"
    if index_pos and index_pos not in ops:
        return f"its index position {index_pos} is not the start of a record"
    for position in chunk_positions:
        if ops.get(position) != RecordType.CHUNK:
            return f"its index places a chunk at byte {position}, where none starts"
    return None


def _record_header(src: io.BufferedReader, offset: int, size: int) -> tuple[Header, int]:
    """The header of the record at ``offset`` and where the next record starts; lengths
    that run past the end of the file raise ``ReaderError``."""
    src.seek(offset)
    (header_size,) = struct.unpack("<I", _exactly(src, 4))
    if offset + 4 + header_size + 4 > size:
        raise ReaderError(f"header of {header_size} bytes runs past the end")
    header = Header.read(io.BytesIO(struct.pack("<I", header_size) + _exactly(src, header_size)))
    (data_size,) = struct.unpack("<I", _exactly(src, 4))
    end = offset + 8 + header_size + data_size
    if end > size:
        raise ReaderError(f"data of {data_size} bytes runs past the end")
    return header, end


def _exactly(src: io.BufferedReader, count: int) -> bytes:
    data = src.read(count)
    if len(data) != count:
        raise ReaderError("the file ends inside a record")
    return data


def _reason(err: BaseException) -> str:
    return str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__

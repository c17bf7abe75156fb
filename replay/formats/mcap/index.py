"""Each channel's first and last log time in an indexed MCAP file, read from its indexes.

The summary of an MCAP file counts every channel's messages but gives log times per chunk,
and a chunk interleaves several channels. The message index records written after each
chunk list the log time of every message of one channel in that chunk, uncompressed. A
channel's first message lies in a chunk that starts no later than the earliest end of the
chunks holding that channel (and its last in one that ends no earlier than their latest
start), so a few small reads give both times exactly, without decompressing any chunk.
"""

from __future__ import annotations

from typing import IO, Any

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import ChunkIndex, MessageIndex

__all__ = ["channel_spans"]


def channel_spans(file: IO[bytes], summary: Any) -> dict[int, tuple[int, int]] | None:
    """Channel id -> (first, last) log time in ns of an MCAP file with a summary; None
    when its chunks carry no message indexes (then only reading the chunks tells)."""
    chunks: dict[int, list[ChunkIndex]] = {}
    for chunk in summary.chunk_indexes:
        if not chunk.message_index_offsets:
            return None
        for channel_id in chunk.message_index_offsets:
            chunks.setdefault(channel_id, []).append(chunk)
    spans = {}
    for channel_id, holding in chunks.items():
        earliest_end = min(c.message_end_time for c in holding)
        latest_start = max(c.message_start_time for c in holding)
        first = min(_times(file, c, channel_id)[0] for c in holding
                    if c.message_start_time <= earliest_end)
        last = max(_times(file, c, channel_id)[-1] for c in holding
                   if c.message_end_time >= latest_start)
        spans[channel_id] = (first, last)
    return spans


def _times(file: IO[bytes], chunk: ChunkIndex, channel_id: int) -> list[int]:
    """Sorted log times of one channel's messages in one chunk, from its message index."""
    file.seek(chunk.message_index_offsets[channel_id])
    stream = ReadDataStream(file)
    opcode, length = stream.read1(), stream.read8()
    if opcode != Opcode.MESSAGE_INDEX or length < 6:
        raise ValueError(f"no message index at byte {chunk.message_index_offsets[channel_id]}")
    index = MessageIndex.read(stream)
    if index.channel_id != channel_id or not index.records:
        raise ValueError(f"the message index of channel {channel_id} is inconsistent")
    return sorted(time for time, _offset in index.records)

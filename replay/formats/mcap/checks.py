"""Checks that an MCAP file's own numbers hold before the ``mcap`` library acts on them.

The library allocates a chunk's declared uncompressed size before decompressing it, and
follows the summary's offsets and references as written. A damaged file makes these
numbers anything; :func:`check_chunk_size` and :func:`summary_problem` say when they cannot
be right, so that the reader treats the chunk as damaged or scans the file instead.
"""

from __future__ import annotations

from typing import Any

import zstandard
from mcap.records import Chunk
from mcap.stream_reader import MAGIC_SIZE

__all__ = ["MAX_UNSTATED_CHUNK_BYTES", "check_chunk_size", "summary_problem"]

#: a chunk whose compressed data does not state its size may declare at most this much
MAX_UNSTATED_CHUNK_BYTES = 1 << 30


def check_chunk_size(chunk: Chunk) -> None:
    """Raise ValueError unless a chunk's declared uncompressed size is what its compressed
    data states (the decompressor allocates the declared size up front)."""
    declared = chunk.uncompressed_size
    stated: int | None = None
    if chunk.compression == "":
        stated = len(chunk.data)
    elif chunk.compression == "zstd":
        stated = zstandard.frame_content_size(chunk.data)
        stated = None if stated < 0 else stated
    elif chunk.compression == "lz4":
        import lz4.frame

        stated = lz4.frame.get_frame_info(chunk.data)["content_size"] or None
    if stated is not None and stated != declared:
        raise ValueError(f"the chunk declares {declared} bytes uncompressed, its data {stated}")
    if stated is None and declared > MAX_UNSTATED_CHUNK_BYTES:
        raise ValueError(f"the chunk declares {declared} bytes uncompressed")


def summary_problem(summary: Any, size: int) -> str | None:
    """What makes a summary section unusable (references to records it does not hold,
    offsets past the end of the file), or None."""
    for channel in summary.channels.values():
        if channel.schema_id and channel.schema_id not in summary.schemas:
            return f"names schema {channel.schema_id}, which it does not hold"
    if summary.statistics is not None:
        for cid in summary.statistics.channel_message_counts:
            if cid not in summary.channels:
                return f"counts messages of channel {cid}, which it does not hold"
    for chunk in summary.chunk_indexes:
        ends = [chunk.chunk_start_offset + chunk.chunk_length,
                *(offset + 9 for offset in chunk.message_index_offsets.values())]
        if max(ends) > size or chunk.chunk_start_offset < MAGIC_SIZE:
            return f"places a chunk past the end of the file (byte {max(ends)} of {size})"
        if any(cid not in summary.channels for cid in chunk.message_index_offsets):
            return "indexes a chunk's messages of a channel it does not hold"
    return None

"""The record ``camlog resync`` writes on ``{prefix}/stats``: how the two cameras paired."""

from __future__ import annotations

from dataclasses import dataclass, field

from .base import OMIT_NONE, JsonRecord
from .time_offset import TimeOffset

__all__ = ["OffsetStats", "ResyncStats"]


@dataclass(frozen=True)
class OffsetStats:
    """``right - left`` stamp offsets of the pairs, in nanoseconds."""

    min: int
    median: int
    max: int


@dataclass(frozen=True)
class ResyncStats(JsonRecord):
    """Pair count, slop, the stamps left unpaired per side and the pairs' stamp offsets;
    ``slop_source`` says whether the slop was given or the default (half the median frame
    period). With an offset, the right camera's stamps were moved by
    ``right_stamps_moved_ns`` before pairing (minus the offset), the offset given or
    measured (``time_offset``)."""

    what = "resync stats record"

    pairs: int
    slop_ns: int
    stamp_policy: str
    left_frames: int
    right_frames: int
    left_unpaired_stamps_ns: list[int]
    right_unpaired_stamps_ns: list[int]
    offset_right_minus_left_ns: OffsetStats | None
    left_topic: str = ""
    right_topic: str = ""
    slop_source: str = ""
    peak_buffered_messages: int | None = field(default=None, metadata=OMIT_NONE)
    right_stamps_moved_ns: int | None = field(default=None, metadata=OMIT_NONE)
    time_offset: TimeOffset | None = field(default=None, metadata=OMIT_NONE)

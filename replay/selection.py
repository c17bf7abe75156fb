"""Which messages a command reads: topic patterns, a time window, and several logs merged.

``--start S --end S`` are seconds from the first message (of the earliest log when several
are read); the window is half-open like the readers' ``start_ns <= log_time < end_ns``.
Topic patterns are exact names or shell globs (``/stereo_camera/*/image_raw``).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from fnmatch import fnmatchcase

from .errors import OptionError, TopicError
from .formats.base import LogReader, RawMessage, TopicInfo

__all__ = ["merge_in_time", "select_topics", "window_ns"]


def select_topics(
    topics: Mapping[str, TopicInfo], patterns: Sequence[str] | None, *, where: str
) -> list[str] | None:
    """Topics matching any of ``patterns`` (None: every topic, returned as None).

    A pattern that matches nothing is an error naming ``where`` and the topics there are.

    >>> from replay.formats.base import TopicInfo
    >>> t = {n: TopicInfo(n, "std_msgs/msg/String", 1, "cdr") for n in ("/a/x", "/a/y", "/b")}
    >>> select_topics(t, ["/a/*"], where="log")
    ['/a/x', '/a/y']
    """
    if patterns is None:
        return None
    chosen: list[str] = []
    for pattern in patterns:
        hits = [name for name in sorted(topics) if fnmatchcase(name, pattern)]
        if not hits:
            listed = ", ".join(sorted(topics)) or "none"
            raise TopicError(f"{where} has no topic matching {pattern!r} (topics: {listed})")
        chosen.extend(name for name in hits if name not in chosen)
    return chosen


def window_ns(
    origin_ns: int | None, start_s: float | None, end_s: float | None
) -> tuple[int | None, int | None]:
    """``[origin + start, origin + end)`` in integer nanoseconds; None leaves a side open.

    >>> window_ns(1_000_000_000, 0.5, 2.0)
    (1500000000, 3000000000)
    """
    for name, value in (("--start", start_s), ("--end", end_s)):
        if value is not None and (not math.isfinite(value) or value < 0):
            raise OptionError(f"{name} must be a time in seconds >= 0, got {value}")
    if start_s is not None and end_s is not None and end_s <= start_s:
        raise OptionError(f"--end ({end_s} s) must be after --start ({start_s} s)")
    if origin_ns is None:
        return None, None
    start = None if start_s is None else origin_ns + round(start_s * 1e9)
    end = None if end_s is None else origin_ns + round(end_s * 1e9)
    return start, end


def merge_in_time(
    readers: Sequence[LogReader],
    topics: Sequence[Iterable[str] | None],
    start_ns: int | None = None,
    end_ns: int | None = None,
) -> Iterator[RawMessage]:
    """Raw messages of several logs in log-time order; ties keep the order of ``readers``.

    Each reader streams its own messages, so memory stays flat however long the logs are.
    """
    if len(readers) == 1:
        yield from readers[0].raw_messages(topics[0], start_ns, end_ns)
        return
    streams = [
        ((raw.log_time_ns, index, raw) for raw in reader.raw_messages(wanted, start_ns, end_ns))
        for index, (reader, wanted) in enumerate(zip(readers, topics, strict=True))
    ]
    for _, _, raw in heapq.merge(*streams, key=lambda item: (item[0], item[1])):
        yield raw

"""The instants a check looks at: a few frames per second of each camera (or each pair's
frames taken together), decoded only when chosen.

A camera's frame is chosen once ``1 / rate_hz`` has passed since its last chosen one (by log
time); a pair's right frame is the one nearest in log time to the chosen left frame, within
half a frame period (20 ms at most). Still images are decoded only when chosen; a video
stream is decoded throughout (a picture needs the ones before it).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from replay.formats import LogReader, RawMessage
from replay.msgtypes import RECORD_KINDS, normalize_msgtype

from ..calibrate.pixels import TopicFrames
from .cameras import Checkable

__all__ = ["Sample", "samples"]

#: a pair's frames are taken together when their log times differ by at most this
MAX_SLOP_S = 0.02


@dataclass(frozen=True)
class Sample:
    """One instant of one check: its index in the checks, its log time (ns) and a grey
    image ``(H, W)`` uint8 of each of its cameras."""

    check: int
    log_time_ns: int
    grays: tuple[np.ndarray, ...]


@dataclass
class _LatestImage:
    """The latest message of an image topic (decoded when it was chosen, or a video's)."""

    video: bool
    raw: RawMessage | None = None
    gray: np.ndarray | None = None


@dataclass
class _Check:
    """Sampling state of one check."""

    topics: tuple[str, ...]
    next_ns: int | None = None
    wanted: RawMessage | None = None  # a pair's chosen left frame, waiting for its right
    slop_ns: int = 0
    grays: dict[str, np.ndarray] = field(default_factory=dict)


def _period_ns(reader: LogReader, topic: str) -> float:
    info = reader.topics[topic]
    span = (reader.end_ns or 0) - (reader.start_ns or 0)
    return span / max(1, info.count - 1) if info.count > 1 else 1e9


def samples(reader: LogReader, checks: list[Checkable], *, rate_hz: float) -> Iterator[Sample]:
    """The chosen instants of every check, in log order."""
    frames = TopicFrames()
    step_ns = round(1e9 / rate_hz)
    states = [_Check(tuple(s.image_topic for s in c.sources)) for c in checks]
    for state in states:
        state.slop_ns = round(min(MAX_SLOP_S * 1e9, _period_ns(reader, state.topics[0]) / 2))
    topics = {t: _LatestImage(RECORD_KINDS.get(normalize_msgtype(reader.topics[t].msgtype))
                        == "CompressedVideo") for s in states for t in s.topics}
    by_topic: dict[str, list[int]] = {}
    for index, state in enumerate(states):
        for topic in state.topics:
            by_topic.setdefault(topic, []).append(index)

    def gray(topic: str) -> np.ndarray | None:
        latest = topics[topic]
        if latest.gray is None and latest.raw is not None:
            frame = frames(reader, latest.raw)
            latest.gray = None if frame is None else frame.mono8()
        return latest.gray

    for raw in reader.raw_messages(list(topics)):
        latest = topics[raw.topic]
        latest.raw, latest.gray = raw, None
        if latest.video:
            gray(raw.topic)
        for index in by_topic[raw.topic]:
            state = states[index]
            first = state.topics[0]
            if raw.topic == first and (state.next_ns is None or raw.log_time_ns >= state.next_ns):
                state.next_ns = raw.log_time_ns + step_ns
                state.wanted = raw
                state.grays = {}
                picked = gray(first)
                if picked is None:
                    state.wanted = None
                    continue
                state.grays[first] = picked
            if state.wanted is None:
                continue
            for topic in state.topics[1:]:
                other = topics[topic].raw
                if topic not in state.grays and other is not None \
                        and abs(other.log_time_ns - state.wanted.log_time_ns) <= state.slop_ns:
                    picked = gray(topic)
                    if picked is not None:
                        state.grays[topic] = picked
            if len(state.grays) == len(state.topics):
                yield Sample(index, state.wanted.log_time_ns,
                             tuple(state.grays[t] for t in state.topics))
                state.wanted = None
            elif raw.log_time_ns - state.wanted.log_time_ns > state.slop_ns:
                state.wanted = None  # the partner never came

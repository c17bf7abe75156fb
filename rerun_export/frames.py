"""Per-camera frame bookkeeping of an export: decimation, frame matching, stale overlays.

Pure state, no rerun: the logger asks a camera's :class:`CameraFrames` whether to keep an
image, whether an overlay's frame was kept, which camera saw a stamp, and which overlays
belong to older frames and must be cleared when a new image (not a repeat) arrives.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

__all__ = ["RECENT", "CameraFrames"]

RECENT = 256  # stamps remembered per camera: far more than outputs ever lag their frame

#: an image's content: bytes, or a view of the log's own buffer (not copied)
Buffer = bytes | memoryview


@dataclass
class CameraFrames:
    """Images seen by one camera; ``every`` keeps every N-th (the first always)."""

    every: int = 1
    images: int = 0
    recent: deque[int] = field(default_factory=lambda: deque(maxlen=RECENT))
    dropped: deque[int] = field(default_factory=lambda: deque(maxlen=RECENT))
    live: dict[str, int] = field(default_factory=dict)  # overlay entity -> its frame stamp
    keyframed: bool = False  # the camera's video stream has had a keyframe
    image_key: Buffer | None = None  # the last image's content (bytes without the stamp)

    def take(self, stamp_ns: int) -> bool:
        """Count an image; True when it is kept.

        >>> frames = CameraFrames(every=2)
        >>> [frames.take(s) for s in (10, 20, 30)], frames.shows(20), frames.shows(30)
        ([True, False, True], False, True)
        """
        keep = self.images % self.every == 0
        self.images += 1
        self.recent.append(stamp_ns)
        if not keep:
            self.dropped.append(stamp_ns)
        return keep

    def saw(self, stamp_ns: int | None) -> bool:
        """True if one of the recent images carried this stamp."""
        return stamp_ns in self.recent

    def shows(self, stamp_ns: int) -> bool:
        """Whether an overlay of the frame stamped ``stamp_ns`` is drawn (its image kept)."""
        return self.every == 1 or stamp_ns not in self.dropped

    def drawn(self, entity: str, stamp_ns: int) -> None:
        """Note an overlay that must go when a later frame arrives."""
        self.live[entity] = stamp_ns

    def hold(self, stamp_ns: int, until_ns: int) -> None:
        """Keep the overlays drawn for the frame at ``stamp_ns`` until the frames after
        ``until_ns`` (a held pose's view covers its frames, noisy or not)."""
        for entity, shown in self.live.items():
            if shown == stamp_ns:
                self.live[entity] = max(shown, until_ns)

    def repeats(self, image_key: Buffer) -> bool:
        """Whether an image's content repeats the last image's byte for byte (a held pose in
        a log without sensor noise).

        >>> frames = CameraFrames()
        >>> frames.stale(10, b"board"), frames.repeats(b"board"), frames.repeats(b"moved")
        ([], True, False)
        """
        return _same(self.image_key, image_key)

    def stale(self, stamp_ns: int, image_key: Buffer | None = None) -> list[str]:
        """Overlays of frames older than ``stamp_ns``; forgotten once returned. An image
        whose ``image_key`` (content) repeats the last one's is the same view (a held pose):
        the overlays drawn on it stay.

        >>> frames = CameraFrames()
        >>> frames.drawn("corners", 10); frames.drawn("mask", 20)
        >>> frames.stale(20), frames.stale(30)
        (['corners'], ['mask'])
        >>> frames.drawn("corners", 40); frames.stale(40, b"board")
        []
        >>> frames.stale(50, b"board"), frames.stale(60, b"moved")
        ([], ['corners'])
        """
        previous, self.image_key = self.image_key, image_key
        old = [entity for entity, shown in self.live.items() if shown < stamp_ns]
        if not old or _same(previous, image_key):  # compared only when it matters
            return []
        for entity in old:
            del self.live[entity]
        return old


def _same(a: Buffer | None, b: Buffer | None) -> bool:
    """Whether two contents are equal byte for byte (numpy compares views as fast as bytes)."""
    if a is None or b is None or len(a) != len(b):
        return False
    return bool(np.array_equal(np.frombuffer(a, np.uint8), np.frombuffer(b, np.uint8)))

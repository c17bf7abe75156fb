"""Which frames pass: every N-th, or at most HZ by header stamp (a throttle node).

Both are small state machines fed one stamp at a time, in stream order, so that a stream
needs no look-ahead; :func:`throttle_mask` runs one over a whole array. The registry's
``throttle`` processor is :func:`make_throttle`: the frames it keeps pass through unchanged.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import numpy.typing as npt

from .errors import OptionValueError


class Throttle(Protocol):
    """Decides per frame, in stream order."""

    def keep(self, stamp_ns: int) -> bool:
        """True to process the frame with this header stamp."""
        ...


class KeepAll:
    """No throttling."""

    def keep(self, stamp_ns: int) -> bool:
        """Always true."""
        return True


class EveryNth:
    """Frames 0, N, 2N, ... of the stream (the chapter's 10 Hz spin over a 30 Hz camera)."""

    def __init__(self, n: int) -> None:
        if n < 1:
            raise OptionValueError("throttle", ("every",), f"must be >= 1, got {n}")
        self.n = n
        self._seen = 0

    def keep(self, stamp_ns: int) -> bool:
        """Keep every n-th frame, starting with the first."""
        kept = self._seen % self.n == 0
        self._seen += 1
        return kept


class RateLimit:
    """At most ``rate_hz``: keep a frame when its stamp is at least one period after the last
    kept one (topic_tools throttle, by header stamp). Frames whose stamp goes backwards are
    dropped until the stream passes the last kept stamp plus one period."""

    def __init__(self, rate_hz: float) -> None:
        if not rate_hz > 0:
            raise OptionValueError("throttle", ("rate",), f"must be > 0, got {rate_hz}")
        self.period_ns = round(1e9 / rate_hz)
        self._last_ns: int | None = None

    def keep(self, stamp_ns: int) -> bool:
        """Keep a frame when the rate allows it by its header stamp."""
        if self._last_ns is not None and stamp_ns - self._last_ns < self.period_ns:
            return False
        self._last_ns = stamp_ns
        return True


def make_throttle(*, every: int | None = None, rate: float | None = None) -> Throttle:
    """The throttle keeping every N-th frame or at most ``rate`` Hz (not both), or all."""
    if every is not None and rate is not None:
        raise OptionValueError("throttle", ("every", "rate"), "give one of them, not both")
    if every is not None:
        return EveryNth(every)
    if rate is not None:
        return RateLimit(rate)
    return KeepAll()


def throttle_mask(stamps_ns: npt.ArrayLike, throttle: Throttle) -> npt.NDArray[np.bool_]:
    """``(N,)`` bool: which of the stamps ``(N,)`` (in stream order) the throttle keeps."""
    return np.array([throttle.keep(int(s)) for s in np.asarray(stamps_ns).reshape(-1)],
                    dtype=bool)

"""Real-time pacing: when a message of a replayed log is due on the wall clock.

A message logged at ``t`` is due ``(t - t0) / rate`` seconds after the replay started, where
``t0`` is the first log time of the replay. Loop ``k`` (from 0) is shifted by ``k`` loop
periods: the log's span plus one mean gap between messages, so that a log with a steady
rate loops without a hitch.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from .errors import OptionError

__all__ = ["Pacer", "loop_period_ns"]


def loop_period_ns(first_ns: int, last_ns: int, count: int) -> int:
    """Log time from one loop's start to the next: span + span / (count - 1).

    >>> loop_period_ns(0, 900, 10)
    1000
    """
    span = max(last_ns - first_ns, 0)
    gap = span // (count - 1) if count > 1 and span else 100_000_000  # 0.1 s for one message
    return span + gap


@dataclass
class Pacer:
    """Sleeps until each message is due; ``clock`` and ``sleep`` are injectable for tests.

    ``late_s`` is the largest delay of a message past its due time (the replay's jitter).
    """

    rate: float
    clock: Callable[[], float] = time.monotonic
    sleep: Callable[[float], None] = time.sleep
    late_s: float = 0.0
    _origin: tuple[int, float] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if not (self.rate > 0 and math.isfinite(self.rate)):
            raise OptionError(f"--rate must be > 0, got {self.rate}")

    def due_s(self, log_time_ns: int) -> float:
        """Clock time at which the message is due (the first message is due at once)."""
        if self._origin is None:
            self._origin = (log_time_ns, self.clock())
        first_ns, started = self._origin
        return started + (log_time_ns - first_ns) / 1e9 / self.rate

    def wait(self, log_time_ns: int) -> None:
        """Return when the message logged at ``log_time_ns`` is due."""
        due = self.due_s(log_time_ns)
        ahead = due - self.clock()
        if ahead > 0:
            self.sleep(ahead)
        self.late_s = max(self.late_s, self.clock() - due)

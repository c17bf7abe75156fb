"""Real-time pacing against a fake clock."""

from __future__ import annotations

import pytest

from replay import OptionError
from replay.pacing import Pacer, loop_period_ns


class FakeClock:
    """A clock that moves only when slept on or told to."""

    def __init__(self) -> None:
        self.now, self.slept = 100.0, 0.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        assert seconds > 0
        self.now += seconds
        self.slept += seconds


def test_messages_are_due_at_scaled_log_time() -> None:
    clock = FakeClock()
    pacer = Pacer(4.0, clock=clock, sleep=clock.sleep)
    emitted = []
    for log_time_ns in (1_000_000_000, 1_000_000_000, 1_400_000_000, 3_000_000_000):
        pacer.wait(log_time_ns)
        emitted.append(clock())
    assert emitted == pytest.approx([100.0, 100.0, 100.1, 100.5])
    assert clock.slept == pytest.approx(0.5) and pacer.late_s == 0.0


def test_a_slow_consumer_is_late_not_sped_up() -> None:
    clock = FakeClock()
    pacer = Pacer(1.0, clock=clock, sleep=clock.sleep)
    pacer.wait(0)
    clock.now += 0.5  # handling the first message took 0.5 s
    pacer.wait(100_000_000)  # due 0.1 s after the start
    assert clock.slept == 0.0 and pacer.late_s == pytest.approx(0.4)


def test_loop_period_and_rate_checks() -> None:
    assert loop_period_ns(10, 910, 10) == 1000
    assert loop_period_ns(5, 5, 1) == 100_000_000
    for rate in (0.0, -1.0, float("inf"), float("nan")):
        with pytest.raises(OptionError, match="--rate"):
            Pacer(rate)

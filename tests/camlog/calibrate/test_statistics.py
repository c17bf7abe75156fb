"""The statistics run beside the evidence pass on short logs only: on long ones they would add
their memory to the pass's."""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import pytest

from camlog.calibrate import statistics
from processors.calibration.joint import BoardView


def views(count: int) -> list[BoardView]:
    return [BoardView(i % 2, i // 2, np.arange(40), np.zeros((40, 2))) for i in range(count)]


@pytest.mark.parametrize(("count", "thread"), [(10, "camlog-statistics"), (11, "MainThread")])
def test_the_statistics_of_many_corners_are_computed_in_the_callers_thread(
        count: int, thread: str, monkeypatch: pytest.MonkeyPatch) -> None:
    ran_on: list[str] = []

    def every_camera(*args: Any) -> list[Any]:
        ran_on.append(threading.current_thread().name)
        return ["left", "right"]

    monkeypatch.setattr(statistics, "_every_camera", every_camera)
    monkeypatch.setattr(statistics, "BACKGROUND_CORNERS", 400)  # 10 views of 40 corners
    joint: Any = None  # the stand-in computes nothing from it
    found = statistics.camera_statistics(joint, views(count), np.zeros((40, 3)), [(64, 48)] * 2,
                                         disc_diameter_m=None, background=True)
    assert [f.result(timeout=10) for f in found] == ["left", "right"]
    assert ran_on == [thread]

"""The statistics are computed where the flow asks for them: beside the evidence pass on a
short log, before it on a long one (where they would add their memory to the pass's), and
their error is raised by calibrate_log as one line, the output folder not left."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from camlog.calibrate import flow, statistics
from camlog.errors import CalibrationError
from camlog.requests.calibrate import CalibrateRequest


def request(log: Path, out: Path, *, report: bool = True) -> CalibrateRequest:
    return CalibrateRequest(log=log, size="7x6", square=0.01, camera=("/simple_camera",),
                            output=out, progress=False, report=report)


@pytest.mark.parametrize(("beside_corners", "thread"), [(10_000, "camlog-statistics"),
                                                         (100, "MainThread")])
def test_the_statistics_of_many_corners_are_computed_in_the_callers_thread(
        mono_calibration_log: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        beside_corners: int, thread: str) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"  # about 40 views of 42 corners
    ran_on: list[str] = []
    compute = statistics.camera_statistics

    def recorded(*args: Any, **kwargs: Any) -> list[statistics.CameraStatistics]:
        ran_on.append(threading.current_thread().name)
        return compute(*args, **kwargs)

    monkeypatch.setattr(flow, "camera_statistics", recorded)
    monkeypatch.setattr(statistics, "BESIDE_CORNERS", beside_corners)
    run = flow.calibrate_log(request(log, tmp_path / "cal"))
    assert [name.split("_")[0] for name in ran_on] == [thread]
    # what the summary holds is what was computed
    assert len(run.statistics) == 1
    u = run.summary.cameras[0].uncertainty
    assert u is not None and u.worst_px == run.statistics[0].uncertainty.worst_px > 0


@pytest.mark.parametrize(("report", "beside_corners"), [(True, 10_000), (True, 100),
                                                         (False, 10_000)])
def test_an_error_of_the_statistics_is_one_line(
        mono_calibration_log: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        report: bool, beside_corners: int) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"

    def singular(*args: Any, **kwargs: Any) -> list[statistics.CameraStatistics]:
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(flow, "camera_statistics", singular)
    monkeypatch.setattr(statistics, "BESIDE_CORNERS", beside_corners)
    with pytest.raises(CalibrationError, match=r"^the views leave the calibration's equations "
                                               r"singular \(Singular matrix\)"):
        flow.calibrate_log(request(log, tmp_path / "cal", report=report))
    assert not (tmp_path / "cal").exists()
    assert not any(t.name.startswith("camlog-statistics") for t in threading.enumerate())

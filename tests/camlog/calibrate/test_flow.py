"""calibrate_log's second measurement: the corners a ``measure_again`` gives after the first
solve are solved again, and they alone make the result."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from camlog.calibrate.flow import calibrate_log
from camlog.calibrate.instants import ViewsOfRig
from camlog.calibrate.views import CameraViews
from camlog.errors import CalibrationError
from camlog.requests.calibrate import CalibrateRequest
from processors.calibration.joint import JointResult


def test_corners_given_again_are_solved_again(mono_calibration_log: Path,
                                               tmp_path: Path) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"  # 320x240 mono_checkerboard
    first: list[JointResult] = []

    def stretched(cameras: list[CameraViews], rig: ViewsOfRig, joint: JointResult
                  ) -> ViewsOfRig:
        """Every corner 0.1 % further from the principal point: fx, fy 0.1 % larger."""
        assert [c.source.namespace for c in cameras] == ["/simple_camera"]
        first.append(joint)
        centre = np.array([joint.models[0].cx, joint.models[0].cy])
        views = [dataclasses.replace(v, corners_px=centre + (v.corners_px - centre) * 1.001)
                 for v in rig.views]
        return ViewsOfRig(views, rig.frames_of, rig.pairs, rig.candidates,
                          rig.frame_scatter_px)

    run = calibrate_log(CalibrateRequest(log=log, size="7x6", square=0.01,
                                         camera=("/simple_camera",), output=tmp_path / "cal",
                                         progress=False, report=False),
                        measure_again=stretched)
    assert len(first) == 1
    before, after = first[0].models[0], run.cameras[0].model
    assert after.fx / before.fx == pytest.approx(1.001, abs=2e-4)
    assert after.fy / before.fy == pytest.approx(1.001, abs=2e-4)
    assert after.cx == pytest.approx(before.cx, abs=0.05)
    # the evidence says what the second measurement did: every used corner moved
    evidence = run.summary.cameras[0].evidence
    assert evidence is not None and evidence.measured_again is not None
    used = sum(len(v.corners_px) for i, v in enumerate(run.solved.rig.views)
               if i not in first[0].rejected)
    assert f": {used} of {used} corners moved" in evidence.measured_again


def test_a_pinhole_chessboard_is_measured_once(mono_calibration_log: Path,
                                                tmp_path: Path) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"
    run = calibrate_log(CalibrateRequest(log=log, size="7x6", square=0.01,
                                         camera=("/simple_camera",), output=tmp_path / "cal",
                                         progress=False, report=False))
    assert run.solved.measured_again is None
    evidence = run.summary.cameras[0].evidence
    assert evidence is not None and evidence.measured_again is None


def test_singular_equations_are_one_calibration_error(mono_calibration_log: Path,
                                                      tmp_path: Path) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"

    def singular(cameras: list[CameraViews], rig: ViewsOfRig, joint: JointResult
                 ) -> ViewsOfRig:
        raise np.linalg.LinAlgError("Singular matrix")

    with pytest.raises(CalibrationError, match=r"^the views leave the calibration's equations "
                                               r"singular \(Singular matrix\)"):
        calibrate_log(CalibrateRequest(log=log, size="7x6", square=0.01,
                                       camera=("/simple_camera",), output=tmp_path / "cal",
                                       progress=False, report=False),
                      measure_again=singular)
    assert not (tmp_path / "cal").exists()

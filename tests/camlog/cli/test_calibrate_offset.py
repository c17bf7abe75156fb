"""``camlog calibrate`` of cameras whose stamps are offset from each other: the offset
measured from a waved board and the views paired by it; pairs stamped as one instant but
exposed apart leave the rig and stay in their cameras; a held board does not show it and
loses nothing."""

from __future__ import annotations

import json
import math
from contextlib import redirect_stderr, redirect_stdout
from io import StringIO
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from camlog.cli import main
from tests.camlog.conftest import spec_variant

pytestmark = pytest.mark.slow

LEFT, RIGHT = "/stereo_camera/left", "/stereo_camera/right"
BOARD = ["-s", "7x6", "-q", "0.01"]
INTRINSICS = ("fx", "fy", "cx", "cy", "k1", "k2")


def calibrate(log: Path, out: Path, *options: str) -> tuple[dict[str, Any], str, str]:
    """calibration.json, stdout and stderr of ``camlog calibrate LOG OPTIONS``."""
    printed, warned = StringIO(), StringIO()
    with redirect_stdout(printed), redirect_stderr(warned):
        assert main(["calibrate", str(log), *BOARD, "-o", str(out), "--no-report",
                     "--no-progress", *options]) == 0
    return json.loads((out / "calibration.json").read_text()), printed.getvalue(), \
        warned.getvalue()


def camera(summary: dict[str, Any], namespace: str) -> dict[str, Any]:
    (found,) = (c for c in summary["cameras"] if c["namespace"] == namespace)
    return found


def rotation_error_deg(stereo: dict[str, Any]) -> float:
    """Angle of the solved rig rotation: the truth turns the right camera by none."""
    return float(stereo["rotation_deg"])


def test_a_waved_board_gives_the_offset_and_the_rig(late_board_log: Path,
                                                    tmp_path: Path) -> None:
    summary, printed, warned = calibrate(late_board_log, tmp_path / "auto", "--left", LEFT,
                                         "--right", RIGHT)
    offset = camera(summary, RIGHT)["time_offset"]
    assert offset["reference"] == LEFT and offset["applied"]
    assert offset["truth_ms"] == 17.0
    assert abs(offset["error_ms"]) < 0.5
    assert abs(offset["error_ms"]) < 5 * offset["measured"]["std_ms"] + 0.02
    assert "time_offset" not in camera(summary, LEFT)
    assert "time offset against /stereo_camera/left: +17.0" in printed
    stereo = summary["stereo"]
    assert stereo["joint_views"] > 400  # of 600 frames per camera
    assert abs(stereo["truth"]["baseline_error_percent"]) < 0.5
    assert rotation_error_deg(stereo) < 0.05
    assert not warned

def test_stamps_as_they_are_never_pair_a_waved_board(late_board_log: Path, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]
                                                     ) -> None:
    """Paired by stamps within 20 ms, the frames are 17 ms apart and the board moved in
    between: no pair is taken as one instant (the error says why), none is trusted."""
    assert main(["calibrate", str(late_board_log), *BOARD, "-o", str(tmp_path / "off"),
                 "--no-report", "--no-progress", "--left", LEFT, "--right", RIGHT,
                 "--approximate", "0.02", "--time-offset", "off"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "never see the board at the same instant" in err[0]


@pytest.fixture(scope="module")
def snapshots(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A hand-held board photographed in pairs (2 Hz, as camera_calibration saves them):
    the right camera exposes 15 ms after the left and stamps 15 ms early, so each pair
    carries one stamp; the board drifts slowly (a pose every 1.5 s); 40 pairs at 320x240."""
    tmp = tmp_path_factory.mktemp("snapshots")
    spec = spec_variant("stereo_moving_board", tmp, {
        "rate_hz = 30.0": "rate_hz = 2.0", "segment_s = 0.8": "segment_s = 1.5",
        "exposure_s = 0.004\nposition_m": "position_m",
        "exposure_s = 0.004\nrelative_to": "phase_s = 0.015\nrelative_to"})
    log = tmp / "snapshots.mcap"
    assert main(["record", str(spec), "-o", str(log), "--resolution", "320x240", "--frames",
                 "40", "--latency", "right:-15", "--no-progress"]) == 0
    return log


def test_pairs_exposed_apart_leave_the_rig_and_cost_no_intrinsics(snapshots: Path,
                                                                  tmp_path: Path) -> None:
    joint, printed, warned = calibrate(snapshots, tmp_path / "stereo", "--left", LEFT,
                                       "--right", RIGHT)
    assert "the frames are snapshots" in camera(joint, RIGHT)["time_offset"]["summary"]
    assert "not observable" in printed
    rejected = joint["stereo"]["rejected"]
    assert len(rejected) > 20
    assert all(r["reason"].startswith("not simultaneous: the board moved ") for r in rejected)
    assert all(r["left_stamp_ns"] == r["right_stamp_ns"] for r in rejected)
    for namespace in (LEFT, RIGHT):
        mono, _p, _w = calibrate(snapshots, tmp_path / namespace.rpartition("/")[2],
                                 "--camera", namespace)
        together, alone = camera(joint, namespace), camera(mono, namespace)
        # every view that fits its own camera is used
        assert together["used_views"] == alone["used_views"] == together["boards_found"]
        for name in INTRINSICS:
            got, mono_value = together["parameters"][name], alone["parameters"][name]
            assert abs(got["value"] - mono_value["value"]) < got["std"], name
    if joint["stereo"]["joint_views"] < len(rejected):
        assert "were not simultaneous" in warned


def test_a_held_board_does_not_show_the_offset_and_loses_nothing(rig_log: Path,
                                                                 tmp_path: Path) -> None:
    auto, printed, _warned = calibrate(rig_log, tmp_path / "auto", "--left", LEFT,
                                       "--right", RIGHT)
    off, _printed, _warned = calibrate(rig_log, tmp_path / "off", "--left", LEFT, "--right",
                                       RIGHT, "--time-offset", "off")
    offset = camera(auto, RIGHT)["time_offset"]
    assert not offset["applied"] and "measured" not in offset
    assert "a held one does not" in offset["summary"] and "not observable" in printed
    for namespace in (LEFT, RIGHT):
        for name in INTRINSICS:
            assert camera(auto, namespace)["parameters"][name]["value"] == \
                camera(off, namespace)["parameters"][name]["value"]
    assert auto["stereo"]["baseline_m"] == off["stereo"]["baseline_m"]
    assert math.isclose(auto["stereo"]["rotation_deg"], off["stereo"]["rotation_deg"])
    assert np.isfinite(auto["stereo"]["rotation_std_deg"])

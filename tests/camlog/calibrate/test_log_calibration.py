"""A calibration beside the one the log carries: camera_calibration's archive, imported and
calibrated again, its result compared on the same views (terminal, report, calibration.json).

The archive holds a rendered rig's frames and the true models with their true rectification,
except the left camera's fx, 5 px too long: the comparison must find the right camera's model
as good as camlog's, the left one worse, and the rig the archive implies.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from camlog.cli import main
from processors.calibration.mono import max_projection_difference
from replay import CameraInfo
from replay.calibration_yaml import load_calibration
from replay.camera import CameraModel
from tests.ros_archives import Rendered, pack, views, yaml

FX_ERROR_PX = 5.0

pytestmark = pytest.mark.slow


def rectified(rendered: Rendered) -> tuple[CameraInfo, CameraInfo]:
    """The true cameras with the rectification OpenCV computes for the true rig."""
    left, right = rendered.infos
    rotation, translation = rendered.right_from_left[:3, :3], rendered.right_from_left[:3, 3]
    r1, r2, p1, p2, *_ = cv2.stereoRectify(left.k, left.d, right.k, right.d,
                                           (left.width, left.height), rotation,
                                           translation.reshape(3, 1))
    r1, r2, p1, p2 = (np.asarray(m, dtype=np.float64) for m in (r1, r2, p1, p2))
    return dataclasses.replace(left, r=r1, p=p1), dataclasses.replace(right, r=r2, p=p2)


@pytest.fixture(scope="module")
def calibrated(rendered_rig: Rendered, tmp_path_factory: pytest.TempPathFactory
               ) -> tuple[Path, str, CameraInfo]:
    """The archive imported and calibrated: the output folder, the terminal's text and the
    archive's (wrong) left model."""
    tmp = tmp_path_factory.mktemp("log_calibration")
    left, right = rectified(rendered_rig)
    k = left.k.copy()
    k[0, 0] += FX_ERROR_PX
    wrong = dataclasses.replace(left, k=k)
    members = views(rendered_rig) | {"left.yaml": yaml(wrong, "narrow_stereo/left"),
                                     "right.yaml": yaml(right, "narrow_stereo/right")}
    archive = pack(tmp / "calibrationdata.tar.gz", members)
    log = tmp / "archive.mcap"
    assert main(["import", str(archive), "-o", str(log), "--no-progress"]) == 0
    out = tmp / "cal"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["calibrate", str(log), "--left", "/stereo/left", "--right",
                     "/stereo/right", "--size", "7x6", "--square", "0.01", "-o", str(out),
                     "--no-progress"]) == 0
    return out, printed.getvalue(), wrong


def test_each_camera_is_compared_on_the_same_views(
        calibrated: tuple[Path, str, CameraInfo]) -> None:
    out, _, wrong = calibrated
    summary = json.loads((out / "calibration.json").read_text())
    left, right = (c["log_calibration"] for c in summary["cameras"])
    assert left["info_topic"] == "/stereo/left/camera_info"
    assert left["fx"] == pytest.approx(wrong.k[0, 0]) and left["cy"] == pytest.approx(
        wrong.k[1, 2])
    # the true model fits the views as well as camlog's; one 5 px off in fx does not
    assert right["rms_px"] == pytest.approx(right["camlog_rms_px"], rel=0.1)
    assert left["rms_px"] > 1.3 * left["camlog_rms_px"]
    # the projection difference is the models' own: as measured here between the
    # archive's left model and camlog's
    camlog_left = CameraModel.from_camera_info(load_calibration(out / "left.yaml").camera_info)
    expected = max_projection_difference(camlog_left, CameraModel.from_camera_info(wrong),
                                         align_rotation=True)
    assert left["max_projection_difference_px"] == pytest.approx(expected, rel=1e-6)
    assert left["max_projection_difference_px"] > right["max_projection_difference_px"]
    assert right["max_projection_difference_covered_px"] < 0.2


def test_the_rig_the_archive_implies_is_compared(
        calibrated: tuple[Path, str, CameraInfo], rendered_rig: Rendered) -> None:
    out, printed, _ = calibrated
    stereo = json.loads((out / "calibration.json").read_text())["stereo"]["log_calibration"]
    true_baseline = float(np.linalg.norm(rendered_rig.right_from_left[:3, 3]))
    assert stereo["baseline_m"] == pytest.approx(true_baseline, rel=1e-6)
    assert abs(stereo["baseline_difference_percent"]) < 2.0
    assert stereo["rotation_difference_deg"] < 0.2
    assert "vs the log's camera_infos: baseline" in printed


def test_the_terminal_and_the_report_show_the_comparison(
        calibrated: tuple[Path, str, CameraInfo]) -> None:
    out, printed, wrong = calibrated
    lines = [line for line in printed.splitlines() if "vs the log's /stereo/" in line]
    assert len(lines) == 2 and f"fx {wrong.k[0, 0]:.3f}" in lines[0]
    report = (out / "report.md").read_text()
    assert report.count("Beside the calibration the log carries") == 2
    assert "| the log's camera_info |" in report and "camera_infos imply a baseline" in report

"""``camlog import`` through the command line; the real wide-stereo images and real
camera_calibration archives end to end."""

from __future__ import annotations

import json
import os
import tarfile
from pathlib import Path

import cv2
import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from ruamel.yaml import YAML

from camlog.cli import main
from tests.rrd import load_rrd, rerun_cli


@pytest.mark.slow
def test_import_a_mono_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "frames"
    folder.mkdir()
    for i in range(3):
        cv2.imwrite(str(folder / f"f{i}.png"), np.full((16, 20), 40 * i, np.uint8))
    out = tmp_path / "frames.mcap"
    assert main(["import", str(folder), "-o", str(out), "--camera", "/cam",
                 "--rate", "5", "--start-time", "0", "--no-progress"]) == 0
    assert capsys.readouterr().out.startswith("imported 3 frames per camera to /cam/image_raw")
    converted = rerun_cli("mcap", "convert", str(out), "-o", "frames.rrd", cwd=tmp_path)
    assert converted.returncode == 0, converted.stderr
    with AnyReader([out]) as reader:
        assert [t for _, t, _ in reader.messages()] == [0, 200_000_000, 400_000_000]
    assert main(["import", str(tmp_path / "nope"), "-o", str(tmp_path / "x.mcap")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("camlog import: error: ") and err.count("\n") == 1


@pytest.mark.slow
@pytest.mark.realdata
def test_real_wide_stereo_imports_calibrates_and_views(
        realdata_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = realdata_dir / "ros_wide_stereo"
    if not (folder / "left0003.pgm").is_file():
        pytest.skip(f"real data not found at {folder} (set CAMLOG_REALDATA to its folder)")
    log = tmp_path / "wide.mcap"
    assert main(["import", str(folder), "-o", str(log), "--stereo", "--no-progress"]) == 0
    assert "imported 12 frames per camera" in capsys.readouterr().out
    out = tmp_path / "cal"
    assert main(["calibrate", str(log), "--left", "/stereo/left", "--right", "/stereo/right",
                 "--size", "8x6", "--square", "0.108", "-o", str(out), "--no-progress"]) == 0
    summary = json.loads((out / "calibration.json").read_text())
    assert [c["used_views"] for c in summary["cameras"]] == [12, 12]
    assert summary["stereo"]["baseline_m"] == pytest.approx(0.090, abs=0.002)
    rrd = tmp_path / "cal.rrd"
    assert main(["view", str(out / "calibration.mcap"), "-o", str(rrd), "--no-progress"]) == 0
    rec = load_rrd(rrd)
    for side in ("left", "right"):
        corners = rec.column(f"/raw/stereo/{side}/calibration/corners", "Points2D:positions")
        assert [len(view) for view in corners] == [48] * 12
        assert rec.count(f"/rectified/stereo/{side}/image_rect/image", "Image:buffer") == 12
    # the right camera placed by the calibrated P[0,3]: B along the left camera's
    # rectified x (nearly its own x)
    (translation,) = rec.column("/world/stereo/right", "Transform3D:translation")
    assert translation[0][0] == pytest.approx(summary["stereo"]["baseline_m"], rel=0.02)
    # each camera shown through the pair's rectified pinhole (P, turned by R)
    assert rec.entities_with("Pinhole:image_from_camera") == [
        "/world/stereo/left/rectified", "/world/stereo/right/rectified"]
    verify = rerun_cli("rrd", "verify", str(rrd), cwd=tmp_path)
    assert verify.returncode == 0, verify.stderr


#: camera_calibration archives committed to public repositories (provenance beside them):
#: file -> calibrate's camera and board arguments
ARCHIVES = {
    "jetson_csi_cam-calibrationdata.tar.gz": ["--left", "/stereo/left", "--right",
                                              "/stereo/right", "--size", "8x6", "--square",
                                              "0.03"],
    "tello_ros_gazebo-calibrationdata.tar.gz": ["--camera", "/camera", "--size", "7x7",
                                                "--square", "0.025"],
}


@pytest.mark.realdata
@pytest.mark.slow
@pytest.mark.parametrize("name", list(ARCHIVES))
def test_real_camera_calibration_archives_import_and_compare(
        name: str, realdata_dir: Path, tmp_path: Path) -> None:
    folder = Path(os.environ.get("CAMLOG_ROS_ARCHIVES")
                  or realdata_dir / "ros_calibration_archives")
    archive = folder / name
    if not archive.is_file():
        pytest.skip(f"real archive not found at {archive} (set CAMLOG_ROS_ARCHIVES to its "
                    "folder)")
    # what the archive holds, read with tarfile and a YAML parser of its own
    calibrations = {}
    with tarfile.open(archive) as members:
        names = members.getnames()
        for member in names:
            handle = members.extractfile(member)
            if member.endswith(".yaml") and handle is not None:
                calibrations[member] = YAML(typ="safe").load(handle.read())
    views = sum(n.startswith("left-") for n in names)
    log = tmp_path / "archive.mcap"
    assert main(["import", str(archive), "-o", str(log), "--no-progress"]) == 0
    out = tmp_path / "cal"
    assert main(["calibrate", str(log), *ARCHIVES[name], "-o", str(out), "--no-progress"]) == 0
    summary = json.loads((out / "calibration.json").read_text())
    assert len(summary["cameras"]) == len(calibrations)
    for camera, file in zip(summary["cameras"], sorted(calibrations), strict=True):
        theirs, k = camera["log_calibration"], calibrations[file]["camera_matrix"]["data"]
        assert camera["frames"] == views
        assert (theirs["fx"], theirs["cx"], theirs["fy"], theirs["cy"]) == \
            pytest.approx((k[0], k[2], k[4], k[5]))
        # camlog minimised over these views: the archive's model cannot fit them better
        assert theirs["camlog_rms_px"] <= theirs["rms_px"] * 1.001
        assert theirs["max_projection_difference_covered_px"] > 0
    if len(calibrations) == 2:
        right_p = calibrations["right.yaml"]["projection_matrix"]["data"]
        implied = summary["stereo"]["log_calibration"]["baseline_m"]
        assert implied == pytest.approx(abs(right_p[3] / right_p[0]), rel=1e-6)

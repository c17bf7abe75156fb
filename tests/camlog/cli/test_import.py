"""``camlog import`` through the command line; the real wide-stereo images end to end."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from rosbags.highlevel import AnyReader

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

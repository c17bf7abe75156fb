"""``camlog calibrate`` of a rig of three cameras, judged against the simulator's truth."""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from ruamel.yaml import YAML

from camlog.cli import main
from processors.calibration.rotation import rotation_vectors
from replay.calibration_yaml import load_calibration
from tests.camlog.conftest import scenario
from tests.cli import CliRun
from tests.slow import renders

from ..conftest import record
from .test_calibrate import BOARD, FIGURES, calibrate, summary

#: three synchronised cameras along a 0.06 m bar, each turned its own way; the board's held
#: poses cover each camera's image in turn (fully visible in the camera aimed at)
SPEC = """
name = "rig3"
description = "Synchronised rig of three cameras along a 0.06 m bar, each turned its own way"
seed = 0
duration_s = 6.0
rate_hz = 6.0

[[cameras]]
name = "a"
namespace = "/rig/a"
frame_id = "a_optical_frame"
width = 640
height = 480
hfov_rad = 0.7
distortion = [-0.1, 0.05, 0.0, 0.0, 0.0]
position_m = [0.0, 0.0, 0.5]
forward = [0.0, 0.0, -1.0]
right = [0.0, 1.0, 0.0]

[[cameras]]
name = "b"
namespace = "/rig/b"
frame_id = "b_optical_frame"
width = 640
height = 480
hfov_rad = 0.7
relative_to = "a"
translation_m = [0.03, 0.0, 0.0]
rotation_rpy_rad = [0.0, -0.03, 0.0]

[[cameras]]
name = "c"
namespace = "/rig/c"
frame_id = "c_optical_frame"
width = 640
height = 480
hfov_rad = 0.7
relative_to = "a"
translation_m = [0.06, 0.005, 0.0]
rotation_rpy_rad = [0.02, -0.06, 0.01]

[[targets]]
name = "checkerboard"
kind = "checkerboard"
inner_corners = [7, 6]
square_m = 0.01

[targets.motion]
kind = "random_hold"
hold_s = 0.5
aim = "image"
visible_in = "any"
distance_m = [0.2, 0.35]
max_tilt_rad = 0.8
partial_view_probability = 0.0
"""
CAMERAS = ["/rig/a", "/rig/b", "/rig/c"]


@pytest.fixture(scope="module")
@renders
def rig3_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """36 frames per camera: 12 held poses."""
    tmp = tmp_path_factory.mktemp("rig3")
    spec = tmp / "rig3.toml"
    spec.write_text(SPEC)
    return record(spec, tmp / "rig3.mcap", "--duration", "6")


@pytest.fixture(scope="module")
def rig3(rig3_log: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rig3_calibration") / "out"
    return calibrate(rig3_log, out, *(a for ns in CAMERAS for a in ("--camera", ns)))


def true_camera_from_reference(log: Path) -> dict[str, np.ndarray]:
    """Every camera's true pose relative to the first, from the log's scenario record."""
    poses = {c["namespace"]: np.array(c["world_from_camera"]) for c in scenario(log)["cameras"]}
    reference = poses[CAMERAS[0]]
    return {ns: np.linalg.inv(pose) @ reference for ns, pose in poses.items()}


def test_every_extrinsic_within_3_sigma_of_the_truth(rig3: Path, rig3_log: Path) -> None:
    rig = summary(rig3)["rig"]
    assert rig["reference"] == CAMERAS[0] and rig["convention"] == "camera_from_reference"
    assert [c["namespace"] for c in rig["cameras"]] == CAMERAS
    truth = true_camera_from_reference(rig3_log)
    for camera in rig["cameras"][1:]:
        true = truth[camera["namespace"]]
        rotation_error = rotation_vectors(
            (_matrix(camera["rotation_rad"]) @ true[:3, :3].T)[None])[0]
        translation_error = np.array(camera["translation_m"]) - true[:3, 3]
        for error, std in ((rotation_error, camera["rotation_std_rad"]),
                           (translation_error, camera["translation_std_m"])):
            assert all(s > 0 for s in std)
            assert np.all(np.abs(error) < 3 * np.array(std)), (camera["namespace"], error, std)
        # the summary's own comparison says the same
        np.testing.assert_allclose(camera["truth"]["translation_error_m"], translation_error,
                                   atol=1e-12)
    pairs = {(p["first"], p["second"]): p for p in rig["pairs"]}
    assert set(pairs) == {("/rig/a", "/rig/b"), ("/rig/a", "/rig/c"), ("/rig/b", "/rig/c")}
    for (first, second), pair in pairs.items():
        true = truth[second] @ np.linalg.inv(truth[first])
        assert pair["joint_views"] >= 5
        assert abs(pair["baseline_m"] - np.linalg.norm(true[:3, 3])) < 3 * pair["baseline_std_m"]
        assert pair["truth"]["baseline_m"] == pytest.approx(np.linalg.norm(true[:3, 3]))
        assert pair["epipolar_rms_px"] < 0.1


def _matrix(rotation_rad: list[float]) -> np.ndarray:
    import cv2

    matrix: np.ndarray = cv2.Rodrigues(np.array(rotation_rad))[0]
    return matrix


def test_files_per_camera_rig_yaml_and_report(rig3: Path) -> None:
    data = summary(rig3)
    for namespace in CAMERAS:
        stem = namespace.strip("/").replace("/", "_")
        calibration = load_calibration(rig3 / f"{stem}.yaml")
        (camera,) = (c for c in data["cameras"] if c["namespace"] == namespace)
        assert calibration.camera_info.k[0, 0] == camera["parameters"]["fx"]["value"]
        np.testing.assert_array_equal(calibration.camera_info.r, np.eye(3))
        for figure in FIGURES:
            assert (rig3 / f"{stem}_{figure}").is_file()
    assert not (rig3 / "ost.txt").exists() and not (rig3 / "rectified.png").exists()
    rig: Any = YAML(typ="safe").load((rig3 / "rig.yaml").read_text())
    assert rig["convention"] == "camera_from_reference" and rig["reference"] == "/rig/a"
    for written, summarised in zip(rig["cameras"], data["rig"]["cameras"], strict=True):
        assert written["translation_m"] == summarised["translation_m"]
        assert written["translation_std_m"] == summarised["translation_std_m"]
        np.testing.assert_allclose(np.reshape(written["rotation_matrix"], (3, 3)),
                                   _matrix(summarised["rotation_rad"]), atol=1e-12)
    assert [p["baseline_m"] for p in rig["pairs"]] == \
        [p["baseline_m"] for p in data["rig"]["pairs"]]
    report = (rig3 / "report.md").read_text()
    assert "## Rig" in report and "| /rig/b → /rig/c |" in report
    assert all(f"## {ns}" in report for ns in CAMERAS)


def test_two_cameras_as_a_rig_agree_with_the_stereo_pair(rig3_log: Path,
                                                         tmp_path: Path) -> None:
    stereo = calibrate(rig3_log, tmp_path / "stereo", "--left", "/rig/a", "--right", "/rig/c",
                       "--no-report")
    rig = calibrate(rig3_log, tmp_path / "rig", "--rig", "/rig/a,/rig/c", "--no-report")
    s, r = summary(stereo), summary(rig)
    (pair,) = r["rig"]["pairs"]
    for key in ("baseline_m", "baseline_std_m", "rotation_deg", "rotation_std_deg",
                "epipolar_rms_px", "translation_m"):
        assert pair[key] == s["stereo"][key], key
    assert r["cameras"] == s["cameras"]
    assert sorted(p.name for p in rig.iterdir()) == ["calibration.json", "rig.yaml",
                                                     "rig_a.yaml", "rig_c.yaml"]
    assert math.isclose(r["rig"]["cameras"][1]["rotation_deg"], pair["rotation_deg"])


@pytest.mark.parametrize(("options", "message"), [
    (["--rig", "/rig/a"], "a rig has two cameras or more"),
    (["--camera", "/rig/a", "--left", "/rig/b", "--right", "/rig/c"],
     "give either --camera/--rig or --left/--right"),
    (["--camera", "/rig/a", "--camera", "/rig/a/image_raw"], "a camera is named twice"),
    (["--rig", "/rig/a,/rig/b", "--check", "--calibration", "x.yaml"], "not a rig"),
])
def test_rig_usage_errors(rig3_log: Path, tmp_path: Path, options: list[str],
                          message: str) -> None:
    err = io.StringIO()
    code: int | str | None
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(["calibrate", str(rig3_log), *BOARD, "-o", str(tmp_path / "out"),
                         "--no-progress", *options])
        except SystemExit as exit_:  # argparse's own errors
            code = exit_.code
    result = CliRun(code if isinstance(code, int) else 1, "", err.getvalue())
    assert result.code != 0 and message in result.err
    assert "Traceback" not in result.err and len(result.err.strip().splitlines()) <= 3
    assert not (tmp_path / "out").exists()


def test_json_round_trips(rig3: Path) -> None:
    from replay.records import CalibrationSummary

    text = (rig3 / "calibration.json").read_text()
    again = CalibrationSummary.from_json_text(text)
    assert again.rig is not None and len(again.rig.pairs) == 3
    assert json.loads(again.to_json_text(indent=1)) == json.loads(text)

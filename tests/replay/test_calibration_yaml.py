"""camera_info_manager YAML: round trip, ROS-written files, errors that name the file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from replay import CameraInfo, ReplayError
from replay.calibration_yaml import (
    CalibrationFileError,
    calibration_from_yaml,
    calibration_to_yaml,
    load_calibration,
    save_calibration,
)
from tests.outputs import temp_outputs

# The chapter's stereo calibration of the simulated left camera, as cameracalibrator.py saves it
ROS_LEFT_YAML = """\
image_width: 640
image_height: 480
camera_name: stereo_camera/left
camera_matrix:
  rows: 3
  cols: 3
  data: [1033.951, 0, 319.5, 0, 1033.951, 239.5, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.0017, 0.0412, 0, 0, 0]
rectification_matrix:
  rows: 3
  cols: 3
  data: [0.99999, 0.0001, -0.0002, -0.0001, 1, 0.00005, 0.0002, -0.00005, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [1035.1, 0, 319.5, 0, 0, 1035.1, 239.5, 0, 0, 0, 1, 0]
"""


def model(distortion_model: str, n: int) -> CameraInfo:
    rng = np.random.default_rng(n)
    k = np.array([[1034.4730293 + rng.normal(), 0, 319.5], [0, 1034.47 / 3, 239.5], [0, 0, 1]])
    p = np.hstack([k, [[-20.689460586], [0.0], [0.0]]])
    return CameraInfo(0, "", 640, 480, distortion_model, rng.normal(0, 0.1, n), k,
                      np.eye(3) + rng.normal(0, 1e-4, (3, 3)), p)


@pytest.mark.parametrize(("distortion_model", "n"),
                         [("plumb_bob", 5), ("rational_polynomial", 8), ("plumb_bob", 0)])
def test_save_load_round_trip_is_exact(tmp_path: Path, distortion_model: str, n: int) -> None:
    info = model(distortion_model, n)
    path = tmp_path / "ost.yaml"
    save_calibration(path, info, camera_name="narrow_stereo/left")
    loaded = load_calibration(path)
    assert loaded.camera_name == "narrow_stereo/left"
    assert loaded.camera_info == info
    assert temp_outputs(tmp_path) == []


@pytest.mark.parametrize("name", ["", "true", "my camera: 1", "123"])
def test_odd_camera_names_survive(name: str) -> None:
    text = calibration_to_yaml(model("plumb_bob", 5), camera_name=name)
    assert calibration_from_yaml(text).camera_name == name


def test_reads_what_ros_writes() -> None:
    calibration = calibration_from_yaml(ROS_LEFT_YAML)
    info = calibration.camera_info
    assert calibration.camera_name == "stereo_camera/left"
    assert (info.width, info.height, info.distortion_model) == (640, 480, "plumb_bob")
    assert info.k[0, 0] == 1033.951 and info.k[1, 2] == 239.5
    assert info.d.tolist() == [-0.0017, 0.0412, 0, 0, 0]
    assert info.p.shape == (3, 4) and info.p[0, 0] == 1035.1
    assert info.r[0, 1] == 0.0001


@pytest.mark.parametrize(("edit", "message"), [
    (("  rows: 3\n  cols: 4\n  data: [1035.1, 0, 319.5, 0, 0, 1035.1, 239.5, 0, 0, 0, 1, 0]",
      "  rows: 3\n  cols: 4\n  data: [1035.1, 0, 319.5]"), "projection_matrix: expected 3x4"),
    (("image_width: 640\n", ""), "missing image_width"),
    (("camera_matrix:\n", "camera_matrix: [\n"), "not valid YAML"),
    (("data: [-0.0017", "data: [abc"), "distortion_coefficients: data must be"),
])
def test_malformed_files_name_the_path_and_key(
    tmp_path: Path, edit: tuple[str, str], message: str
) -> None:
    path = tmp_path / "left.yaml"
    path.write_text(ROS_LEFT_YAML.replace(*edit))
    with pytest.raises(CalibrationFileError, match=message) as raised:
        load_calibration(path)
    assert str(raised.value).startswith(f"{path}: ")
    assert isinstance(raised.value, ReplayError)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(CalibrationFileError, match="does not exist"):
        load_calibration(tmp_path / "nope.yaml")

"""Step kinds made from the requests: a ChArUco calibration with every board option, and
the ``convert`` and ``export`` steps, their outputs read back by independent readers."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import pytest
import yaml
from mcap.reader import make_reader

from camlog.cli import main
from replay import open_reader
from tests.camlog.conftest import record, spec_variant
from tests.slow import renders

FRAMES = 60
PIPELINE = """
[[steps]]
run = "calibrate"
size = "8x6"
square = 0.011
pattern = "charuco"
marker = 0.008
dictionary = "DICT_5X5_100"
model = "rational_polynomial"
camera = "/charuco_camera"
camera_name = "charuco"
report = false

[[steps]]
run = "convert"
input = "log"
topics = ["/charuco_camera/image_raw", "/charuco_camera/camera_info"]
compress = "png"
end = 1.0

[[steps]]
run = "export"
input = "log"
topic = "/charuco_camera/image_raw"
every = 10
format = "jpg"
"""


@pytest.fixture(scope="module")
@renders
def charuco_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """mono_charuco (rational_polynomial lens), 60 frames at 640x480: 20 poses."""
    tmp = tmp_path_factory.mktemp("charuco_batch")
    spec = spec_variant("mono_charuco", tmp, {"hold_s = 0.25": "hold_s = 0.1"})
    return record(spec, tmp / "charuco.mcap", "--frames", str(FRAMES))


def test_calibrate_convert_and_export_steps(charuco_log: Path, tmp_path: Path) -> None:
    pipeline = tmp_path / "pipe.toml"
    pipeline.write_text(PIPELINE)
    out = tmp_path / "out"
    assert main(["batch", str(pipeline), str(charuco_log), "-o", str(out), "-j", "1",
                 "--no-progress"]) == 0
    folder = out / "charuco"
    (log_status,) = json.loads((out / "batch_summary.json").read_text())["logs"]
    assert log_status["status"] == "ok", log_status

    # calibrate: the ChArUco board and the rational model reached the solver
    ost = yaml.safe_load((folder / "01_calibrate" / "ost.yaml").read_text())
    assert ost["camera_name"] == "charuco"
    assert ost["distortion_model"] == "rational_polynomial"
    assert len(ost["distortion_coefficients"]["data"]) == 8
    fx = ost["camera_matrix"]["data"][0]
    assert fx == pytest.approx(512.3, rel=0.02)
    assert not (folder / "01_calibrate" / "calibration.mcap").exists()  # report = false

    # convert: the chosen topics of the first second, images as PNG, read by mcap itself
    with open_reader(charuco_log) as reader:
        first_ns = reader.start_ns
    counts: dict[str, int] = {}
    schemas: dict[str, str] = {}
    with (folder / "02_convert" / "converted.mcap").open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            schemas[channel.topic] = schema.name
            assert message.log_time < (first_ns or 0) + 1_000_000_000
    assert schemas == {"/charuco_camera/image_raw/compressed": "sensor_msgs/msg/CompressedImage",
                       "/charuco_camera/camera_info": "sensor_msgs/msg/CameraInfo"}
    assert counts["/charuco_camera/image_raw/compressed"] == 30  # 30 Hz, [0, 1 s)

    # export: every 10th frame as a JPEG named by its stamp, read by OpenCV
    files = sorted((folder / "03_export" / "images").glob("*.jpg"))
    assert len(files) == FRAMES // 10
    for file in files:
        image = cv2.imread(str(file))
        assert image is not None and image.shape == (480, 640, 3)
    with open_reader(charuco_log) as reader:
        stamps = [r.message.stamp_ns for r in reader.messages(["/charuco_camera/image_raw"])]
    assert [int(f.stem) for f in files] == stamps[::10]

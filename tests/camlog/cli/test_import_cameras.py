"""A camera is named by its namespace or by its image topic, from ``import`` to ``calibrate``
and ``resync``: frames exported from the golden checkerboard log, imported and calibrated."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from camlog.cli import main
from replay import Image, open_reader, open_writer
from tests.conftest import REPO_ROOT

GOLDEN = REPO_ROOT / "datasets/golden/mono_checkerboard-seed0-640x480-f240.mcap"
BOARD = ["--size", "7x6", "--square", "0.01"]


@pytest.fixture(scope="module")
def frames(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """20 rendered checkerboard images (every 12th frame of the golden log) as PNG files."""
    folder = tmp_path_factory.mktemp("checkerboard") / "frames"
    assert main(["export", str(GOLDEN), "--topic", "/simple_camera/image_raw", "-o",
                 str(folder), "--every", "12", "--no-progress"]) == 0
    return folder


def topics(log: Path) -> list[str]:
    with open_reader(log) as reader:
        return sorted(reader.topics)


@pytest.mark.parametrize(("option", "value", "image_topic"), [
    ("--topic", "/fisheye", "/fisheye/image_raw"),
    ("--camera", "/fisheye/", "/fisheye/image_raw"),
    ("--camera", "/fisheye/image_raw", "/fisheye/image_raw"),
    ("--topic", "/fisheye/image_rect", "/fisheye/image_rect"),
])
def test_import_writes_the_cameras_image_topic(frames: Path, tmp_path: Path, option: str,
                                               value: str, image_topic: str) -> None:
    log = tmp_path / "fish.mcap"
    assert main(["import", str(frames), "-o", str(log), option, value, "--no-progress"]) == 0
    assert topics(log) == [image_topic]


def test_import_refuses_a_compressed_topic(frames: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "fish.mcap"
    assert main(["import", str(frames), "-o", str(log), "--camera",
                 "/fisheye/image_raw/compressed", "--no-progress"]) == 1
    assert capsys.readouterr().err == (
        "camlog import: error: /fisheye/image_raw/compressed is a topic for compressed images "
        "or video; import writes raw images: name the camera /fisheye (images on "
        "/fisheye/image_raw)\n")
    assert not log.exists()


@pytest.mark.slow
@pytest.mark.parametrize("camera", ["/fisheye", "/fisheye/image_raw"])
def test_an_imported_camera_calibrates_by_namespace_or_image_topic(
        frames: Path, tmp_path: Path, camera: str,
        capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "fish.mcap"
    assert main(["import", str(frames), "-o", str(log), "--topic", "/fisheye",
                 "--no-progress"]) == 0
    out = tmp_path / "calibration"
    assert main(["calibrate", str(log), *BOARD, "--camera", camera, "-o", str(out),
                 "--no-report", "--no-progress"]) == 0
    assert capsys.readouterr().out.splitlines()[2].startswith("/fisheye: 16 views")
    summary = json.loads((out / "calibration.json").read_text())
    assert [c["namespace"] for c in summary["cameras"]] == ["/fisheye"]


def bare_topic_log(path: Path, frames: Path) -> None:
    """The frames on the image topic ``/fisheye`` itself, without camera_info (as an import
    before camera namespaces, or another tool, writes them)."""
    import cv2

    with open_writer(path) as writer:
        for i, file in enumerate(sorted(frames.iterdir())):
            rgb = cv2.cvtColor(cv2.imread(str(file)), cv2.COLOR_BGR2RGB)
            stamp_ns = 1_000_000_000 + i * 100_000_000
            writer.write("/fisheye", Image(stamp_ns, "fisheye", "rgb8", rgb),
                         log_time_ns=stamp_ns)


@pytest.mark.slow
def test_a_bare_image_topic_is_a_camera(frames: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "bare.mcap"
    bare_topic_log(log, frames)
    for options in (["--camera", "/fisheye"], []):  # named, or the log's only camera
        out = tmp_path / f"calibration{len(options)}"
        assert main(["calibrate", str(log), *BOARD, *options, "-o", str(out), "--no-report",
                     "--no-progress"]) == 0
        assert "/fisheye: 16 views" in capsys.readouterr().out
    assert main(["calibrate", str(log), *BOARD, "--camera", "/fish", "-o",
                 str(tmp_path / "nope"), "--no-progress"]) == 1
    assert capsys.readouterr().err.endswith(
        "cameras, by namespace (image topic), either of which names one: "
        "/fisheye (/fisheye))\n")


def test_resync_takes_image_topics(tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "pair.mcap"
    with open_writer(log) as writer:
        for i in range(6):
            pixels = np.full((8, 8), 20 * i, np.uint8)
            writer.write("/a", Image(i * 100_000_000, "a", "mono8", pixels))
            writer.write("/b/image_raw", Image(i * 100_000_000 + 3_000_000, "b", "mono8",
                                               pixels))
    out = tmp_path / "synced.mcap"
    assert main(["resync", str(log), "-o", str(out), "--left", "/a", "--right",
                 "/b/image_raw"]) == 0
    capsys.readouterr()
    with open_reader(out) as reader:
        assert reader.topics["/stereo_sync/left/image_raw"].count == 6
        assert reader.topics["/stereo_sync/right/image_raw"].count == 6

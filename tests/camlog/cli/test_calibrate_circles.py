"""``camlog calibrate`` on a circle grid: the circles' diameter measured from the images by
default, or given with ``--diameter``, and said which."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from processors.calibration.board import make_board
from replay import CameraInfo, Image, open_writer
from tests.cli import run_cli
from tests.slow import renders

from ...processors.calibration.synthetic import K_TRUE, circle_texture, pose, warp_texture

BOARD = make_board("4x11", 0.01, "acircles")
FLAGS = ["-s", "4x11", "-q", "0.01", "-p", "acircles", "--camera", "/cam", "--no-progress",
         "--no-report"]
PX_PER_M = 4000.0


@pytest.fixture(scope="module")
@renders
def circles_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Sixteen pinhole views (K_TRUE) of discs 1 cm across, tilted every way."""
    path = tmp_path_factory.mktemp("circles") / "circles.mcap"
    texture, origin = circle_texture(BOARD, PX_PER_M, radius_m=0.005)
    rng = np.random.default_rng(3)
    with open_writer(path) as writer:
        for i in range(16):
            rotation = np.array([*rng.uniform(-0.5, 0.5, 2), rng.uniform(-0.4, 0.4)])
            camera_from_board = pose(rotation, np.array([*rng.uniform(-0.06, 0.0, 2), 0.3]))
            image = warp_texture(texture, PX_PER_M, origin, K_TRUE, camera_from_board)
            stamp = 1_000_000_000 + i * 100_000_000
            writer.write("/cam/image_raw", Image(stamp, "cam", "mono8", image), log_time_ns=stamp)
            writer.write("/cam/camera_info", CameraInfo(stamp, "cam", 640, 480, "plumb_bob",
                                                        np.zeros(5), K_TRUE), log_time_ns=stamp)
    return path


def test_the_diameter_is_measured_from_the_images(circles_log: Path, tmp_path: Path) -> None:
    result = run_cli("calibrate", circles_log, *FLAGS, "-o", tmp_path / "out")
    assert result.code == 0, result.err
    assert "circle diameter 0.0100" in result.out and "(measured from the images)" in result.out
    board = json.loads((tmp_path / "out" / "calibration.json").read_text())["board"]
    assert board["diameter_measured"] is True
    assert abs(board["diameter_m"] / 0.01 - 1) < 3e-3


def test_a_given_diameter_is_used_and_checked(circles_log: Path, tmp_path: Path) -> None:
    result = run_cli("calibrate", circles_log, *FLAGS, "--diameter", "0.008", "-o",
                     tmp_path / "out")
    assert result.code == 0, result.err
    assert "circle diameter 0.00800 m (given; the images show 0.0100" in result.out
    assert "--diameter 0.008 m, but the images show circles 0.0100" in result.err
    board = json.loads((tmp_path / "out" / "calibration.json").read_text())["board"]
    assert board["diameter_m"] == 0.008 and board["diameter_measured"] is False


def reprojection_median(text: str) -> float:
    """The median of ``--check``'s reprojection RMS line."""
    line = next(t for t in text.splitlines() if t.startswith("reprojection RMS:"))
    return float(line.split("median ")[1].split()[0])


def test_check_predicts_the_discs_centroids(circles_log: Path, tmp_path: Path) -> None:
    """``--check`` models the circles as ``calibrate`` does: with the diameter the images show
    the reprojection is that of the discs' centroids; with circles far too small (nearly
    points) the offset of the centroids from the centres shows as error."""
    assert run_cli("calibrate", circles_log, *FLAGS, "-o", tmp_path / "out").code == 0
    check = [*FLAGS, "--check", "--calibration", tmp_path / "out" / "ost.yaml"]
    measured = run_cli("calibrate", circles_log, *check)
    assert measured.code == 0, measured.err
    assert "circle diameter 0.0100" in measured.out and "(measured from the images)" in measured.out
    points = run_cli("calibrate", circles_log, *check, "--diameter", "0.001")
    assert points.code == 0, points.err
    assert "circle diameter 0.00100 m (given; the images show 0.0100" in points.out
    assert reprojection_median(measured.out) < 0.6 * reprojection_median(points.out)

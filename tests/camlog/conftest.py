"""Simulated calibration recordings shared by the camlog tests, each rendered once per
session, and calibrations of them made by the flow (``calibrate_log``).

The scenarios hold the board 0.5 s per pose; these variants hold it 0.1 s (3 frames at
30 Hz), so a few hundred frames show about a hundred poses, at the 640x480 the calibration
accuracy is stated for.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from replay.records import CalibrationSummary, CameraSummary
from tests.cli import cli
from tests.slow import renders
from tests.workers import made_once

SCENARIOS = Path(__file__).resolve().parents[2] / "datasets" / "scenarios"
HOLD = "hold_s = 0.5"
PARTIAL = "partial_view_probability = 0.05"


def spec_variant(name: str, folder: Path, replacements: dict[str, str]) -> Path:
    """A copy of a built-in scenario spec with some lines replaced (each must exist once)."""
    text = (SCENARIOS / f"{name}.toml").read_text()
    for old, new in replacements.items():
        assert text.count(old) == 1, f"{name}.toml: expected one {old!r}"
        text = text.replace(old, new)
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


def record(spec: Path | str, output: Path, *options: str) -> Path:
    """``camlog record`` of a spec at 640x480 into ``output``."""
    cli("record", spec, "-o", output, "--resolution", "640x480", "--no-progress", *options)
    return output


@pytest.fixture(scope="session")
@renders
@made_once
def rig_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """stereo_checkerboard, 240 frames per camera: 80 poses seen by an ideal 0.02 m rig."""
    tmp = tmp_path_factory.mktemp("rig")
    spec = spec_variant("stereo_checkerboard", tmp, {HOLD: "hold_s = 0.1"})
    return record(spec, tmp / "rig.mcap", "--frames", "240")


@pytest.fixture(scope="session")
@renders
@made_once
def plumb_bob_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """mono_checkerboard through a k1 = -0.2, k2 = 0.05 lens, 330 frames (110 poses)."""
    tmp = tmp_path_factory.mktemp("plumb_bob")
    spec = spec_variant("mono_checkerboard", tmp, {HOLD: "hold_s = 0.1"})
    return record(spec, tmp / "plumb_bob.mcap", "--frames", "330",
                  "--distortion", "plumb_bob:-0.2,0.05,0,0,0")


@pytest.fixture(scope="session")
@renders
@made_once
def unsynced_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """stereo_unsynced (own stamps, 7 ms phase, jitter, drops), 120 frames (40 poses), and
    the board cut by the image border in 30 % of the poses."""
    tmp = tmp_path_factory.mktemp("unsynced")
    spec = spec_variant("stereo_unsynced", tmp, {
        HOLD: "hold_s = 0.1", PARTIAL: "partial_view_probability = 0.3"})
    return record(spec, tmp / "unsynced.mcap", "--frames", "120")


@pytest.fixture(scope="session")
@renders
@made_once
def few_poses_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """mono_checkerboard as built in (0.5 s per pose), 30 frames: two board poses."""
    tmp = tmp_path_factory.mktemp("few_poses")
    return record("mono_checkerboard", tmp / "few.mcap", "--frames", "30")


# --- calibrations of those recordings, made by the flow ----------------------------------------

LEFT, RIGHT = "/stereo_camera/left", "/stereo_camera/right"


@dataclass(frozen=True)
class Calibrated:
    """A calibration's output folder and its summary (what calibration.json holds)."""

    folder: Path
    summary: CalibrationSummary

    def camera(self, namespace: str) -> CameraSummary:
        """The summary of one calibrated camera."""
        (camera,) = (c for c in self.summary.cameras if c.namespace == namespace)
        return camera


def scenario(log: Path) -> dict[str, Any]:
    """The log's scenario record (``/camlog/scenario``) as JSON data."""
    from replay import Text, open_reader

    with open_reader(log) as reader:
        (record,) = list(reader.messages(["/camlog/scenario"]))
    assert isinstance(record.message, Text)
    data: dict[str, Any] = json.loads(record.message.data)
    return data


def calibrate(log: Path, output: Path, **fields: Any) -> Calibrated:
    """``calibrate_log`` of a 7x6 board of 0.01 m squares (unless ``fields`` say otherwise)
    into ``output``, without progress bars."""
    from camlog.calibrate.flow import calibrate_log
    from camlog.requests.calibrate import CalibrateRequest

    request = CalibrateRequest(**{"log": log, "output": output, "size": "7x6", "square": 0.01,
                                  "progress": False, **fields})
    run = calibrate_log(request)
    return Calibrated(run.output_dir, run.summary)


@pytest.fixture(scope="session")
def rig_left(rig_log: Path, tmp_path_factory: pytest.TempPathFactory) -> Calibrated:
    """The rig's left camera alone, default options (tangential distortion if the views
    show it: this simulated lens has none)."""
    return calibrate(rig_log, tmp_path_factory.mktemp("calibrated") / "mono", camera=(LEFT,))


@pytest.fixture(scope="session")
def rig_stereo(rig_log: Path, tmp_path_factory: pytest.TempPathFactory) -> Calibrated:
    """The rig as a stereo pair."""
    return calibrate(rig_log, tmp_path_factory.mktemp("calibrated") / "stereo", left=LEFT,
                     right=RIGHT)


@pytest.fixture(scope="session")
@renders
@made_once
def late_board_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """stereo_moving_board for 20 s at 320x240 without motion blur (to render fast), the
    right camera stamping 17 ms late (``--latency right:17``)."""
    tmp = tmp_path_factory.mktemp("late_board")
    spec = spec_variant("stereo_moving_board", tmp, {
        "exposure_s = 0.004\nposition_m": "position_m",
        "exposure_s = 0.004\nrelative_to": "relative_to"})
    cli("record", spec, "-o", tmp / "late.mcap", "--resolution", "320x240", "--duration", "20",
        "--latency", "right:17", "--no-progress")
    return tmp / "late.mcap"

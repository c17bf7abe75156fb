"""Small camlog logs made through the command line, once per test session.

Used by the view / play / convert tests: a red_block rig with processor outputs, a mono
calibration log and a resynced stereo log, all at 320x240 so that each takes about a second.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.cli import cli
from tests.slow import renders

SCENARIOS = Path(__file__).resolve().parents[1] / "datasets" / "scenarios"
LEFT = "/stereo_camera/left"
RED_FRAMES = 20


@pytest.fixture(scope="session")
@renders
def red_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """red_block, 20 frames per camera at 320x240: scenario, camera_info, ground truth."""
    path = tmp_path_factory.mktemp("red") / "red.mcap"
    cli("record", "red_block", "--frames", str(RED_FRAMES), "--resolution", "320x240",
        "-o", str(path), "--no-progress")
    return path


@pytest.fixture(scope="session")
def red_processed_log(red_log: Path) -> Path:
    """red_log plus red pixels and edges of the left camera (every input copied through)."""
    path = red_log.with_name("red_processed.mcap")
    cli("process", str(red_log), "--topic", f"{LEFT}/image_raw", "--red-pixels", "--edges",
        "-o", str(path))
    return path


def held_for(folder: Path, scenario: str, *, hold_s: float) -> Path:
    """A copy of a scenario in ``folder`` whose board holds each pose ``hold_s`` instead of
    0.5 s (more poses in a few frames)."""
    text = (SCENARIOS / f"{scenario}.toml").read_text()
    assert text.count("hold_s = 0.5") == 1
    spec = folder / f"{scenario}.toml"
    spec.write_text(text.replace("hold_s = 0.5", f"hold_s = {hold_s}"))
    return spec


@pytest.fixture(scope="session")
@renders
def mono_calibration_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``camlog calibrate``'s calibration.mcap of 120 frames of mono_checkerboard (board
    held 0.1 s per pose, so about 40 poses) at 320x240."""
    tmp = tmp_path_factory.mktemp("mono_calibration")
    spec = held_for(tmp, "mono_checkerboard", hold_s=0.1)
    log = tmp / "mono.mcap"
    cli("record", str(spec), "--frames", "120", "--resolution", "320x240", "-o", str(log),
        "--no-progress")
    cli("calibrate", str(log), "--size", "7x6", "--square", "0.01", "-o", str(tmp / "cal"),
        "--no-progress")
    return tmp / "cal" / "calibration.mcap"


@pytest.fixture(scope="session")
@renders
def resynced_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """stereo_unsynced, 20 frames at 320x240, and its /stereo_sync pairs."""
    tmp = tmp_path_factory.mktemp("resynced")
    cli("record", "stereo_unsynced", "--frames", "20", "--resolution", "320x240",
        "-o", str(tmp / "unsynced.mcap"), "--no-progress")
    cli("resync", str(tmp / "unsynced.mcap"), "-o", str(tmp / "synced.mcap"))
    return tmp / "synced.mcap"


def chunked_camera_log(path: Path, frames: int = 40) -> list[int]:
    """A mono camera log (``/cam/image_raw`` 80x60 noise + ``/cam/camera_info``) in small
    MCAP chunks, so that damage hits only part of it. Returns the image log times."""
    import numpy as np

    from replay import CameraInfo, Image, open_writer

    k = np.array([[80.0, 0, 39.5], [0, 80.0, 29.5], [0, 0, 1]])
    stamps = [1_700_000_000_000_000_000 + i * 33_000_000 for i in range(frames)]
    with open_writer(path, chunk_size=20_000) as writer:
        for i, stamp in enumerate(stamps):
            pixels = np.random.default_rng(i).integers(0, 256, (60, 80), dtype=np.uint8)
            writer.write("/cam/camera_info", CameraInfo(stamp, "cam", 80, 60, "plumb_bob",
                                                        np.zeros(5), k))
            writer.write("/cam/image_raw", Image(stamp, "cam", "mono8", pixels))
    return stamps


def corrupt_middle_chunk(path: Path) -> int:
    """Flip 32 bytes inside the middle chunk of an MCAP file; returns that chunk's first
    log time (everything before it is intact)."""
    from mcap.reader import make_reader

    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    chunks = sorted((c.chunk_start_offset, c.chunk_length, c.message_start_time)
                    for c in summary.chunk_indexes)
    assert len(chunks) >= 4
    offset, length, first_ns = chunks[len(chunks) // 2]
    data = bytearray(path.read_bytes())
    middle = offset + length // 2
    data[middle: middle + 32] = bytes(b ^ 0xFF for b in data[middle: middle + 32])
    path.write_bytes(bytes(data))
    return first_ns

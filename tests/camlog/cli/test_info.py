"""``camlog info`` through the real command line entry point."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camlog.cli import main
from replay import Image, Text, open_writer


def write_camera_log(path: Path, frames: int = 4, **options: object) -> None:
    with open_writer(path, **options) as writer:  # type: ignore[arg-type]
        for i in range(frames):
            pixels = np.random.default_rng(i).integers(0, 256, (64, 64), dtype=np.uint8)
            writer.write("/cam/image_raw", Image(i * 50_000_000, "cam", "mono8", pixels))
        writer.write("/notes", Text("hi"), log_time_ns=1)


def test_info_prints_the_summary(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "run.mcap"
    write_camera_log(path)
    assert main(["info", str(path)]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    lines = out.splitlines()
    assert lines[0] == f"path:      {path}"
    assert "format:    mcap" in lines
    assert "messages:  5" in lines
    assert "duration:  0.150 s" in lines
    (image_row,) = [line for line in lines if line.strip().startswith("/cam/image_raw")]
    assert image_row.split() == ["/cam/image_raw", "sensor_msgs/msg/Image", "4", "20.00",
                                 "mono8", "64x64"]


def test_info_of_a_rosbag2_directory(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "run"
    write_camera_log(path, fmt="rosbag2-sqlite3")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "format:    rosbag2 (sqlite3)" in out
    size = sum(f.stat().st_size for f in path.iterdir())
    assert f"({size} bytes)" in out


def test_missing_log_is_one_error_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "nope.mcap"
    assert main(["info", str(path)]) == 1
    out, err = capsys.readouterr()
    assert out == ""
    assert err == f"camlog info: error: {path} does not exist\n"


def _corrupt(path: Path) -> None:
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 64] = bytes(b ^ 0xFF for b in data[middle : middle + 64])
    path.write_bytes(bytes(data))


def test_corrupt_log_fails_and_recover_reads_the_rest(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad.mcap"
    write_camera_log(path, frames=20, chunk_size=8_000)
    _corrupt(path)
    assert main(["info", "--verify", str(path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith(f"camlog info: error: {path} is corrupt")
    assert "--recover" in err

    assert main(["info", "--recover", str(path)]) == 0
    out, err = capsys.readouterr()
    assert "warning" not in out  # the summary alone on stdout, what is wrong on stderr
    warnings = err.splitlines()
    assert len(warnings) == 1 and warnings[0].startswith("warning: ") and str(path) in err
    (count_line,) = [line for line in out.splitlines() if line.startswith("messages:")]
    assert 0 < int(count_line.split()[1]) < 21


def test_log_argument_is_required(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["info"])
    assert exited.value.code == 2
    assert "LOG" in capsys.readouterr().err

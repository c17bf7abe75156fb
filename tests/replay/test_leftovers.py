"""Temporary outputs of unfinished runs: found beside the output a later run writes, and in a
folder, each with what to do with it."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

from replay import Image, open_writer
from replay.atomic import AtomicFolder, write_text_atomic
from replay.leftovers import format_age, leftovers_in, leftovers_of
from replay.sizes import format_size

HEX = "0123456789abcdef"


def unfinished_log(folder: Path, name: str) -> Path:
    """A log written under the temporary name a killed run leaves for ``name``."""
    path = folder / f".{name}.camlog-{HEX}.tmp"
    with open_writer(path, fmt="mcap") as writer:
        writer.write("/cam/image_raw", Image(0, "cam", "mono8", np.zeros((4, 4), np.uint8)))
    return path


def test_writing_an_output_names_its_leftover_once(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    leftover = unfinished_log(tmp_path, "run[1].mcap")
    capsys.readouterr()
    for _ in range(2):
        with open_writer(tmp_path / "run[1].mcap", overwrite=True) as writer:
            writer.write("/cam/image_raw",
                         Image(0, "cam", "mono8", np.zeros((4, 4), np.uint8)))
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"warning: {leftover} (file, ")
    assert line.endswith(f"recover it with: camlog convert --recover '{leftover}' "
                         f"'{tmp_path / 'run[1]-recovered.mcap'}'")


def test_a_folder_leftover_can_be_removed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    leftover = tmp_path / f".calib.camlog-{HEX}.tmp"
    leftover.mkdir()
    (leftover / "left.yaml").write_text("x: 1\n")
    with open_writer(leftover / "calibration.mcap") as writer:  # a log in it: still no log
        writer.write("/cam/image_raw", Image(0, "cam", "mono8", np.zeros((4, 4), np.uint8)))
    size = format_size(sum(f.stat().st_size for f in leftover.iterdir())).split(" (")[0]
    old_s = time.time() - 7200
    os.utime(leftover, (old_s, old_s))
    with AtomicFolder(tmp_path / "calib", ["left.yaml"], overwrite=False) as folder:
        (folder.path / "left.yaml").write_text("x: 2\n")
    (line,) = capsys.readouterr().err.splitlines()
    assert line == (f"warning: {leftover} (folder, {size}, 2 h old), left by a run that "
                    f"did not finish writing calib; it can be removed: rm -r {leftover}")
    assert leftover.is_dir()  # never deleted by a later run


def test_leftovers_in_a_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = unfinished_log(tmp_path, "rec.mcap")
    write_text_atomic(tmp_path / "notes.txt", "not a leftover")
    other = tmp_path / f".notes.txt.camlog-{HEX}.tmp"
    other.write_text("half")
    capsys.readouterr()
    found = leftovers_in(tmp_path)
    assert [(f.path, f.final, f.is_log) for f in found] == [
        (other, tmp_path / "notes.txt", False), (log, tmp_path / "rec.mcap", True)]
    assert leftovers_of(tmp_path / "rec.mcap") == found[1:]
    assert found[1].recovery(final_in_use=False).endswith(f"{log} {tmp_path / 'rec.mcap'}")
    assert leftovers_of(tmp_path / "rec") == []


@pytest.mark.parametrize(("age_s", "text"), [(0.4, "0 s"), (59, "59 s"), (61, "1 min"),
                                             (7300, "2 h"), (3 * 86_400, "3 days")])
def test_format_age(age_s: float, text: str) -> None:
    assert format_age(age_s) == text

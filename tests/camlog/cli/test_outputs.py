"""Output rules of every command: inputs are never replaced, and nothing camlog did not create
in the run is deleted (earlier runs' leftovers and users' files stay where they are)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from camlog.cli import main
from replay import open_reader
from tests.outputs import temp_outputs
from tests.recordings import chunked_camera_log

LEFT = "/stereo_camera/left"
QUICK = ["--frames", "2", "--resolution", "64x48", "--no-progress"]


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` with its bytes."""
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def killed_recording(folder: Path, final_name: str) -> tuple[Path, int]:
    """What a recording killed mid-way leaves: the first part of an MCAP under camlog's
    temporary name for ``final_name``. Returns it and the images of the complete log."""
    complete = folder / "complete.mcap"
    images = len(chunked_camera_log(complete))
    leftover = folder / f".{final_name}.camlog-0123456789abcdef.tmp"
    leftover.write_bytes(complete.read_bytes()[: complete.stat().st_size * 2 // 3])
    complete.unlink()
    return leftover, images


@pytest.mark.slow
def test_record_leaves_earlier_leftovers_and_user_files_alone(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    output = tmp_path / "run.mcap"
    leftover, _ = killed_recording(tmp_path, output.name)
    user_file = tmp_path / "run.mcap.partial"  # the name earlier versions used for their temp
    user_file.write_text("mine")
    before = snapshot(tmp_path)
    code, _, err = run(capsys, "record", "mono_checkerboard", "-o", str(output), *QUICK)
    # the leftover is named, with the command that recovers it, and left where it is
    assert code == 0
    (line,) = err.splitlines()
    assert line.startswith(f"warning: {leftover}") and "camlog convert --recover" in line
    assert snapshot(tmp_path) | {"run.mcap": b""} == before | {"run.mcap": b""}
    assert temp_outputs(tmp_path) == [leftover]


@pytest.mark.parametrize("name", ["crash.mcap.partial", ".crash.mcap.camlog-0123456789abcdef.tmp"])
def test_convert_recover_keeps_the_recording_it_recovers(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str) -> None:
    leftover, images = killed_recording(tmp_path, "crash.mcap")
    if leftover.name != name:
        leftover = leftover.rename(tmp_path / name)
    before = leftover.read_bytes()
    output = tmp_path / "crash.mcap"
    code, out, err = run(capsys, "convert", "--recover", str(leftover), str(output),
                         "--no-progress")
    assert code == 0, err
    assert leftover.read_bytes() == before
    with open_reader(output) as reader:
        recovered = reader.topics["/cam/image_raw"].count
    assert 0 < recovered < images
    assert f"wrote {output}" in out


def test_info_opens_a_leftover_and_says_what_it_is(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    leftover, _ = killed_recording(tmp_path, "crash.mcap")
    code, out, err = run(capsys, "info", str(leftover))
    assert code == 0
    assert "/cam/image_raw" in out
    assert "camlog's temporary output for crash.mcap" in out + err


def _inputs(red_log: Path, tmp_path: Path) -> dict[str, Path]:
    log = shutil.copy(red_log, tmp_path / "red.mcap")
    cal = tmp_path / "cal"
    cal.mkdir()
    shutil.copy(red_log, cal / "calibration.mcap")
    bag = tmp_path / "bag"
    assert main(["convert", str(log), str(bag), "--no-progress"]) == 0
    rrd_named = shutil.copy(red_log, tmp_path / "red.rrd")  # a log is found by content
    return {"log": Path(log), "cal": cal, "bag": bag, "rrd": Path(rrd_named)}


@pytest.mark.parametrize(("command", "needle"), [
    ("play {log} -o {log} --overwrite --rate 1000", "is the input"),
    ("process {log} --topic " + LEFT + "/image_raw --edges -o {log} --overwrite", "is the input"),
    ("resync {log} --left /a --right /b -o {log} --overwrite", "is the input"),
    ("convert {log} {log} --overwrite", "is the input"),
    ("convert {bag} {bag}/out.mcap", "inside the input"),
    ("convert {bag}/bag.mcap {bag} --overwrite", "holds the input"),
    ("convert {bag}/bag.mcap {bag}/out.mcap", "inside the input"),
    ("view {rrd} -o {rrd} --overwrite", "is the input"),
    ("calibrate {cal}/calibration.mcap --size 7x6 --square 0.01 --camera " + LEFT
     + " -o {cal} --overwrite", "is the input"),
    ("calibrate {bag} --size 7x6 --square 0.01 --camera " + LEFT + " -o {bag}", "is the input"),
    ("calibrate {bag} --size 7x6 --square 0.01 --camera " + LEFT + " -o {bag}/cal",
     "inside the input"),
])
def test_an_output_never_replaces_or_enters_an_input(
        red_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str,
        needle: str) -> None:
    paths = _inputs(red_log, tmp_path)
    before = snapshot(tmp_path)
    argv = command.format(**{k: str(v) for k, v in paths.items()}).split()
    code, _, err = run(capsys, *argv)
    assert code == 1
    assert err.count("\n") == 1 and err.startswith(f"camlog {argv[0]}: error: ")
    assert needle in err
    assert snapshot(tmp_path) == before

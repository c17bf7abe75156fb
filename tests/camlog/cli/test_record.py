"""``camlog record``: help, outputs, overwrite, crash safety and one-line errors."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from camlog.cli import build_parser, main
from replay import CameraInfo, Image, Text, open_reader
from tests.conftest import REPO_ROOT
from tests.outputs import temp_outputs

BUILTINS = sorted(p.stem for p in (REPO_ROOT / "datasets" / "scenarios").glob("*.toml"))
#: a recording that takes a fraction of a second
QUICK = ["--frames", "2", "--resolution", "64x48", "--no-progress"]


def camlog(*args: str, env: dict[str, str] | None = None,
           timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "camlog", *args], capture_output=True, text=True,
        env=env, timeout=timeout, cwd=REPO_ROOT, check=False,
    )


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_error_line(err: str, *needles: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("camlog record: error: ")
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0]
    return lines[0]


def seed_of(path: Path) -> int:
    with open_reader(path) as reader:
        (record,) = reader.messages(["/camlog/scenario"])
    assert isinstance(record.message, Text)
    seed: int = json.loads(record.message.data)["seed"]
    return seed


# --- help -----------------------------------------------------------------------------------

def test_top_level_help_lists_each_command_with_a_summary(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    for command in ("record", "info"):
        (line,) = [ln for ln in out.splitlines() if ln.split()[:1] == [command]]
        summary = line.split(None, 1)[1]
        assert len(summary.split()) >= 4, line


@pytest.mark.slow
def test_record_help_documents_every_option(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["record", "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    for option in ("--output", "--format", "--overwrite", "--seed", "--duration", "--frames",
                   "--resolution", "--hfov", "--intrinsics", "--distortion", "--noise",
                   "--supersample", "--encoding", "--no-progress"):
        assert option in out
    for name in BUILTINS:
        assert name in out
    (record_parser,) = [
        action.choices["record"] for action in build_parser()._actions
        if isinstance(action, argparse._SubParsersAction)
    ]
    for action in record_parser._actions:
        assert action.help, f"{action.option_strings or action.dest} has no help"
        for option in action.option_strings:
            assert option in out


# --- outputs --------------------------------------------------------------------------------

@pytest.mark.slow
def test_record_writes_the_output_and_no_partial(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "run.mcap"
    code, out, err = run(capsys, "record", "mono_checkerboard", "-o", str(output), *QUICK)
    assert (code, err) == (0, "")
    assert f"wrote {output}" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]
    with open_reader(output) as reader:
        images = [r.message for r in reader.messages(["/simple_camera/image_raw"])]
    assert len(images) == 2
    assert all(isinstance(i, Image) and i.pixels.shape == (48, 64, 3) for i in images)


@pytest.mark.slow
def test_record_a_fisheye_from_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "fisheye.mcap"
    code, _, err = run(capsys, "record", "-o", str(output), *QUICK, "--hfov", "1.2",
                       "--distortion", "equidistant:-0.04,0.0012,0,0")
    assert (code, err) == (0, "")
    with open_reader(output) as reader:
        infos = [r.message for r in reader.messages(["/simple_camera/camera_info"])]
    assert len(infos) == 2
    info = infos[0]
    assert isinstance(info, CameraInfo) and info.distortion_model == "equidistant"
    np.testing.assert_allclose(info.d, [-0.04, 0.0012, 0, 0])
    assert info.k[0, 0] == pytest.approx(32 / 0.6)  # equidistant: fx = (W / 2) / (hfov / 2)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "fmt"), [("run.bag", "ros1"), ("run", "rosbag2")])
def test_output_format_follows_the_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, fmt: str
) -> None:
    output = tmp_path / name
    code, _, err = run(capsys, "record", "-o", str(output), *QUICK)
    assert (code, err) == (0, "")
    with open_reader(output) as reader:
        assert reader.format_name.split()[0] == fmt
        assert reader.topics["/simple_camera/image_raw"].count == 2
    assert temp_outputs(tmp_path) == []


@pytest.mark.slow
def test_existing_output_needs_overwrite(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "run.mcap"
    assert run(capsys, "record", "-o", str(output), "--seed", "1", *QUICK)[0] == 0
    before = output.read_bytes()
    code, out, err = run(capsys, "record", "-o", str(output), "--seed", "2", *QUICK)
    assert code == 1 and out == ""
    assert_one_error_line(err, str(output), "--overwrite")
    assert output.read_bytes() == before
    code, _, err = run(capsys, "record", "-o", str(output), "--seed", "2", "--overwrite", *QUICK)
    assert (code, err) == (0, "")
    assert seed_of(output) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]


def _size(path: Path) -> int:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size if path.exists() else 0


@pytest.mark.slow
@pytest.mark.parametrize(("name", "written"), [("crash.mcap", 300_000),
                                               ("crash.bag", 2_500_000),  # 1 MiB chunks
                                               ("crash", 300_000)],
                         ids=["mcap", "ros1", "rosbag2"])
def test_killed_recording_leaves_a_readable_partial(tmp_path: Path, name: str,
                                                    written: int) -> None:
    output = tmp_path / name
    process = subprocess.Popen(
        [sys.executable, "-m", "camlog", "record", "mono_checkerboard", "-o", str(output),
         "--frames", "5000", "--resolution", "320x240", "--no-progress"],
        cwd=REPO_ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    try:
        # wait until a few chunks of frames are on disk
        deadline = time.monotonic() + 90
        while not temp_outputs(tmp_path) or _size(temp_outputs(tmp_path)[0]) < written:
            assert process.poll() is None, process.stderr.read() if process.stderr else ""
            assert time.monotonic() < deadline, "the recording wrote nothing"
            time.sleep(0.05)
        os.kill(process.pid, signal.SIGKILL)
    finally:
        process.kill()
        process.wait(timeout=30)
        if process.stderr:
            process.stderr.close()
    assert process.returncode == -signal.SIGKILL
    assert not output.exists()
    (partial,) = temp_outputs(tmp_path)
    assert partial.name.startswith(f".{name}.camlog-")
    with open_reader(partial) as reader:
        images = [r.message for r in reader.messages(["/simple_camera/image_raw"])]
        assert reader.warnings  # says that the log is incomplete
    assert len(images) > 0
    stamps = [i.stamp_ns for i in images if isinstance(i, Image)]
    assert len(stamps) == len(images)
    assert stamps == sorted(stamps)
    for image in images:
        assert isinstance(image, Image)
        assert image.pixels.shape == (240, 320, 3)
        assert np.asarray(image.pixels).std() > 10


# --- one-line errors ------------------------------------------------------------------------

def test_unknown_scenario_lists_the_builtins(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(capsys, "record", "no_such_scenario", "-o", str(tmp_path / "x.mcap"))
    assert code == 1
    assert_one_error_line(err, "no_such_scenario", *BUILTINS)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("text", "needle"), [
    ("name = \n", "not valid TOML"),
    ("name = 'x'\n[[cameras]]\nname = 'c'\nwidth = 'abc'\n", "cameras[0].width: expected"),
    ("name = 'x'\nbogus_key = 1\n[[cameras]]\nname = 'c'\nforward = [0, 0, 1]\n"
     "right = [1, 0, 0]\nposition_m = [0, 0, 0]\n", "bogus_key: unknown key"),
    ("name = 'x'\n", "cameras: "),
])
def test_bad_spec_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, needle: str
) -> None:
    spec = tmp_path / "bad.toml"
    spec.write_text(text)
    code, _, err = run(capsys, "record", str(spec), "-o", str(tmp_path / "x.mcap"))
    assert code == 1
    assert_one_error_line(err, str(spec), needle)


@pytest.mark.parametrize("where", ["parent is a file", "missing directory"])
def test_unwritable_output(tmp_path: Path, capsys: pytest.CaptureFixture[str], where: str) -> None:
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a directory")
    parent = blocker if where == "parent is a file" else tmp_path / "missing"
    output = parent / "x.mcap"
    code, _, err = run(capsys, "record", "-o", str(output), *QUICK)
    assert code == 1
    assert_one_error_line(err, str(output))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker"]


@pytest.mark.parametrize(("args", "needle"), [
    (["--frames", "0"], "--frames: expected 1.."),
    (["--noise", "-1"], "--noise: expected a number >= 0"),
    (["--hfov", "0"], "--hfov: expected a number > 0"),
    (["--distortion", "plumb_bob:-5,0,0,0,0"], "not invertible"),
    (["--intrinsics=-500,500,32,24"], "fx"),
    (["--drift", "right:tilt:0.1@1"], "AXIS one of roll, pitch, yaw"),
    (["--drift", "right:pitch:0.1"], "CAMERA:AXIS:DEGREES@SECONDS"),
    (["--drift", "middle:pitch:0.1@1"], "no camera 'middle'"),
])
def test_bad_values(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], needle: str
) -> None:
    output = tmp_path / "x.mcap"
    try:
        code, _, err = run(capsys, "record", *args, "-o", str(output), "--resolution", "64x48")
    except SystemExit as refused:  # argument types refuse before anything runs
        code, err = int(refused.code or 0), capsys.readouterr().err
    assert code in (1, 2)
    assert_one_error_line(err, needle)
    assert list(tmp_path.iterdir()) == []


def test_unknown_output_suffix(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "record", "-o", str(tmp_path / "x.txt"), *QUICK)
    assert code == 1
    assert_one_error_line(err, "x.txt", "--format")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
@pytest.mark.parametrize("args", [
    ["--resolution", "abc"],
    ["--intrinsics", "1,2,3"],
    ["--distortion", "fisheye:0.1"],
    ["--frames", "ten"],
    ["--frames", "3", "--duration", "1"],
])
def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str], args: list[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["record", *args])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "camlog record: error: " in err
    assert "Traceback" not in err


@pytest.mark.slow
def test_missing_gl_backend_is_one_line(tmp_path: Path) -> None:
    env = {**os.environ, "MUJOCO_GL": "nonexistent_backend"}
    result = camlog("record", "-o", str(tmp_path / "x.mcap"), *QUICK, env=env)
    assert result.returncode == 1
    line = assert_one_error_line(result.stderr, "MUJOCO_GL")
    assert "nonexistent_backend" in line
    assert result.stdout == ""
    assert list(tmp_path.iterdir()) == []

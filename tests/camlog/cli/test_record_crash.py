"""``camlog record`` killed or interrupted: what stays on disk and what is said.

kill -9 of a recording in each format after a few seconds keeps every frame rendered up to a
second before the kill (the recording's progress bar, on a pseudo-terminal, says how many
frames were rendered when); Ctrl-C at any moment ends with one line and no output (or the
whole log, when the signal lands after it was renamed into place).
"""

from __future__ import annotations

import fcntl
import os
import pty
import re
import select
import shlex
import signal
import struct
import subprocess
import sys
import termios
import time
from pathlib import Path

import pytest

from replay import Image, open_reader
from tests.conftest import REPO_ROOT

#: subprocesses import this checkout's packages from any folder
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(
    filter(None, [str(REPO_ROOT), os.environ.get("PYTHONPATH")]))}

FRAMES = 20_000  # per camera; the recording is killed long before
PROGRESS = re.compile(rb"(\d+)/" + str(2 * FRAMES).encode())  # shots of both cameras


IMAGE_TOPICS = ["/stereo_camera/left/image_raw", "/stereo_camera/right/image_raw"]


def only_entry(folder: Path) -> Path:
    """The one file or folder a killed command left in ``folder``."""
    entries = list(folder.iterdir())
    assert len(entries) == 1, entries
    return entries[0]


def record_until_killed(output: Path, *, fmt: str, seconds: float) -> list[tuple[float, int]]:
    """Run ``camlog record`` into ``output`` and kill it with SIGKILL once it has rendered for
    ``seconds``; returns (when the test saw it, frames rendered) of its progress, with the
    moment of the kill last (frames -1)."""
    master, terminal = pty.openpty()  # tqdm shows its bar on a terminal only
    fcntl.ioctl(terminal, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))
    process = subprocess.Popen(
        [sys.executable, "-m", "camlog", "record", "red_block", "-o", str(output),
         "--format", fmt, "--frames", str(FRAMES), "--resolution", "160x120"],
        cwd=REPO_ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=terminal)
    os.close(terminal)
    rendered: list[tuple[float, int]] = []
    try:
        deadline = time.monotonic() + 120
        while not rendered or rendered[-1][0] - rendered[0][0] < seconds:
            assert time.monotonic() < deadline and process.poll() is None, "no progress"
            if select.select([master], [], [], 0.5)[0]:
                chunk = os.read(master, 65536)
                counts = [int(n) for n in PROGRESS.findall(chunk)]
                if counts and counts[-1] > 0:
                    rendered.append((time.monotonic(), counts[-1]))
        process.send_signal(signal.SIGKILL)
        rendered.append((time.monotonic(), -1))
    finally:
        process.kill()
        process.wait(timeout=30)
        os.close(master)
    assert process.returncode == -signal.SIGKILL
    return rendered


@pytest.mark.slow
@pytest.mark.parametrize("fmt", ["mcap", "rosbag2", "rosbag2-sqlite3", "ros1"])
def test_killed_recording_keeps_all_but_the_last_second(tmp_path: Path, fmt: str) -> None:
    out = tmp_path / "out"
    out.mkdir()
    name = "run.bag" if fmt == "ros1" else "run.mcap" if fmt == "mcap" else "run"
    *rendered, (killed_at, _) = record_until_killed(out / name, fmt=fmt, seconds=3.0)
    assert not (out / name).exists()
    durable = max((n for seen, n in rendered if seen <= killed_at - 1.0), default=0)
    assert durable > 0
    with open_reader(only_entry(out)) as reader:
        assert reader.warnings  # it says that the log is incomplete
        images = [(r.topic, r.message) for r in reader.messages(IMAGE_TOPICS)]
    assert len(images) >= durable
    for topic in IMAGE_TOPICS:
        stamps = [m.stamp_ns for t, m in images if t == topic and isinstance(m, Image)]
        assert stamps == sorted(set(stamps))
        assert len(stamps) >= durable // 2
    assert len(images) <= rendered[-1][1] + 50  # not more than was rendered (bar lags a bit)


def camlog(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``camlog ARGS`` run in ``cwd``."""
    return subprocess.run([sys.executable, "-m", "camlog", *args], cwd=cwd, env=ENV,
                          capture_output=True, text=True, timeout=300, check=False)


@pytest.mark.slow
def test_a_killed_recordings_leftover_is_found_and_recovered(tmp_path: Path) -> None:
    record_until_killed(tmp_path / "rec.mcap", fmt="mcap", seconds=1.5)
    leftover = only_entry(tmp_path)
    assert leftover.name.startswith(".rec.mcap.camlog-")

    listed = camlog("info", ".", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    assert f"  {leftover.name}\n" in listed.stdout
    assert "meant to become rec.mcap" in listed.stdout
    assert f"camlog convert --recover {leftover.name} rec.mcap\n" in listed.stdout

    again = camlog("record", "red_block", "-o", "rec.mcap", "--frames", "3",
                   "--resolution", "160x120", "--no-progress", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    (warning,) = [line for line in again.stderr.splitlines() if leftover.name in line]
    assert warning.startswith(f"warning: {leftover.name} (file, ")
    assert "did not finish writing rec.mcap" in warning
    command = warning.split("recover it with: ")[1]
    assert command == f"camlog convert --recover {leftover.name} rec-recovered.mcap"

    recovered = camlog(*shlex.split(command)[1:], cwd=tmp_path)
    assert recovered.returncode == 0, recovered.stderr
    with open_reader(tmp_path / "rec-recovered.mcap") as reader:
        assert sum(1 for _ in reader.raw_messages(IMAGE_TOPICS)) > 0
    assert leftover.exists()  # recovering keeps it: removing it is the user's choice


#: moments to interrupt, from the first line of camlog's code: start-up (imports, argument
#: parsing, scene building) to mid-recording
INTERRUPT_AFTER_S = (0.0, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.8, 1.2, 1.8, 2.5)
#: the ``camlog`` console script, saying on stdout when it runs (Ctrl-C while Python itself
#: starts is Python's to handle; camlog.cli imports only the standard library, the packages
#: load inside ``main``)
LAUNCH = ("import sys; from camlog.cli import main; print('started', flush=True); "
          "sys.exit(main())")


@pytest.mark.slow
@pytest.mark.parametrize("delay_s", INTERRUPT_AFTER_S)
def test_ctrl_c_at_any_moment_ends_cleanly(tmp_path: Path, delay_s: float) -> None:
    out = tmp_path / "out"
    out.mkdir()
    process = subprocess.Popen(
        [sys.executable, "-c", LAUNCH, "record", "red_block", "-o", str(out / "run.mcap"),
         "--frames", "400", "--resolution", "160x120", "--no-progress"],
        cwd=REPO_ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout is not None
    assert process.stdout.readline() == "started\n"
    time.sleep(delay_s)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert "Traceback" not in stderr, stderr
    if process.returncode == 0:  # finished before the signal came
        assert (out / "run.mcap").is_file()
        return
    lines = stderr.splitlines()
    # MuJoCo's EGL start-up can fail on the signal instead: then it is that one error line
    assert (process.returncode, lines) == (130, ["camlog record: interrupted"]) or (
        process.returncode == 1 and len(lines) == 1
        and lines[0].startswith("camlog record: error: cannot load MuJoCo")), stderr
    left = list(out.iterdir())
    # nothing, or (the signal landed after the output was renamed into place) the whole log
    assert left in ([], [out / "run.mcap"])
    if left:
        frames: dict[str, int] = {}
        with open_reader(left[0]) as reader:
            for raw in reader.raw_messages():
                if raw.topic.endswith("/image_raw"):
                    frames[raw.topic] = frames.get(raw.topic, 0) + 1
        assert frames and set(frames.values()) == {400}, frames

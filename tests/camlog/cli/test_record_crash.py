"""``camlog record`` killed or interrupted: what stays on disk and what is said.

kill -9 of a recording in each format after a few seconds keeps every frame rendered up to a
second before the kill (the recording's progress bar, on a pseudo-terminal, says how many
frames were rendered when); Ctrl-C at any moment ends with one line and no output.
"""

from __future__ import annotations

import fcntl
import os
import pty
import re
import select
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

FRAMES = 20_000  # per camera; the recording is killed long before
PROGRESS = re.compile(rb"(\d+)/" + str(2 * FRAMES).encode())  # shots of both cameras


IMAGE_TOPICS = ["/stereo_camera/left/image_raw", "/stereo_camera/right/image_raw"]


def only_entry(folder: Path) -> Path:
    """The one file or folder a killed command left in ``folder``."""
    entries = list(folder.iterdir())
    assert len(entries) == 1, entries
    return entries[0]


@pytest.mark.parametrize("fmt", ["mcap", "rosbag2", "rosbag2-sqlite3", "ros1"])
def test_killed_recording_keeps_all_but_the_last_second(tmp_path: Path, fmt: str) -> None:
    out = tmp_path / "out"
    out.mkdir()
    name = "run.bag" if fmt == "ros1" else "run.mcap" if fmt == "mcap" else "run"
    master, terminal = pty.openpty()  # tqdm shows its bar on a terminal only
    fcntl.ioctl(terminal, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))
    process = subprocess.Popen(
        [sys.executable, "-m", "camlog", "record", "red_block", "-o", str(out / name),
         "--format", fmt, "--frames", str(FRAMES), "--resolution", "160x120"],
        cwd=REPO_ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=terminal)
    os.close(terminal)
    rendered: list[tuple[float, int]] = []  # (when the test saw it, frames rendered)
    try:
        deadline = time.monotonic() + 120
        while not rendered or rendered[-1][0] - rendered[0][0] < 3.0:
            assert time.monotonic() < deadline and process.poll() is None, "no progress"
            if select.select([master], [], [], 0.5)[0]:
                chunk = os.read(master, 65536)
                counts = [int(n) for n in PROGRESS.findall(chunk)]
                if counts and counts[-1] > 0:
                    rendered.append((time.monotonic(), counts[-1]))
        process.send_signal(signal.SIGKILL)
        killed_at = time.monotonic()
    finally:
        process.kill()
        process.wait(timeout=30)
        os.close(master)
    assert process.returncode == -signal.SIGKILL
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


#: moments to interrupt, from the first line of camlog's code: start-up (imports, argument
#: parsing, scene building) to mid-recording
INTERRUPT_AFTER_S = (0.0, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.8, 1.2, 1.8, 2.5)
#: the ``camlog`` console script, saying on stdout when it runs (Ctrl-C while Python itself
#: starts is Python's to handle; camlog.cli imports only the standard library, the packages
#: load inside ``main``)
LAUNCH = ("import sys; from camlog.cli import main; print('started', flush=True); "
          "sys.exit(main())")


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
    assert list(out.iterdir()) == []

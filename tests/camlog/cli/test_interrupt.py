"""Ctrl-C at any moment of any command: one line, exit status 130, no output left behind."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from camlog.cli import _interrupt_where_it_can_be_handled
from tests.camlog.cli.test_record_crash import LAUNCH
from tests.conftest import REPO_ROOT

#: command -> arguments after the input log (OUT is the output folder)
COMMANDS = {
    "info": [],
    "convert": ["OUT/copy.bag"],
    "process": ["--topic", "/stereo_camera/left/image_raw", "--edges", "-o", "OUT/p.mcap"],
    "resync": ["--left", "/stereo_camera/left", "--right", "/stereo_camera/right",
               "-o", "OUT/r.mcap"],
    "calibrate": ["--size", "7x6", "--square", "0.01", "--camera", "/stereo_camera/left",
                  "-o", "OUT/cal"],
    "view": ["-o", "OUT/v.rrd"],
    "play": ["--rate", "0.5", "-o", "OUT/played.mcap"],
}

#: how a command ends when it finishes before the signal comes: the red-block log holds no
#: board, so calibrate stops with its one-line error
FINISHED = {"calibrate": (1, "no 7x6 board found")}


@pytest.mark.slow
@pytest.mark.parametrize("delay_s", [0.1, 0.7, 1.6])
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_ctrl_c_ends_every_command_cleanly(
    tmp_path: Path, red_log: Path, command: str, delay_s: float
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    args = [a.replace("OUT", str(out)) for a in COMMANDS[command]]
    process = subprocess.Popen([sys.executable, "-c", LAUNCH, command, str(red_log), *args],
                               cwd=REPO_ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    assert process.stdout is not None
    assert process.stdout.readline() == "started\n"
    time.sleep(delay_s)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert "Traceback" not in stderr and "Exception ignored" not in stderr, stderr
    finished_status, finished_words = FINISHED.get(command, (0, ""))
    if process.returncode == finished_status:  # done before the signal came
        assert finished_words in stderr, stderr
        return
    assert process.returncode == 130, (process.returncode, stderr)
    assert stderr.splitlines()[-1] == f"camlog {command}: interrupted", stderr
    assert list(out.iterdir()) == []


def test_a_ctrl_c_python_cannot_raise_arrives_once_the_hook_has_returned() -> None:
    """In the main thread the re-sent signal must not go off inside the hook (where it would
    be "Exception ignored in sys.unraisablehook" again) but right after it."""
    passed_on: list[object] = []
    hook = _interrupt_where_it_can_be_handled(passed_on.append)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        assert hook(SimpleNamespace(exc_value=KeyboardInterrupt())) is None
        with pytest.raises(KeyboardInterrupt):
            time.sleep(5)
    finally:
        signal.signal(signal.SIGINT, previous)
    other = SimpleNamespace(exc_value=ValueError("not a Ctrl-C"))
    hook(other)
    assert passed_on == [other]  # other unraisable errors go to the previous hook

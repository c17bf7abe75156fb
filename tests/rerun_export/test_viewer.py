"""Live viewers: ``--spawn`` fails in seconds when no viewer can start, a spawned viewer
listens on 127.0.0.1 unless asked, an existing viewer is reused, and a viewer that stops
taking data ends the command within a bounded time instead of hanging it.

The real rerun viewer runs in these tests. The machines they run on have no display, so a
spawned viewer gets as far as listening and then fails to open its window; its own log says
where it listened.
"""

from __future__ import annotations

import contextlib
import os
import re
import socket
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Iterator
from pathlib import Path

import pytest
from rerun.error_utils import RerunWarning

from rerun_export import sink as sink_module
from rerun_export.errors import ViewerError
from rerun_export.sink import RecordingSink
from tests.conftest import REPO_ROOT
from tests.rrd import Receiver, load_rrd

#: how long a camlog command may take to start and read a short log, loaded or not
STARTUP_S = 15.0


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def camlog(*args: str, env: dict[str, str]) -> tuple[subprocess.CompletedProcess[str], float]:
    started = time.monotonic()
    result = subprocess.run([sys.executable, "-m", "camlog", *args], cwd=REPO_ROOT, env=env,
                            capture_output=True, text=True, timeout=180, check=False)
    return result, time.monotonic() - started


def without_display() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}


def missing_x_display() -> str:
    """An X display number with no server behind it."""
    number = next(n for n in range(90, 200) if not Path(f"/tmp/.X11-unix/X{n}").exists())
    return f":{number}"


@pytest.mark.slow
def test_spawn_without_a_display_fails_at_once(red_log: Path, tmp_path: Path) -> None:
    result, took_s = camlog("view", str(red_log), "--spawn", "--port", str(free_port()),
                            env=without_display())
    assert result.returncode == 1
    assert result.stderr.splitlines() == [result.stderr.strip()]
    assert "cannot start a rerun viewer: there is no display" in result.stderr
    assert took_s < 30


@pytest.mark.slow
@pytest.mark.parametrize(("bind", "listens_on"), [([], "127.0.0.1"),
                                                   (["--bind", "0.0.0.0"], "0.0.0.0")])
def test_spawned_viewer_that_cannot_open_a_window(
    red_log: Path, bind: list[str], listens_on: str
) -> None:
    port = free_port()
    env = without_display() | {"DISPLAY": missing_x_display()}
    result, took_s = camlog("view", str(red_log), "--spawn", "--port", str(port), *bind,
                            env=env)
    assert result.returncode == 1
    (line,) = result.stderr.splitlines()
    assert line.startswith("camlog view: error: the rerun viewer stopped at start-up"), line
    assert took_s < 60
    found = re.search(r"its log: (\S+)\)$", line)
    assert found, line
    log = Path(found.group(1))
    try:
        text = re.sub(r"\x1b\[[0-9;]*m", "", log.read_text(errors="replace"))
    finally:
        log.unlink()
    # the viewer starts its server and its window concurrently: when the window fails
    # first, it may stop before it says where it listens; when it says, it is the address
    listening = re.findall(r"Listening for gRPC connections on (\S+):(\d+)", text)
    assert all(found == (listens_on, str(port)) for found in listening), listening
    assert "Failed to open connection to X server" in text or listening, text


@pytest.mark.slow
def test_spawn_uses_a_viewer_already_listening(red_log: Path, tmp_path: Path) -> None:
    receiver = Receiver(tmp_path)
    try:
        result, _ = camlog("view", str(red_log), "--spawn", "--port", str(receiver.port),
                           "--no-progress", env=without_display())
        assert result.returncode == 0, result.stderr
        assert "sent to the viewer" in result.stdout
        deadline = time.monotonic() + 30
        images = 0
        while images < 20 and time.monotonic() < deadline:
            time.sleep(0.3)
            with warnings.catch_warnings():  # the file has no footer while it is written
                warnings.filterwarnings("ignore", "RRD file has no footer", RerunWarning)
                try:
                    recording = load_rrd(receiver.path)
                except (OSError, ValueError):
                    continue
            images = recording.count("/world/stereo_camera/left/image", "Image:buffer")
    finally:
        receiver.stop()
    assert images == 20


#: what a fake viewer does with each connection it accepts
SILENT, CLOSES, ANSWERS_ONCE = "never answers", "closes it", "answers once, then nothing"


@contextlib.contextmanager
def fake_viewer(behaviour: str) -> Iterator[int]:
    """A loopback port that accepts connections and then does ``behaviour``; ANSWERS_ONCE
    sends the HTTP/2 SETTINGS frame a gRPC server greets with, and then never reads."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    held: list[socket.socket] = []
    stop = threading.Event()

    def accept() -> None:
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                connection = server.accept()[0]
            except OSError:
                continue
            if behaviour == CLOSES:
                connection.close()
                continue
            if behaviour == ANSWERS_ONCE:
                connection.sendall(bytes([0, 0, 0, 4, 0, 0, 0, 0, 0]))
            held.append(connection)

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        yield int(server.getsockname()[1])
    finally:
        stop.set()
        thread.join()
        for connection in held:
            connection.close()
        server.close()


VIEW, PLAY = ["view"], ["play", "--rate", "20"]


@pytest.mark.slow
@pytest.mark.parametrize(("command", "behaviour", "said"), [
    # connecting is one step of the sink whichever command opens it: once, through view
    (VIEW, SILENT, "accepted the connection but did not answer within 5 s"),
    (VIEW, CLOSES, "closed the connection without answering"),
    # a stall while writing: view writes as fast as it reads, play paced
    (VIEW, ANSWERS_ONCE, f"the viewer accepted no data for {sink_module.NETWORK_STALL_S:g} s"),
    (PLAY, ANSWERS_ONCE, f"the viewer accepted no data for {sink_module.NETWORK_STALL_S:g} s"),
], ids=["view-never answers", "view-closes it", "view-answers once", "play-answers once"])
def test_connect_to_a_viewer_that_stops_answering_ends_in_time(
    red_log: Path, command: list[str], behaviour: str, said: str
) -> None:
    """Connecting, the first answer and every later write have a deadline: the command
    ends within 15 s of the stall (plus its start-up) with one line naming the URL."""
    with fake_viewer(behaviour) as port:
        result, took_s = camlog(*command, str(red_log), "--connect", f"127.0.0.1:{port}",
                                "--no-progress", env=dict(os.environ))
    assert result.returncode == 1
    (line,) = [line for line in result.stderr.splitlines()
               if not line.startswith("images to write")]
    assert said in line and f"rerun+http://127.0.0.1:{port}/proxy" in line, line
    assert took_s < 15 + STARTUP_S, took_s


def test_a_viewer_that_takes_the_data_but_never_lets_go_is_a_stall(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """rerun's flush can return once the data sits in the socket's buffers, and its
    disconnect then wait for the silent viewer for good: the sink gives up after the stall
    time and says so in one error."""
    monkeypatch.setattr(sink_module, "NETWORK_STALL_S", 0.5)
    monkeypatch.setattr(sink_module, "GIVE_UP_S", 0.2)
    released = threading.Event()
    with fake_viewer(ANSWERS_ONCE) as port, \
            pytest.raises(ViewerError, match="accepted no data") as raised, \
            RecordingSink(connect=f"127.0.0.1:{port}") as sink:
        monkeypatch.setattr(sink.rec, "flush", lambda **_: None)
        monkeypatch.setattr(sink.rec, "disconnect", lambda: released.wait(30))
        started = time.perf_counter()
    assert time.perf_counter() - started < 5
    assert f"127.0.0.1:{port}" in str(raised.value)
    released.set()  # let the abandoned disconnect thread end

"""The background writer: the same log as writing in place, every format; errors reach the
caller and leave nothing behind."""

from __future__ import annotations

import subprocess
import sys
import threading
from collections.abc import Callable
from functools import partial
from pathlib import Path

import pytest

from replay import Image, LogWriteError, OutputError, RawMessage, Text, open_writer
from replay.formats.background import BackgroundWriter
from replay.wire import CDR, serialize

from .samples import WRITE_FORMATS, Entry, random_pixels, read_log


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_same_log_as_writing_in_place(fmt: str, log_path: Callable[[str], Path],
                                      sample_entries: list[Entry]) -> None:
    path = log_path(fmt)
    text = Text("raw")
    raw = RawMessage("/raw", "std_msgs/msg/String", sample_entries[-1][1] + 1,
                     serialize(text, CDR), CDR)
    # a queue of one: the caller waits on the worker again and again
    with BackgroundWriter(partial(open_writer, path, fmt=fmt), max_queued=1) as log:
        for topic, log_time_ns, message in sample_entries:
            log.write(topic, message, log_time_ns=log_time_ns)
        log.write_raw(raw)
    assert read_log(path) == [*sample_entries, ("/raw", raw.log_time_ns, text)]


def test_worker_error_reaches_the_caller_and_leaves_nothing(tmp_path: Path) -> None:
    path = tmp_path / "t.mcap"
    with (
        pytest.raises(LogWriteError, match="topic /x has type std_msgs/msg/String"),
        BackgroundWriter(partial(open_writer, path), max_queued=1) as log,
    ):
        log.write("/x", Text("a"), log_time_ns=1)
        log.write("/x", Image(2, "cam", "mono8", random_pixels("mono8")))
        for stamp_ns in range(3, 1000):  # the error stops the caller at a later call
            log.write("/y", Text("b"), log_time_ns=stamp_ns)
    assert list(tmp_path.iterdir()) == []


def test_worker_error_is_raised_by_close(tmp_path: Path) -> None:
    path = tmp_path / "t.mcap"
    log = BackgroundWriter(partial(open_writer, path))
    log.write("/x", Text("a"), log_time_ns=1)
    log.write("/x", Image(2, "cam", "mono8", random_pixels("mono8")))
    with pytest.raises(LogWriteError, match="topic /x has type"):
        log.close()
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(RuntimeError, match="closed"):
        log.write("/x", Text("b"), log_time_ns=3)


def test_open_error_is_raised_at_once(tmp_path: Path) -> None:
    with pytest.raises(OutputError, match="does not exist"):
        BackgroundWriter(partial(open_writer, tmp_path / "missing" / "t.mcap"))
    assert not any(t.name == "camlog-writer" for t in threading.enumerate())


def test_caller_error_drops_the_log(tmp_path: Path) -> None:
    path = tmp_path / "t.mcap"
    with pytest.raises(RuntimeError, match="boom"), \
            BackgroundWriter(partial(open_writer, path)) as log:
        log.write("/x", Text("a"), log_time_ns=1)
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    assert not any(t.name == "camlog-writer" for t in threading.enumerate())


INTERRUPTED = """
import sys, threading
from pathlib import Path
from replay import Text, open_writer
from replay.formats.background import BackgroundWriter

moment, out = sys.argv[1], Path(sys.argv[2])
real_start, real_join = threading.Thread.start, threading.Thread.join

def start_then_interrupt(self):  # the thread has begun when Ctrl-C lands in start
    real_start(self)
    raise KeyboardInterrupt

def interrupted_join(self, timeout=None):  # Ctrl-C while close waits for the worker
    threading.Thread.join = real_join
    raise KeyboardInterrupt

if moment == "start":
    threading.Thread.start = start_then_interrupt
writer = BackgroundWriter(lambda: open_writer(out / "run.mcap"))
for i in range(50):
    writer.write("/chatter", Text("x" * 10000), log_time_ns=i + 1)
if moment == "close":
    threading.Thread.join = interrupted_join
writer.close()
"""


@pytest.mark.slow
@pytest.mark.parametrize("moment", ["start", "close"])
def test_ctrl_c_leaves_no_temporary_file(tmp_path: Path, moment: str) -> None:
    done = subprocess.run([sys.executable, "-c", INTERRUPTED, moment, str(tmp_path)],
                          capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode != 0 and "KeyboardInterrupt" in done.stderr
    left = sorted(p.name for p in tmp_path.iterdir())
    # a log is never left half-written: gone, or (Ctrl-C while it was being finished) whole
    assert left in ([], ["run.mcap"]), left
    if left:
        assert len(read_log(tmp_path / "run.mcap")) == 50

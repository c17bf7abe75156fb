"""Several ``.rrd`` recordings combined into one file as a stream, in bounded memory.

An ``.rrd`` file ends with a footer that indexes its chunks by byte offset, so files cannot
simply be concatenated. ``rerun rrd merge`` holds every recording in memory at its
uncompressed size (a peak of 1.3 GB for two short recordings, 3.8 GB for two 30 s ones).
``rerun rrd filter`` with nothing to filter reads a stream of concatenated ``.rrd`` files
from its standard input, keeps each recording apart (its own application and recording id),
re-encodes chunk by chunk and writes one file with a footer; but it reads ahead of what it
writes without a bound. The parts are therefore fed to it only as fast as its output grows
(at most :data:`IN_FLIGHT_BYTES` sent and not yet written) and while its memory stays under
:data:`MAX_RESIDENT_BYTES`.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from .errors import ViewerError

__all__ = ["BLOCK_BYTES", "IN_FLIGHT_BYTES", "MAX_RESIDENT_BYTES", "combine_recordings"]

#: bytes of .rrd read and sent at a time
BLOCK_BYTES = 1 << 20
#: bytes sent to the combiner beyond what it has written (bounds its memory)
IN_FLIGHT_BYTES = 4 << 20
#: the combiner's resident memory beyond which it gets no more input until it has written
#: what it holds (images compress 10-40x in an .rrd: a few MB of input can be far more)
MAX_RESIDENT_BYTES = 256 << 20
#: output that has not grown for this long means the combiner waits for input
PATIENCE_S = 0.1
POLL_S = 0.002
_PAGE_BYTES = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096


def combine_recordings(parts: Sequence[Path], output: Path) -> None:
    """Write the recordings of ``parts`` (``.rrd`` files, in order) to ``output``; raises
    :class:`~rerun_export.errors.ViewerError` with rerun's reason when that fails."""
    command = [*_rerun(), "rrd", "filter", "-o", str(output)]
    with tempfile.TemporaryFile() as errors:
        proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                stderr=errors)
        assert proc.stdin is not None
        try:
            with contextlib.suppress(BrokenPipeError):  # it stopped: its status says why
                _feed(proc, parts, output)
        finally:
            with contextlib.suppress(BrokenPipeError):
                proc.stdin.close()
            status = proc.wait()
        if status != 0 or not output.is_file():
            errors.seek(0)
            lines = [line for line in errors.read().decode(errors="replace").splitlines()
                     if line.strip()]
            reason = next((line for line in lines if "error" in line.lower()),
                          lines[-1] if lines else f"exit status {status}")
            raise ViewerError(f"cannot combine the recordings: rerun rrd filter failed: "
                              f"{reason.strip()}")


def _rerun() -> list[str]:
    """rerun's command line program itself (whose memory is watched), not the Python
    wrapper that ``python -m rerun`` starts it through."""
    override = os.environ.get("RERUN_CLI_PATH")
    if override:
        return [override]
    import rerun_cli  # the package that holds the program

    program = Path(rerun_cli.__file__).with_name("rerun.exe" if os.name == "nt" else "rerun")
    return [str(program)] if program.is_file() else [sys.executable, "-m", "rerun_cli"]


def _feed(proc: subprocess.Popen[bytes], parts: Sequence[Path], output: Path) -> None:
    assert proc.stdin is not None
    sent = 0
    for part in parts:
        with part.open("rb") as source:
            while block := source.read(BLOCK_BYTES):
                _wait_for(proc, output, sent - IN_FLIGHT_BYTES)
                proc.stdin.write(block)
                sent += len(block)


def _wait_for(proc: subprocess.Popen[bytes], output: Path, written: int) -> None:
    """Wait until ``output`` holds ``written`` bytes while the combiner's memory stays under
    :data:`MAX_RESIDENT_BYTES`, or until its output stops growing for :data:`PATIENCE_S`
    (it has written all it can without more input), or until it has ended."""
    last, since = -1, time.monotonic()
    while proc.poll() is None:
        size = _size(output)
        if size >= written and _resident(proc.pid) <= MAX_RESIDENT_BYTES:
            return
        if size != last:
            last, since = size, time.monotonic()
        elif time.monotonic() - since > PATIENCE_S:
            return
        time.sleep(POLL_S)


def _resident(pid: int) -> int:
    """A process's resident bytes (0 where /proc does not tell)."""
    try:
        return int(Path(f"/proc/{pid}/statm").read_bytes().split()[1]) * _PAGE_BYTES
    except (OSError, ValueError, IndexError):
        return 0


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return 0

"""Image decoders' own messages kept off the terminal: camlog counts damaged frames itself.

OpenCV decodes JPEG and PNG frames with libjpeg and libpng, which print what they find wrong
in a frame (``Corrupt JPEG data: bad Huffman code``, ``Premature end of JPEG file``,
``libpng error: IDAT: CRC error``) from C straight to the process's standard error, file
descriptor 2, whichever thread decodes; OpenCV has no setting that reaches them
(``OPENCV_LOG_LEVEL`` governs OpenCV's own ``[ WARN]`` lines only). camlog reports such
frames in one line per topic, so in camlog's own process (the ``camlog`` program) fd 2
becomes a pipe that a thread reads, dropping those lines and passing every other byte on to
the terminal, while Python's ``sys.stderr`` writes to the terminal directly: camlog's
progress bars, warnings and errors neither wait for the thread nor lose the terminal.
Stdlib only: it is installed before any library loads.
"""

from __future__ import annotations

import atexit
import fcntl
import io
import os
import re
import select
import signal
import sys
import threading

__all__ = ["DECODER_MESSAGE", "filter_decoder_messages", "forward"]

#: lines libjpeg (its warnings, ``JWRN_*``) and libpng print about a damaged image
DECODER_MESSAGE = re.compile(
    rb"(Corrupt JPEG data: .*|Premature end of JPEG file|Invalid SOS parameters for "
    rb"sequential JPEG|Inconsistent progression sequence for component .*|Warning: unknown "
    rb"JFIF revision number .*|Warning: thumbnail image size does not match data length .*"
    rb"|libpng (warning|error): .*)")
#: how long the start of a line waits for its end before it is passed on as it is
PARTIAL_LINE_S = 0.05
_CHUNK = 65536


def forward(data: bytes) -> tuple[bytes, bytes]:
    """(what to pass on, the unfinished last line kept back) of ``data`` read from fd 2,
    decoders' message lines left out.

    >>> forward(b"a\\nCorrupt JPEG data: bad Huffman code\\nPremature end")
    (b'a\\n', b'Premature end')
    """
    *lines, pending = data.split(b"\n")
    kept = b"".join(line + b"\n" for line in lines
                    if not DECODER_MESSAGE.fullmatch(line.removesuffix(b"\r")))
    return kept, pending


class _Filter:
    """The thread between fd 2 (a pipe) and the terminal (``target``, a copy of the old fd 2)."""

    def __init__(self, source: int, target: int) -> None:
        self.source, self.target = source, target
        self.pending = b""
        self.lock = threading.Lock()  # one reader at a time: the thread, or the drain at exit
        self.done = False

    def _write(self, data: bytes) -> None:
        while data:
            try:
                data = data[os.write(self.target, data):]
            except OSError:  # the terminal is gone: nothing left to say it to
                return

    def _pass(self, data: bytes, *, flush: bool) -> None:
        kept, self.pending = forward(self.pending + data)
        if flush and self.pending:
            kept, self.pending = kept + self.pending, b""
        self._write(kept)

    def run(self) -> None:
        """Pass fd 2's bytes on until the pipe closes or :meth:`drain` took over."""
        while not self.done:
            ready = select.select([self.source], [], [], PARTIAL_LINE_S)[0]
            with self.lock:
                if self.done:
                    return
                if not ready:
                    self._pass(b"", flush=True)
                    continue
                try:
                    data = os.read(self.source, _CHUNK)
                except BlockingIOError:
                    continue
                if not data:
                    self._pass(b"", flush=True)
                    return
                self._pass(data, flush=False)

    def drain(self) -> None:
        """At exit: fd 2 back to the terminal, what is left in the pipe passed on (without
        waiting for processes that inherited the pipe and still hold it)."""
        os.dup2(self.target, 2)
        with self.lock:
            self.done = True
            os.set_blocking(self.source, False)
            while True:
                try:
                    data = os.read(self.source, _CHUNK)
                except (BlockingIOError, OSError):
                    break
                if not data:
                    break
                self._pass(data, flush=False)
            self._pass(b"", flush=True)


def filter_decoder_messages() -> None:
    """Leave decoders' message lines out of this process's fd 2 from now on (see the module
    docstring); does nothing where fd 2 is not open."""
    # Ctrl-C waits until the switch is whole: landing half way (fd 2 the pipe, no thread
    # reading it yet), its one line would be written into a pipe nobody reads
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        _switch()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, blocked)


def _switch() -> None:
    """fd 2 to a pipe, its thread and its drain at exit (see :func:`filter_decoder_messages`)."""
    try:
        terminal = os.dup(2)
    except OSError:
        return
    read_end, write_end = os.pipe()
    fcntl.fcntl(terminal, fcntl.F_SETFD, fcntl.FD_CLOEXEC)
    sys.stderr.flush()
    os.dup2(write_end, 2)
    os.close(write_end)
    old = sys.stderr
    sys.stderr = io.TextIOWrapper(
        io.FileIO(terminal, "w", closefd=False), encoding=old.encoding, errors=old.errors,
        line_buffering=True, write_through=True)
    pipe = _Filter(read_end, terminal)
    threading.Thread(target=pipe.run, name="decoder-messages", daemon=True).start()
    atexit.register(pipe.drain)

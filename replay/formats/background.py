"""A log writer on a thread of its own, behind a bounded queue.

:class:`BackgroundWriter` takes messages from the calling thread and hands them to a
:class:`~.base.LogWriter` that lives on one worker thread: serialization, chunk compression
and file writes happen there, while the caller goes on with its own work (zstd, CRCs and
file writes release the GIL, so two cores work at once). The writer is opened, used and
closed on that one thread, as some storages (SQLite) require. An error on the worker is
raised to the caller by its next call, or by :meth:`~BackgroundWriter.close`; the output
then never appears under its final name.
"""

from __future__ import annotations

import atexit
import queue
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .base import KeptOnSuccess, LogWriter, RawMessage

if TYPE_CHECKING:
    from ..messages import Message

__all__ = ["BackgroundWriter"]

#: queue item that ends the worker and drops the partial log
_ABORT = object()
#: queue item that ends the worker and finishes the log
_CLOSE = object()
#: how often a caller waiting on a full queue looks for the worker's error
_POLL_S = 0.2
#: how long the interpreter's exit waits for a worker whose start was interrupted to begin
_BEGIN_S = 1.0


class BackgroundWriter(KeptOnSuccess):
    """Writes through the :class:`~.base.LogWriter` that ``open_log`` opens, on a worker
    thread; at most ``max_queued`` messages wait for it (the caller blocks beyond that).

    Use as a context manager: the log is finished and committed when the block ends without
    an exception (the worker's own error, if any, is raised then), and dropped otherwise."""

    def __init__(self, open_log: Callable[[], LogWriter], *, max_queued: int = 4) -> None:
        self._queue: queue.Queue[Any] = queue.Queue(maxsize=max_queued)
        self.error: BaseException | None = None
        self.closed = False
        self._drop = False  # a Ctrl-C while the log is finished, or the interpreter's exit
        self._open_log = open_log
        self._opened = threading.Event()
        self._began, self._worker_done = threading.Event(), False
        self._thread = threading.Thread(target=self._run, name="camlog-writer",
                                        daemon=True)
        # a Ctrl-C can land inside Thread.start, after the thread began: nothing here can
        # tell, so the interpreter's exit drops a log whose worker still runs
        atexit.register(self._drop_at_exit)
        try:
            self._thread.start()
            self._opened.wait()
        except BaseException:  # Ctrl-C while the log opens: drop it once it is open
            self.abort()
            raise
        if self.error is not None:  # the log could not be opened
            self._thread.join()
            atexit.unregister(self._drop_at_exit)
            raise self.error

    def write(self, topic: str, message: Message, *, log_time_ns: int | None = None) -> None:
        """Queue a typed record (see :meth:`.LogWriter.write`)."""
        self._put(lambda writer: writer.write(topic, message, log_time_ns=log_time_ns))

    def write_raw(self, raw: RawMessage, *, msgdef: str = "") -> None:
        """Queue a raw message (see :meth:`.LogWriter.write_raw`)."""
        self._put(lambda writer: writer.write_raw(raw, msgdef=msgdef))

    def submit(self, work: Callable[[LogWriter], None]) -> None:
        """Queue ``work``, to be called with the writer on the worker thread (e.g. to
        finish a frame there before writing it)."""
        self._put(work)

    def close(self) -> None:
        """Write what is queued, finish and commit the log; raise the worker's error."""
        self._stop(_CLOSE)
        if self.error is not None:
            raise self.error

    def abort(self) -> None:
        """Drop what is queued and the partial log."""
        self._stop(_ABORT)

    def _put(self, item: Callable[[LogWriter], None]) -> None:
        if self.closed:
            raise RuntimeError("the background writer is closed")
        while True:
            if self.error is not None:
                raise self.error
            try:
                self._queue.put(item, timeout=_POLL_S)
                return
            except queue.Full:
                continue

    def _stop(self, sentinel: object) -> None:
        if not self.closed:
            self.closed = True
            # the worker drains the queue even after an error, and takes this once it runs
            while not self._worker_done:
                try:
                    self._queue.put(sentinel, timeout=_POLL_S)
                    break
                except queue.Full:
                    continue
        self._join()

    def _join(self) -> None:
        """Wait for the worker to finish or drop the log. A Ctrl-C meanwhile asks it to drop
        the log unless it is already finishing it, and is raised once it is done: the
        process never ends with the worker half-way and its temporary file left behind."""
        interrupted: BaseException | None = None
        while self._thread.is_alive():
            try:
                self._thread.join()
            except KeyboardInterrupt as err:
                interrupted = err
                self._drop = True
        if self._worker_done:
            atexit.unregister(self._drop_at_exit)
        if interrupted is not None:
            raise interrupted

    def _drop_at_exit(self) -> None:
        """At the interpreter's exit, a worker that still runs drops its log (one whose
        start was interrupted may only now begin: given a second to)."""
        self._drop = True
        if not self._worker_done:
            self._began.wait(_BEGIN_S)
        self._stop(_ABORT)

    def _run(self) -> None:
        self._began.set()
        try:
            self._serve()
        finally:
            self._worker_done = True

    def _serve(self) -> None:
        try:
            writer = self._open_log()
        except BaseException as err:  # handed to the caller
            self.error = err
            return
        finally:
            self._opened.set()
        # after an error, keep taking items without writing so that the caller never blocks
        while (item := self._queue.get()) is not _CLOSE and item is not _ABORT:
            if self.error is None:
                try:
                    item(writer)
                except BaseException as err:
                    self.error = err
        try:
            if item is _CLOSE and self.error is None and not self._drop:
                writer.close()
            else:
                writer.abort()
        except BaseException as err:
            self.error = self.error or err

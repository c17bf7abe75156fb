"""One background thread that finishes a writer's chunks, in order, while the caller builds
the next.

Compression (zstd, lz4) and ``zlib.crc32`` release the GIL, so on a second core a chunk is
compressed, checksummed and written while the messages of the next one are converted. Jobs
run in the order given; at most ``depth`` are handed over and not yet done, which bounds the
memory held. A job's exception is raised to the caller by every later :meth:`submit` and
:meth:`drain`; the jobs after a failed one are skipped, so nothing is written past a failed
write.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable

__all__ = ["OrderedWorker"]


class OrderedWorker:
    """Runs jobs in order on one thread, started with the first job."""

    def __init__(self, *, depth: int = 2) -> None:
        self._depth = depth
        self._jobs: deque[Callable[[], None]] = deque()
        self._undone = 0  # jobs queued or running
        self._error: BaseException | None = None
        self._stopping = False
        self._changed = threading.Condition()
        self._thread: threading.Thread | None = None

    def submit(self, job: Callable[[], None]) -> None:
        """Queue ``job``; wait while more than ``depth`` jobs are not yet done."""
        with self._changed:
            self._raise_failure()
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="camlog-chunks",
                                                daemon=True)
                self._thread.start()
            self._jobs.append(job)
            self._undone += 1
            self._changed.notify_all()
            while self._undone > self._depth and self._error is None:
                self._changed.wait()
            self._raise_failure()

    def drain(self) -> None:
        """Wait for every job given so far; raise the exception of a failed one."""
        with self._changed:
            while self._undone and self._error is None:
                self._changed.wait()
            self._raise_failure()

    def close(self) -> None:
        """Wait for every job, then stop the thread (a job's exception is raised)."""
        try:
            self.drain()
        finally:
            self.abort()

    def abort(self) -> None:
        """Drop the jobs not yet started, wait for the running one, stop the thread."""
        with self._changed:
            self._undone -= len(self._jobs)
            self._jobs.clear()
            self._stopping = True
            self._changed.notify_all()
        if self._thread is not None:
            self._thread.join()
            self._thread = None

    def _raise_failure(self) -> None:
        if self._error is not None:
            raise self._error

    def _run(self) -> None:
        while True:
            with self._changed:
                while not self._jobs and not self._stopping:
                    self._changed.wait()
                if not self._jobs:
                    return
                job = self._jobs.popleft()
                failed = self._error is not None
            try:
                if not failed:
                    job()
            except BaseException as err:  # handed to the caller's thread
                with self._changed:
                    self._error = err
            with self._changed:
                self._undone -= 1
                self._changed.notify_all()

"""One background thread that finishes a writer's chunks, in order, while the caller builds
the next.

Compression (zstd, lz4) and ``zlib.crc32`` release the GIL, so on a second core a chunk is
compressed, checksummed and written while the messages of the next one are converted. Jobs
run in the order given; at most ``depth`` are handed over and not yet done, which bounds the
memory held. A job's exception is raised to the caller at its next :meth:`submit` or at
:meth:`drain`; the jobs after a failed one are skipped, so nothing is written past a failed
write.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor

__all__ = ["OrderedWorker"]


class OrderedWorker:
    """Runs jobs in order on one thread, started with the first job."""

    def __init__(self, *, depth: int = 2) -> None:
        self._depth = depth
        self._pool: ThreadPoolExecutor | None = None
        self._pending: deque[Future[None]] = deque()
        self._failed = False

    def submit(self, job: Callable[[], None]) -> None:
        """Queue ``job``; wait while more than ``depth`` jobs are not yet done (raising the
        first one's exception, if it failed)."""
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="camlog-chunks")
        self._pending.append(self._pool.submit(self._run, job))
        while len(self._pending) > self._depth:
            self._pending.popleft().result()

    def _run(self, job: Callable[[], None]) -> None:
        if self._failed:
            return
        try:
            job()
        except BaseException:
            self._failed = True
            raise

    def drain(self) -> None:
        """Wait for every job given so far; raise the exception of a failed one."""
        while self._pending:
            self._pending.popleft().result()

    def close(self) -> None:
        """Wait for every job, then stop the thread (a job's exception is raised)."""
        try:
            self.drain()
        finally:
            self.abort()

    def abort(self) -> None:
        """Drop the jobs not yet started, wait for the running one, stop the thread."""
        self._failed = True
        self._pending.clear()
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

"""Log calls to a rerun recording in message order, each at the times of its message.

An image may still be encoding (JPEG on a worker thread) when the next messages arrive: the
calls after it wait behind it, at most :data:`MAX_PENDING` of them, so that every call still
reaches rerun in message order and memory stays bounded.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

import numpy as np
import rerun as rr

from .blueprint import LOG_TIME, REPLAY_TIME, STAMP_TIME
from .columns import ClearRow, ColumnBatcher, ImageRow, PointsRow, Times
from .sink import FLUSH_INTERVAL_S, flush_recording

__all__ = ["FLUSH_BYTES", "FLUSH_EVERY", "MAX_PENDING", "Emitter", "Flush"]

#: log calls held back behind an image still being encoded (bounds memory)
MAX_PENDING = 16
#: log calls between blocking flushes of the recording (bounds rerun's write queue)
FLUSH_EVERY = 400
#: bytes of rows (pixels) between blocking flushes: 400 calls of 640x480 colour images
#: would queue 120 MB (uncompressed) for rerun's writer
FLUSH_BYTES = 48 << 20

#: a blocking flush of the recording (default: :func:`flush_recording`)
Flush = Callable[[], None] | None
ROWS = (ImageRow, PointsRow, ClearRow)


class Emitter:
    """Sends ``(entity, archetype)`` log calls to ``rec`` at the current message's times;
    an archetype may be a :class:`~concurrent.futures.Future` of one (see :meth:`encode`,
    which runs on ``encoders`` worker threads), or a row (:mod:`rerun_export.columns`),
    sent in a batch of its entity's rows with ``columns`` and as its archetype otherwise (a
    live replay shows every frame when it comes). Counts rows per entity. ``flush`` waits
    for rerun's writer every :data:`FLUSH_EVERY` calls or :data:`FLUSH_BYTES` of rows,
    and at least every :data:`~.sink.FLUSH_INTERVAL_S` while calls come."""

    def __init__(self, rec: rr.RecordingStream, *, encoders: int = 0,
                 flush: Flush = None, columns: bool = False) -> None:
        self.rec = rec
        self._columns = ColumnBatcher(rec) if columns else None
        # a blocking flush that gives up when rerun stalls (see sink.flush_recording)
        self._flush = flush or (lambda: flush_recording(rec))
        self._pool = ThreadPoolExecutor(encoders, thread_name_prefix="camlog-jpeg") \
            if encoders else None
        self.counts: dict[str, int] = {}  # entity -> logged rows
        self._now: Times = (0, None, None)
        self._applied: Times | None = None  # times last set on the stream
        self._pending: deque[tuple[Times, str, Any]] = deque()
        self._logged = 0
        self._unflushed_bytes = 0  # of rows (pixels) sent since the last flush
        self._flushed_at = time.monotonic()

    def at(self, log_time_ns: int, stamp_ns: int | None, replay_ns: int | None) -> None:
        """The times of the message whose calls follow."""
        self._now = (log_time_ns, stamp_ns, replay_ns)

    def emit(self, entity: str, archetype: Any, *, count: bool = True) -> None:
        """Log at the current message's times, after anything logged before it."""
        self._pending.append((self._now, entity, archetype))
        self.drain(MAX_PENDING)
        if count:
            self.counts[entity] = self.counts.get(entity, 0) + 1

    def drain(self, keep: int = 0) -> None:
        """Send pending log calls in order; wait for an encoding only beyond ``keep``."""
        while self._pending:
            times, entity, archetype = self._pending[0]
            if isinstance(archetype, Future):
                if len(self._pending) <= keep and not archetype.done():
                    return
                archetype = archetype.result()
            self._pending.popleft()
            self._send(times, entity, archetype)
            self._logged += 1
            if isinstance(archetype, ROWS):
                self._unflushed_bytes += archetype.nbytes
            if self._logged % FLUSH_EVERY == 0 or self._unflushed_bytes >= FLUSH_BYTES or \
                    time.monotonic() - self._flushed_at >= FLUSH_INTERVAL_S:
                # rerun writes on its own thread; without back-pressure its queue grows with
                # the log's length whenever logging outpaces writing
                if self._columns is not None:
                    self._columns.flush()
                self._flush()
                self._flushed_at = time.monotonic()
                self._unflushed_bytes = 0

    def _send(self, times: Times, entity: str, archetype: Any) -> None:
        if self._columns is not None:
            if isinstance(archetype, ROWS):
                self._columns.add(entity, times, archetype)
                return
            self._columns.flush_entity(entity)  # the entity's earlier rows first
        if isinstance(archetype, ROWS):
            archetype = archetype.archetype()
        if times != self._applied:
            self._apply(times)
        self.rec.log(entity, archetype)

    def encode(self, make: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """``make(*args, **kwargs)``: an archetype, made on a worker thread when there are
        encoders (then a Future of it, which :meth:`emit` takes)."""
        if self._pool is None:
            return make(*args, **kwargs)
        return self._pool.submit(make, *args, **kwargs)

    def close(self) -> None:
        """Send what is still pending and stop the worker threads."""
        try:
            self.drain()
            if self._columns is not None:
                self._columns.flush()
        finally:
            if self._pool is not None:
                self._pool.shutdown(cancel_futures=True)

    def _apply(self, times: Times) -> None:
        log_time_ns, stamp_ns, replay_ns = times
        self.rec.set_time(LOG_TIME, timestamp=np.datetime64(log_time_ns, "ns"))
        if stamp_ns is None:
            self.rec.disable_timeline(STAMP_TIME)
        else:
            self.rec.set_time(STAMP_TIME, timestamp=np.datetime64(stamp_ns, "ns"))
        if replay_ns is not None:
            self.rec.set_time(REPLAY_TIME, timestamp=np.datetime64(replay_ns, "ns"))
        self._applied = times

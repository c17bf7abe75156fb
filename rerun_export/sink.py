"""Where a rerun recording goes: an ``.rrd`` file (atomically), a spawned or a running viewer.

An ``.rrd`` is written to a hidden temporary sibling (:mod:`replay.atomic`) and renamed when
the recording is complete, so a failed export never leaves a half-written file under the final
name.
"""

from __future__ import annotations

import shutil
import threading
import uuid
from collections.abc import Iterable
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import rerun as rr

from replay.atomic import AtomicOutput

from .combine import combine_recordings
from .errors import ViewerError
from .viewer import DEFAULT_PORT, LOCALHOST, grpc_url, require_viewer, spawn_viewer

__all__ = ["Destination", "RecordingSink", "flush_recording"]

APPLICATION_ID = "camlog"


#: rerun's file sink can hang when its first write fails: refuse a nearly full disk first
MIN_FREE_BYTES = 1 << 20


def _require_space(path: Path) -> None:
    free = shutil.disk_usage(path.parent).free
    if free < MIN_FREE_BYTES:
        raise ViewerError(f"cannot write {path.parent}: no space left on device "
                          f"({free} bytes free)")


#: seconds between blocking flushes of a recording however few its log calls (see
#: :class:`~.emitter.Emitter`): a live replay logs a few calls a second
FLUSH_INTERVAL_S = 2.0
#: how long a recording whose writer failed may take to let go of it
GIVE_UP_S = 2.0
#: a flush that makes no progress for this long means rerun's file writer, or the viewer
#: it sends to, is gone: rerun would wait for it forever. A viewer's is shorter by the
#: flush interval and the time to give up, so that a viewer that stops taking data ends
#: the command within :data:`VIEWER_DEADLINE_S`.
STALL_S = 10.0
VIEWER_DEADLINE_S = 15.0
NETWORK_STALL_S = VIEWER_DEADLINE_S - FLUSH_INTERVAL_S - GIVE_UP_S


def flush_recording(rec: rr.RecordingStream, watched: Path | None = None, *,
                    stall_s: float = STALL_S) -> None:
    """Wait until rerun has sent everything logged so far. Raises ``RuntimeError`` when it
    makes no progress for ``stall_s`` (a file ``watched`` that grows is progress)."""
    while True:
        before = _size(watched)
        try:
            rec.flush(timeout_sec=stall_s)
            return
        except RuntimeError as err:
            if "timed out" in str(err) and _size(watched) > before:
                continue  # slow, not stalled
            raise


def _disconnect(rec: rr.RecordingStream, wait_s: float) -> bool:
    """Drop a recording's sink; whether that finished. rerun can block here for good (after
    its writer failed, or with a viewer that takes the connection but never answers), so
    give it ``wait_s`` and then leave it behind (and skip rerun's flush at exit)."""
    done = threading.Thread(target=rec.disconnect, name="camlog-rerun-disconnect",
                            daemon=True)
    done.start()
    done.join(wait_s)
    if done.is_alive():
        _ABANDONED.append(rec)  # never collected: dropping it would block as well
        rr.unregister_shutdown()
        return False
    return True


#: recordings whose writer hung; kept alive so that nothing waits for them
_ABANDONED: list[rr.RecordingStream] = []


def _size(path: Path | None) -> int:
    try:
        return path.stat().st_size if path is not None else 0
    except OSError:
        return 0


def _rerun_failure(err: BaseException, *, to_file: bool) -> str:
    """rerun's error, with what it usually means."""
    text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    if "timed out" in text:
        return (f"rerun's file writer made no progress for {STALL_S:g} s: is the disk full "
                "or the file too large?") if to_file else \
            f"the viewer accepted no data for {NETWORK_STALL_S:g} s"
    if "shut down" in text or "Failed to write" in text:
        return f"rerun's writer stopped ({text}): is the disk full or the file too large?"
    return text


class RecordingSink:
    """A recording stream attached to exactly one destination; use as a context manager.

    ``output``: an ``.rrd`` path; ``connect``: a viewer URL; ``spawn``: start a viewer that
    listens on ``bind:port`` (default 127.0.0.1:9876). ``inputs``: the logs the recording is
    made from (an ``.rrd`` over one is refused).
    """

    def __init__(self, *, output: Path | None = None, connect: str | None = None,
                 spawn: bool = False, overwrite: bool = False, blueprint: Any = None,
                 bind: str = LOCALHOST, port: int = DEFAULT_PORT,
                 application_id: str = APPLICATION_ID, inputs: Iterable[Path] = (),
                 recording_id: str | None = None) -> None:
        chosen = sum((output is not None, connect is not None, spawn))
        if chosen != 1:
            raise ViewerError("choose one destination: -o OUT.rrd, --connect URL or --spawn")
        if output is not None and output.suffix != ".rrd":
            raise ViewerError(f"{output}: a rerun recording must end in .rrd")
        self.output = output
        self._url = grpc_url(connect) if connect is not None else None
        self._spawn = spawn
        self._bind, self._port = bind, port
        self._atomic = AtomicOutput(output, overwrite=overwrite, inputs=inputs,
                                    what="a rerun recording") if output is not None else None
        self._blueprint = blueprint
        self.rec = rr.RecordingStream(application_id, recording_id=recording_id or uuid.uuid4())
        self._stalled: RuntimeError | None = None

    def __enter__(self) -> Self:
        try:
            if self._atomic is not None:
                _require_space(self._atomic.temp)
                self.rec.save(self._atomic.temp, default_blueprint=self._blueprint)
            elif self._url is not None:
                require_viewer(self._url)
                self.rec.connect_grpc(self._url)
            else:
                self._url = spawn_viewer(bind=self._bind, port=self._port)
                self.rec.connect_grpc(self._url)
        except Exception as err:  # rerun raises RuntimeError/OSError/ValueError from Rust
            self._discard()
            if isinstance(err, ViewerError):
                raise
            raise ViewerError(f"cannot send the recording to {self._where()}: {err}") from None
        except BaseException:  # Ctrl-C: no output left behind
            self._discard()
            raise
        if self._atomic is None and self._blueprint is not None:
            self.rec.send_blueprint(self._blueprint, make_active=True, make_default=True)
        return self

    def _discard(self, *, failed: bool = False) -> None:
        try:
            if not any(rec is self.rec for rec in _ABANDONED):  # left behind already
                _disconnect(self.rec, GIVE_UP_S if failed else STALL_S)
        finally:  # a Ctrl-C while rerun lets go still removes the file
            if self._atomic is not None:
                self._atomic.discard()

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None,
                 tb: TracebackType | None) -> None:
        if et is not None:
            self._discard(failed=isinstance(ev, RuntimeError))
            if isinstance(ev, RuntimeError):  # rerun's writer thread died
                raise self._failure(_rerun_failure(ev, to_file=self._atomic is not None)) \
                    from None
            return
        try:
            self.flush()
            if not _disconnect(self.rec, STALL_S if self._atomic is not None
                               else NETWORK_STALL_S):
                raise RuntimeError("disconnecting timed out")  # said as a stall
            if self._atomic is not None:
                self._atomic.commit()
        except (OSError, RuntimeError) as err:
            self._discard(failed=True)
            reason = err.strerror if isinstance(err, OSError) and err.strerror \
                else _rerun_failure(err, to_file=self._atomic is not None)
            raise self._failure(reason) from None
        except BaseException:  # Ctrl-C while the last data is written: no output left
            self._discard()
            raise

    def _failure(self, reason: str) -> ViewerError:
        if self._atomic is not None:
            return ViewerError(f"cannot write {self.output}: {reason}")
        return ViewerError(f"cannot send the recording to {self._where()}: {reason}")

    def flush(self) -> None:
        """Wait until everything logged so far is written or sent; ``RuntimeError`` when
        rerun stalls (see :func:`flush_recording`)."""
        if self._stalled is not None:
            raise self._stalled  # once is enough
        try:
            if self._atomic is not None:
                flush_recording(self.rec, self._atomic.temp)
            else:
                flush_recording(self.rec, stall_s=NETWORK_STALL_S)
        except RuntimeError as err:
            self._stalled = err
            raise

    @property
    def url(self) -> str | None:
        """The viewer this sink sends to (known once entered), None for a file."""
        return self._url

    def _where(self) -> str:
        return str(self.output or self._url or "a spawned viewer")


class Destination:
    """Where the recordings of one export go; use as a context manager and take a
    :meth:`sink` per recording. One recording goes where :class:`RecordingSink` sends it.
    Several (unrelated logs) share the application id, each with its own recording id: to
    a viewer one after the other (the first started with ``spawn``), or into one ``.rrd``
    that holds them all, combined as a stream from one file per recording
    (:mod:`~.combine`, which keeps recordings apart). The layout goes with the first
    recording."""

    def __init__(self, *, count: int, blueprint: Any, output: Path | None = None,
                 connect: str | None = None, spawn: bool = False, overwrite: bool = False,
                 bind: str = LOCALHOST, port: int = DEFAULT_PORT,
                 inputs: Iterable[Path] = ()) -> None:
        self._count = count
        self._output, self._connect, self._spawn = output, connect, spawn
        self._overwrite, self._blueprint = overwrite, blueprint
        self._bind, self._port, self._inputs = bind, port, list(inputs)
        self._parts: list[Path] = []
        self._made = 0
        self._base = uuid.uuid4()
        self._first: RecordingSink | None = None
        self._atomic: AtomicOutput | None = None
        if count > 1 and output is not None:
            if output.suffix != ".rrd":
                raise ViewerError(f"{output}: a rerun recording must end in .rrd")
            self._atomic = AtomicOutput(output, overwrite=overwrite, inputs=self._inputs,
                                        what="a rerun recording")

    def __enter__(self) -> Self:
        if self._atomic is not None:
            self._atomic.temp.mkdir()
        return self

    def sink(self) -> RecordingSink:
        """The sink of the next recording (enter it to send)."""
        index, self._made = self._made, self._made + 1
        blueprint = self._blueprint if index == 0 else None  # one per application id
        # ids that sort in order (the viewer opens the first, which the layout's first tab
        # shows)
        recording_id = f"{self._base}-{index:03d}" if self._count > 1 else None
        if self._atomic is not None:
            part = self._atomic.temp / f"{index}.rrd"
            self._parts.append(part)
            return RecordingSink(output=part, blueprint=blueprint, recording_id=recording_id)
        if index > 0 and self._first is not None and self._first.url is not None:
            # the viewer the first recording started (or connected to)
            return RecordingSink(connect=self._first.url, blueprint=blueprint,
                                 recording_id=recording_id)
        sink = RecordingSink(
            output=self._output, connect=self._connect, spawn=self._spawn,
            overwrite=self._overwrite, blueprint=self._blueprint, bind=self._bind,
            port=self._port, inputs=self._inputs, recording_id=recording_id)
        self._first = self._first or sink
        return sink

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None,
                 tb: TracebackType | None) -> None:
        if self._atomic is None:
            return
        if et is not None:
            self._atomic.discard()
            return
        combined = self._atomic.temp / "combined.rrd"
        try:
            combine_recordings(self._parts, combined)
            self._atomic.commit(combined)
        except ViewerError as err:
            self._atomic.discard()
            raise ViewerError(f"cannot write {self._output}: {err}") from None
        except BaseException:  # Ctrl-C while combining: no output left
            self._atomic.discard()
            raise

"""Where a rerun recording goes: an ``.rrd`` file (atomically), a spawned or a running viewer.

An ``.rrd`` is written to a hidden temporary sibling (:mod:`replay.atomic`) and renamed when
the recording is complete, so a failed export never leaves a half-written file under the final
name.
"""

from __future__ import annotations

import socket
import uuid
from collections.abc import Iterable
from pathlib import Path
from types import TracebackType
from typing import Any, Self
from urllib.parse import urlsplit

import rerun as rr

from ..atomic import AtomicOutput
from ..errors import ViewerError

__all__ = ["RecordingSink", "default_output", "grpc_url", "require_listening"]

APPLICATION_ID = "camlog"
_SCHEMES = ("rerun://", "rerun+http://", "rerun+https://")


def default_output(log: Path) -> Path:
    """``run.mcap`` -> ``run.rrd``; a rosbag2 directory ``run`` -> ``run.rrd`` beside it."""
    return log.with_name(log.name + ".rrd") if log.is_dir() else log.with_suffix(".rrd")


def grpc_url(text: str) -> str:
    """A viewer address: ``rerun+http://host:port/proxy``, or ``host:port`` for short.

    >>> grpc_url("127.0.0.1:9876")
    'rerun+http://127.0.0.1:9876/proxy'
    """
    if text.startswith(_SCHEMES):
        return text
    host, _, port = text.rpartition(":")
    if host and port.isdigit():
        return f"rerun+http://{host}:{port}/proxy"
    raise ViewerError(f"not a viewer address: {text!r} (use rerun+http://HOST:PORT/proxy or "
                      "HOST:PORT)")


def require_listening(url: str, *, timeout_s: float = 2.0) -> None:
    """Fail early, with the address, when no viewer accepts connections at ``url`` (rerun
    itself would buffer the recording and drop it silently)."""
    parts = urlsplit(url.replace("rerun+", "", 1).replace("rerun://", "https://", 1))
    host, port = parts.hostname or "127.0.0.1", parts.port or 9876
    try:
        socket.create_connection((host, port), timeout=timeout_s).close()
    except OSError as err:
        raise ViewerError(f"no rerun viewer is listening at {url} ({err.strerror or err}); "
                          "start one with `rerun` or use --spawn") from None


class RecordingSink:
    """A recording stream attached to exactly one destination; use as a context manager.

    ``output``: an ``.rrd`` path; ``connect``: a viewer URL; ``spawn``: start a viewer.
    ``inputs``: the logs the recording is made from (an ``.rrd`` over one is refused).
    """

    def __init__(self, *, output: Path | None = None, connect: str | None = None,
                 spawn: bool = False, overwrite: bool = False, blueprint: Any = None,
                 application_id: str = APPLICATION_ID, inputs: Iterable[Path] = ()) -> None:
        chosen = sum((output is not None, connect is not None, spawn))
        if chosen != 1:
            raise ViewerError("choose one destination: -o OUT.rrd, --connect URL or --spawn")
        if output is not None and output.suffix != ".rrd":
            raise ViewerError(f"{output}: a rerun recording must end in .rrd")
        self.output = output
        self._url = grpc_url(connect) if connect is not None else None
        self._spawn = spawn
        self._atomic = AtomicOutput(output, overwrite=overwrite, inputs=inputs,
                                    what="a rerun recording") if output is not None else None
        self._blueprint = blueprint
        self.rec = rr.RecordingStream(application_id, recording_id=uuid.uuid4())

    def __enter__(self) -> Self:
        try:
            if self._atomic is not None:
                self.rec.save(self._atomic.temp, default_blueprint=self._blueprint)
            elif self._url is not None:
                require_listening(self._url)
                self.rec.connect_grpc(self._url)
            else:
                self.rec.spawn(connect=True)
        except ViewerError:
            self._discard()
            raise
        except Exception as err:  # rerun raises RuntimeError/OSError/ValueError from Rust
            self._discard()
            where = self.output or self._url or "a spawned viewer"
            raise ViewerError(f"cannot send the recording to {where}: {err}") from None
        if self._atomic is None and self._blueprint is not None:
            self.rec.send_blueprint(self._blueprint, make_active=True, make_default=True)
        return self

    def _discard(self) -> None:
        self.rec.disconnect()
        if self._atomic is not None:
            self._atomic.discard()

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None,
                 tb: TracebackType | None) -> None:
        if et is not None:
            self._discard()
            return
        try:
            self.rec.flush()
            self.rec.disconnect()
            if self._atomic is not None:
                self._atomic.commit()
        except OSError as err:
            self._discard()
            raise ViewerError(f"cannot write {self.output}: {err.strerror or err}") from None

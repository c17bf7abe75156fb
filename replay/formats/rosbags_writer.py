"""Writing through a ``rosbags`` writer object, shared by the rosbag2 and ROS1 writers."""

from __future__ import annotations

import contextlib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..errors import LogWriteError
from .base import LogWriter, RawMessage
from .rosbags_reader import first_line

__all__ = ["RosbagsWriter"]


class RosbagsWriter(LogWriter):
    """Shared writing through a rosbags writer: one connection per topic.

    Errors of the storage below (OS errors, SQLite's "disk is full") become
    :class:`LogWriteError` naming the output.
    """

    _writer: Any

    def __init__(self, path: Path, *, overwrite: bool, inputs: Iterable[Path]) -> None:
        super().__init__(path, overwrite=overwrite, inputs=inputs)
        self._conns: dict[str, Any] = {}

    def _open(self, writer: Any) -> None:
        self._writer = writer
        try:
            writer.open()
        except Exception as err:
            raise LogWriteError(f"cannot write {self.path}: {first_line(err)}") from None

    def _typestore(self) -> Any:
        raise NotImplementedError

    def _write(self, raw: RawMessage, msgdef: str) -> None:
        try:
            conn = self._conns.get(raw.topic)
            if conn is None:
                conn = self._writer.add_connection(raw.topic, raw.msgtype,
                                                   typestore=self._typestore())
                self._conns[raw.topic] = conn
            self._writer.write(conn, raw.log_time_ns, raw.data)  # copied into its chunk
        except (OSError, LogWriteError):
            raise
        except Exception as err:  # sqlite3.Error, rosbags' WriterError
            raise LogWriteError(f"cannot write {self.path}: {first_line(err)}") from None

    def _finish(self) -> None:
        try:
            self._writer.close()
        except OSError:
            raise
        except Exception as err:
            raise LogWriteError(f"cannot write {self.path}: {first_line(err)}") from None

    def _abort(self) -> None:
        with contextlib.suppress(Exception):  # the output is discarded anyway
            self._writer.abort()

"""rosbag2 directories (metadata.yaml + MCAP or SQLite storage files), read through ``rosbags``."""

from __future__ import annotations

import sqlite3
import tempfile
from pathlib import Path

from rosbags.rosbag2 import Reader as Reader2

from ..errors import LogReadError
from .rosbag2_reindex import ZSTD_MAGIC, lone_storage, rolled_back_copy
from .rosbags_reader import RosbagsReader, first_line

__all__ = ["Rosbag2LogReader"]


class Rosbag2LogReader(RosbagsReader):
    """Reader for a rosbag2 directory (metadata.yaml + .mcap or .db3 files).

    A directory without metadata.yaml (the recording was cut short) is read from its one
    SQLite storage file up to its last commit, as ``ros2 bag reindex`` would (see
    :mod:`.rosbag2_reindex`; the input is never modified), with a warning.
    """

    format_name = "rosbag2"

    def __init__(self, path: Path, *, recover: bool = False) -> None:
        self._scratch: tempfile.TemporaryDirectory[str] | None = None
        storage = None if (path / "metadata.yaml").exists() else lone_storage(path)
        try:
            opened = path if storage is None else self._recovered(storage)
            try:
                reader = Reader2(opened)
            except Exception as err:
                raise LogReadError(f"cannot read {path}: {first_line(err)}") from None
            super().__init__(path, reader)
        except BaseException:
            self._close_scratch()
            raise
        kind = "sqlite3" if opened.suffix == ".db3" or any(
            f.suffix == ".db3" for f in path.iterdir()) else "mcap"
        self.format_name = f"rosbag2 ({kind})"
        if storage is not None:
            self._decompress = self._first_message_is_zstd()
            self.warnings.append(
                f"{path} has no metadata.yaml (its recording was cut short?); read its "
                f"storage file {storage.relative_to(path)} up to its last commit, as `ros2 "
                f"bag reindex` would: {self.message_count} messages")

    def _recovered(self, storage: Path) -> Path:
        self._scratch = tempfile.TemporaryDirectory(prefix="camlog-reindex-")
        try:
            return rolled_back_copy(storage, Path(self._scratch.name))
        except (OSError, sqlite3.Error) as err:
            raise LogReadError(f"cannot read {storage}: {first_line(err)}") from None

    def _first_message_is_zstd(self) -> bool:
        """Whether messages carry rosbag2's per-message zstd compression, which only the
        missing metadata.yaml would have said."""
        for raw in self.raw_messages():
            return bytes(raw.data[:4]) == ZSTD_MAGIC
        return False

    def _close_scratch(self) -> None:
        if self._scratch is not None:
            self._scratch.cleanup()

    def close(self) -> None:
        try:
            super().close()
        finally:
            self._close_scratch()

"""rosbag2 directories (metadata.yaml + SQLite or MCAP storage files), read through ``rosbags``.

A folder whose storage is one SQLite file is read from that file as a bare ``.db3``: topics,
types and counts come from the database itself, as ``ros2 bag reindex`` takes them, and
metadata.yaml is only checked against it (a count it gets wrong, a line repeated, a file
listed twice is reported, not believed). Folders split over several files, or with other
storage, are read as their metadata.yaml says. A single MCAP storage file is read by the
MCAP reader (see :func:`replay.formats.open_reader`).
"""

from __future__ import annotations

import sqlite3
import tempfile
from pathlib import Path

from rosbags.rosbag2 import Reader as Reader2

from ...errors import LogReadError
from ..rosbags_reader import RosbagsReader, first_line
from .metadata import BagMetadata, count_warnings, read_metadata
from .reindex import ZSTD_MAGIC, has_journal, lone_storage, rolled_back_copy
from .salvage import Salvaged, salvaged_copy

__all__ = ["Rosbag2LogReader"]


class Rosbag2LogReader(RosbagsReader):
    """Reader for a rosbag2 directory (metadata.yaml + .mcap or .db3 files).

    A directory without metadata.yaml (the recording was cut short) is read from its one
    SQLite storage file up to its last commit, as ``ros2 bag reindex`` would (see
    :mod:`.reindex`; the input is never modified), with a warning. With
    ``recover``, a damaged SQLite storage file is read row by row: the rows that read are
    kept, and what was lost (rows, log times) is reported (:mod:`.salvage`).
    """

    format_name = "rosbag2"

    def __init__(self, path: Path, *, recover: bool = False) -> None:
        self._scratch: tempfile.TemporaryDirectory[str] | None = None
        metadata = read_metadata(path) if (path / "metadata.yaml").exists() else None
        storage = _sqlite_storage(path, metadata)
        salvaged = None
        if storage is not None and not recover:
            self.recover_hint = "; use --recover to read the rows that still read"
        try:
            opened = path
            if storage is not None:
                opened = storage
                if metadata is None or has_journal(storage):
                    opened = self._rolled_back(storage)
                if recover:
                    salvaged = self._salvaged(opened)
                    opened = salvaged.path
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
        if storage is None:
            return
        if isinstance(metadata, BagMetadata):
            self._decompress = metadata.message_compression
            self.warnings += count_warnings(
                path, metadata, {name: info.count for name, info in self.topics.items()})
        else:
            self._decompress = self._first_message_is_zstd()
            why = "has no metadata.yaml (its recording was cut short?)" if metadata is None \
                else f"has a damaged metadata.yaml ({metadata})"
            self.warnings.append(
                f"{path} {why}; read its storage file {storage.relative_to(path)} up to its "
                f"last commit, as `ros2 bag reindex` would: {self.message_count} messages")
        if salvaged is not None:
            self.warnings += _salvage_report(storage, salvaged)

    def _scratch_folder(self) -> Path:
        if self._scratch is None:
            self._scratch = tempfile.TemporaryDirectory(prefix="camlog-reindex-")
        return Path(self._scratch.name)

    def _rolled_back(self, storage: Path) -> Path:
        try:
            return rolled_back_copy(storage, self._scratch_folder())
        except (OSError, sqlite3.Error) as err:
            raise LogReadError(f"cannot read {storage}: {first_line(err)}") from None

    def _salvaged(self, storage: Path) -> Salvaged:
        folder = self._scratch_folder() / "salvaged"
        folder.mkdir()
        try:
            return salvaged_copy(storage, folder)
        except (OSError, sqlite3.Error) as err:
            raise LogReadError(f"cannot recover {storage}: {first_line(err)}") from None

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


def _sqlite_storage(folder: Path, metadata: BagMetadata | str | None) -> Path | None:
    """The one SQLite storage file to read as a bare database (None: let metadata.yaml
    lead, for storage split over several files or not SQLite)."""
    if isinstance(metadata, BagMetadata):
        files = set(metadata.files)
        if metadata.storage != "sqlite3" or len(files) != 1:
            return None
        storage = folder / files.pop()
        return storage if storage.is_file() else None
    lone = lone_storage(folder)
    return lone if lone is not None and lone.suffix == ".db3" else None


def _salvage_report(storage: Path, salvaged: Salvaged) -> list[str]:
    """One line per kind of loss of a salvaged SQLite storage file."""
    lines = []
    if salvaged.lost:
        spans = ", ".join(f"{'start' if a is None else a} to {'end' if b is None else b}"
                          for a, b in salvaged.gaps[:3])
        more = f" and {len(salvaged.gaps) - 3} more" if len(salvaged.gaps) > 3 else ""
        lines.append(f"{storage}: {salvaged.lost} message rows do not read and are lost, "
                     f"between log times {spans}{more} ns; read the other {salvaged.rows}")
    if salvaged.tables_lost:
        lines.append(f"{storage}: its tables {', '.join(salvaged.tables_lost)} do not read "
                     "(message definitions, QoS and bag metadata may be missing)")
    return lines

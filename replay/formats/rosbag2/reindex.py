"""rosbag2 directories whose recording was cut short: storage written, metadata.yaml not.

rosbag2 writes metadata.yaml when a recording closes. Without it, the storage file still
holds every committed message: an MCAP storage file is read directly, an SQLite one is
copied to a temporary folder where SQLite rolls back the transaction that was open when the
writer died (the input keeps its hot journal, untouched) and read as a bare ``.db3`` by
rosbags, which takes topics and counts from the database — what ``ros2 bag reindex``
rebuilds metadata.yaml from.
"""

from __future__ import annotations

import shutil
import sqlite3
from pathlib import Path

__all__ = ["ZSTD_MAGIC", "has_journal", "lone_storage", "rolled_back_copy"]

#: first bytes of a zstd frame (rosbag2's per-message compression); CDR starts 00 01
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
#: SQLite's side files: rollback journal, write-ahead log
_SIDE_FILES = ("-journal", "-wal")


def lone_storage(path: Path) -> Path | None:
    """The one storage file (``.mcap`` or ``.db3``) of a rosbag2 directory, or of its one
    subfolder (camlog's temporary output holds it one folder down); None when there is not
    exactly one."""
    for pattern in ("*", "*/*"):
        found = [p for p in sorted(path.glob(pattern))
                 if p.suffix in (".mcap", ".db3") and p.is_file()]
        if found:
            return found[0] if len(found) == 1 else None
    return None


def has_journal(db3: Path) -> bool:
    """Whether SQLite left a rollback journal or write-ahead log next to ``db3`` (a writer
    that did not finish)."""
    return any(db3.with_name(db3.name + suffix).is_file() for suffix in _SIDE_FILES)


def rolled_back_copy(db3: Path, scratch: Path) -> Path:
    """Copy ``db3`` and its journal into ``scratch`` and let SQLite recover the copy to its
    last committed state; returns the copy's path."""
    copy = scratch / db3.name
    shutil.copyfile(db3, copy)
    for suffix in _SIDE_FILES:
        side = db3.with_name(db3.name + suffix)
        if side.is_file():
            shutil.copyfile(side, copy.with_name(copy.name + suffix))
    connection = sqlite3.connect(copy)
    try:
        # the first read of a database with a hot journal rolls it back
        connection.execute("SELECT count(*) FROM sqlite_master").fetchone()
        connection.execute("PRAGMA journal_mode=DELETE").fetchone()  # merge a WAL, if any
    finally:
        connection.close()
    return copy

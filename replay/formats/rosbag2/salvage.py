"""The rows of a damaged rosbag2 SQLite storage file that still read, in a new database.

SQLite stops a query at the first damaged page (``database disk image is malformed``), so
one bad page makes a whole storage file unreadable through ``rosbags``. For ``--recover``,
:func:`salvaged_copy` builds a new database with the same tables: every table copied whole
where it reads, and the messages row by row past the rows that do not, counting them and
noting between which log times they lay. The input is opened read-only and never modified.
"""

from __future__ import annotations

import sqlite3
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Salvaged", "salvaged_copy"]


@dataclass(frozen=True)
class Salvaged:
    """The new database and what did not make it into it."""

    path: Path
    rows: int  # messages copied
    lost: int  # message rows that do not read
    #: (first_ns, last_ns) of the readable messages on either side of each run of lost
    #: rows (None at the ends of the table)
    gaps: tuple[tuple[int | None, int | None], ...]
    tables_lost: tuple[str, ...]  # other tables that do not read


def salvaged_copy(db3: Path, scratch: Path) -> Salvaged:
    """Copy what reads of ``db3`` into a new database in ``scratch``; raises
    ``sqlite3.DatabaseError`` when not even its table of topics reads."""
    copy = scratch / db3.name
    source = sqlite3.connect(f"file:{db3}?mode=ro", uri=True)
    target = sqlite3.connect(copy)
    try:
        tables = source.execute("SELECT name, sql FROM sqlite_master WHERE type = 'table' "
                                "AND sql IS NOT NULL AND name NOT LIKE 'sqlite_%'").fetchall()
        lost_tables = []
        for _name, sql in tables:
            target.execute(sql)
        for name, _sql in tables:
            if name == "messages":
                continue
            try:
                _copy_rows(source, target, f'SELECT * FROM "{name}"', name)
            except sqlite3.DatabaseError:
                if name == "topics":
                    raise
                lost_tables.append(name)
        rows, lost, gaps = _copy_messages(source, target)
        target.commit()
    finally:
        source.close()
        target.close()
    return Salvaged(copy, rows, lost, tuple(gaps), tuple(lost_tables))


def _copy_rows(source: sqlite3.Connection, target: sqlite3.Connection, query: str,
               table: str, parameters: tuple[int, ...] = ()) -> int:
    count = 0
    for row in source.execute(query, parameters):
        marks = ", ".join("?" * len(row))
        target.execute(f'INSERT INTO "{table}" VALUES ({marks})', row)
        count += 1
    return count


def _copy_messages(source: sqlite3.Connection, target: sqlite3.Connection,
                   ) -> tuple[int, int, list[tuple[int | None, int | None]]]:
    """Messages in id order, in one pass while it reads, then row by row."""
    copied = 0
    last_id = 0
    last_ns: int | None = None
    try:
        for row in source.execute("SELECT * FROM messages ORDER BY id"):
            target.execute(f"INSERT INTO messages VALUES ({', '.join('?' * len(row))})", row)
            copied += 1
            last_id, last_ns = row[0], row[2]
        return copied, 0, []
    except sqlite3.DatabaseError:
        pass
    (highest,) = source.execute("SELECT max(id) FROM messages").fetchone()
    lost = 0
    gaps: list[tuple[int | None, int | None]] = []
    in_gap = False
    for row_id in range(last_id + 1, (highest or 0) + 1):
        try:
            row = source.execute("SELECT * FROM messages WHERE id = ?", (row_id,)).fetchone()
        except sqlite3.DatabaseError:
            lost += 1
            if not in_gap:
                gaps.append((last_ns, None))
                in_gap = True
            continue
        if row is None:
            continue
        target.execute(f"INSERT INTO messages VALUES ({', '.join('?' * len(row))})", row)
        copied += 1
        last_ns = row[2]
        if in_gap:
            gaps[-1] = (gaps[-1][0], last_ns)
            in_gap = False
    if lost == 0:  # the one pass failed on something it could not say: count it once
        lost, gaps = 1, [(last_ns, None)]
    return copied, lost, gaps

"""Benchmark tables written into the page that shows them.

A table of ``docs/benchmarks.md`` that a benchmark measures sits between two marker lines::

    <!-- table: NAME -->
    | ... |
    <!-- /table: NAME -->

and the benchmark, given ``--write-docs``, replaces what lies between them with the table it
measured (:func:`write_table`), or only its own rows of a table several benchmarks share
(:func:`write_rows`: the rows whose first cell starts with the benchmark's key). The page is
rewritten atomically; a missing, repeated or unclosed marker is one error naming the page and
the table, and nothing is written.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Iterable, Sequence
from pathlib import Path

from replay.atomic import write_text_atomic

__all__ = ["PAGE", "TABLES", "DocsTableError", "add_write_docs", "markdown_row",
           "markdown_table", "replace_rows", "replace_table", "write_rows", "write_table"]

PAGE = Path(__file__).resolve().parents[1] / "docs" / "benchmarks.md"
#: the tables of :data:`PAGE` that benchmarks write -> the command that writes them
TABLES = {
    "summary": "python -m benchmarks --write-docs (or any one of its benchmarks, for its rows)",
    "peers": "python -m benchmarks.peers --write-docs",
    "peers_growth": "python -m benchmarks.peers --runs 0 --growth 4,40,400 --write-docs",
    "calibration_accuracy": "python -m benchmarks.calibrate_speed --write-docs",
    "vs_mrcal": "python -m benchmarks.vs_mrcal --write-docs",
    "calibration_honesty": "python -m benchmarks.calibration_honesty --write-docs",
    "corpus": "python -m benchmarks.corpus.run --write-docs",
    "time_offset_board": "python -m benchmarks.time_offset --cases board --write-docs",
    "time_offset_natural": "python -m benchmarks.time_offset --cases natural --write-docs",
    "time_offset_rig": "python -m benchmarks.time_offset --cases rig --write-docs",
}


class DocsTableError(Exception):
    """A page without the markers of the table a benchmark writes (or with them twice)."""


def add_write_docs(parser: argparse.ArgumentParser) -> None:
    """``--write-docs``: write the benchmark's table into ``docs/benchmarks.md``."""
    parser.add_argument("--write-docs", action="store_true",
                        help="write the measured table into docs/benchmarks.md (between its "
                             "<!-- table: NAME --> markers)")


def markdown_row(cells: Sequence[str]) -> str:
    """One row of a Markdown table (``|`` in a cell is escaped; an empty cell is ``| |``)."""
    return "|" + "|".join(f" {c} ".replace("|", "\\|") if c else " " for c in cells) + "|"


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> list[str]:
    """The lines of a Markdown table: the header, its rule, the rows."""
    return [markdown_row(header), "| " + " | ".join("---" for _ in header) + " |",
            *map(markdown_row, rows)]


def _block(text: str, name: str, where: str) -> tuple[int, int]:
    """Start and end offsets of what lies between the markers of table ``name``."""
    opening = re.compile(rf"^<!-- table: {re.escape(name)} -->\n", re.M)
    closing = re.compile(rf"^<!-- /table: {re.escape(name)} -->$", re.M)
    starts, ends = list(opening.finditer(text)), list(closing.finditer(text))
    if len(starts) != 1 or len(ends) != 1 or ends[0].start() < starts[0].end():
        raise DocsTableError(
            f"{where} has no single '<!-- table: {name} -->' ... '<!-- /table: {name} -->' "
            f"block (found {len(starts)} opening and {len(ends)} closing markers): add one "
            f"around the table")
    return starts[0].end(), ends[0].start()


def replace_table(text: str, name: str, lines: Sequence[str], *, where: str = "the page") -> str:
    """``text`` with the block of table ``name`` replaced by ``lines``."""
    start, end = _block(text, name, where)
    return text[:start] + "\n" + "".join(f"{line}\n" for line in lines) + "\n" + text[end:]


def replace_rows(text: str, name: str, key: str, rows: Sequence[str], *,
                 where: str = "the page") -> str:
    """``text`` with the rows of table ``name`` whose first cell starts with ``key`` (each
    with the rows after it whose first cell is empty: a group such as a case's figures)
    replaced by ``rows``, in place of the first of them or after the table's last row; the
    header and every other row stay."""
    start, end = _block(text, name, where)
    lines = text[start:end].splitlines()
    mine: list[int] = []
    in_group = False
    for i, line in enumerate(lines):
        if line.startswith("|"):
            first = line[1:].split("|", 1)[0].strip()
            in_group = first.startswith(key) if first else in_group
            if in_group:
                mine.append(i)
        else:
            in_group = False
    table = [i for i, line in enumerate(lines) if line.startswith("|")]
    at = mine[0] if mine else (table[-1] + 1 if table else len(lines))
    kept = [line for i, line in enumerate(lines) if i not in set(mine)]
    kept[at:at] = rows
    return text[:start] + "".join(f"{line}\n" for line in kept) + text[end:]


def write_table(name: str, lines: Sequence[str], *, page: Path | None = None) -> None:
    """Replace table ``name`` of ``page`` (default :data:`PAGE`) by ``lines``, atomically; a
    page without the table's markers ends the benchmark with one error line."""
    page = page or PAGE
    try:
        text = replace_table(page.read_text(), name, lines, where=str(page))
    except DocsTableError as err:
        raise SystemExit(f"error: {err}") from None
    write_text_atomic(page, text)
    print(f"wrote table {name} into {page}", flush=True)


def write_rows(name: str, key: str, rows: Sequence[str], *, page: Path | None = None) -> None:
    """Replace the rows of table ``name`` of ``page`` (default :data:`PAGE`) that start with
    ``key``, atomically; a page without the table's markers ends the benchmark with one
    error line."""
    page = page or PAGE
    try:
        text = replace_rows(page.read_text(), name, key, rows, where=str(page))
    except DocsTableError as err:
        raise SystemExit(f"error: {err}") from None
    write_text_atomic(page, text)
    print(f"wrote {len(rows)} rows of {key} into table {name} of {page}", flush=True)

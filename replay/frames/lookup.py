"""Looking a message kind's encoding up in the frame tables, or failing with the choices."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TypeVar

__all__ = ["table_entry"]

Entry = TypeVar("Entry")


def table_entry(table: Mapping[tuple[type, str], Entry], kind: type, key: str, *,
                error: Callable[[str], Exception], unknown: str, shown: str | None = None,
                choices: str = "supported: {}", sep: str = ", ") -> Entry:
    """``table[kind, key]``, else ``error`` with one line: ``unknown``, the key as the user
    gave it (``shown``, default ``key``) and, in ``choices``, the table's keys for ``kind``,
    sorted and joined with ``sep``.

    >>> table_entry({(str, "png"): 1}, str, "gif", error=ValueError, unknown="no format")
    Traceback (most recent call last):
    ValueError: no format 'gif' (supported: png)
    """
    entry = table.get((kind, key))
    if entry is None:
        known = sep.join(sorted(k for t, k in table if t is kind))
        raise error(f"{unknown} {key if shown is None else shown!r} ({choices.format(known)})")
    return entry

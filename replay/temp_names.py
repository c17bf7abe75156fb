"""The names of camlog's temporary outputs: ``.NAME.camlog-<16 hex digits>.tmp`` beside
``NAME`` (see :mod:`replay.atomic`, which writes them, and :mod:`replay.leftovers`, which
finds those an unfinished run left)."""

from __future__ import annotations

import re
import secrets
from pathlib import Path

__all__ = ["is_temp_output", "temp_output_of", "temp_sibling"]

_TEMP = re.compile(r"^\.(?P<name>.+)\.camlog-[0-9a-f]{16}\.tmp$")


def temp_sibling(final: Path) -> Path:
    """A hidden name next to ``final`` that no file has: ``.NAME.camlog-<random>.tmp``."""
    while True:
        temp = final.parent / f".{final.name}.camlog-{secrets.token_hex(8)}.tmp"
        if not (temp.exists() or temp.is_symlink()):
            return temp


def is_temp_output(path: Path) -> bool:
    """Whether ``path`` is named like a camlog temporary output."""
    return _TEMP.match(path.name) is not None


def temp_output_of(path: Path) -> Path | None:
    """The final path a camlog temporary output was meant for (None: not a temp name)."""
    match = _TEMP.match(path.name)
    return path.with_name(match["name"]) if match else None

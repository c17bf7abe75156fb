"""What a finished or failed command leaves next to its outputs."""

from __future__ import annotations

from pathlib import Path

from replay.atomic import is_temp_output


def temp_outputs(folder: Path) -> list[Path]:
    """camlog's temporary outputs in ``folder`` (none after a run that finished or failed)."""
    return sorted(p for p in folder.iterdir() if is_temp_output(p))

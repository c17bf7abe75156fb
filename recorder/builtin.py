"""The scenario specs that ship with camlog, and the limits of a recording, without loading
the recorder (for ``camlog record``'s argument parser)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["DEFAULT_SCENARIO", "MAX_FRAMES", "builtin_dir", "builtin_names"]

DEFAULT_SCENARIO = "mono_checkerboard"

#: most frames per camera of one recording (9 hours at 30 Hz; planning and memory stay sane)
MAX_FRAMES = 1_000_000


def builtin_dir() -> Path:
    """Folder of the built-in scenario specs."""
    return Path(str(resources.files("camlog_datasets") / "scenarios"))


def builtin_names() -> list[str]:
    """Names of the scenario specs that ship with camlog."""
    return sorted(p.stem for p in builtin_dir().glob("*.toml"))

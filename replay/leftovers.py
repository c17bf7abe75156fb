"""Temporary outputs an earlier run left behind, found and described.

A run killed mid-way leaves its hidden temporary output, ``.NAME.camlog-<16 hex>.tmp``
(:mod:`replay.atomic`), beside the ``NAME`` it was writing. A later run writing ``NAME``
says so in one line (:func:`warn_leftovers`, called by every atomic output), and ``camlog
info FOLDER`` lists them (:func:`leftovers_in`): each with its size, its age, what it was
meant to become and the command that recovers it (a log) or that it can be removed.
"""

from __future__ import annotations

import shlex
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from .sizes import bytes_on_disk, format_size
from .temp_names import temp_output_of

__all__ = ["Leftover", "describe_leftovers", "format_leftovers", "leftovers_in", "leftovers_of",
           "warn_leftovers"]

#: leftovers a warning was printed for in this process (one line each, once)
_WARNED: set[Path] = set()
#: how a log file begins: MCAP, ROS1 bag
LOG_MAGICS = (b"\x89MCAP", b"#ROSBAG V2.0")
#: the files of a rosbag2 folder that has no metadata.yaml yet: storage files and SQLite's
#: journals (a temporary one holds them one folder down)
STORAGE_FILES = (".mcap", ".db3", ".db3-journal", ".db3-wal", ".db3-shm")


@dataclass(frozen=True, slots=True)
class Leftover:
    """One earlier run's temporary output: where it is and the ``final`` name it was for."""

    path: Path
    final: Path

    @property
    def size_bytes(self) -> int:
        """Bytes of the file, or of every file below the folder."""
        try:
            return bytes_on_disk(self.path)
        except OSError:
            return 0

    @property
    def age_s(self) -> float:
        """Seconds since it was last written."""
        try:
            return max(0.0, time.time() - self.path.stat().st_mtime)
        except OSError:
            return 0.0

    @property
    def is_log(self) -> bool:
        """Whether it is a log (an MCAP file, a rosbag2 folder, a ROS1 bag), which
        ``camlog convert --recover`` reads up to its last complete chunk."""
        try:
            if self.path.is_dir():
                return _is_rosbag2(self.path)
            with self.path.open("rb") as f:
                head = f.read(16)
        except OSError:
            return False
        return head.startswith(LOG_MAGICS)

    def recovery(self, *, final_in_use: bool) -> str:
        """What to do with it: the command that recovers a log into ``final`` (or, when
        ``final_in_use``, into a name beside it), else that it can be removed."""
        if not self.is_log:
            return f"it can be removed: rm -r {shlex.quote(str(self.path))}"
        target = self.final
        if final_in_use or target.exists() or target.is_symlink():
            target = target.with_name(f"{target.stem}-recovered{target.suffix}")
        return (f"recover it with: camlog convert --recover {shlex.quote(str(self.path))} "
                f"{shlex.quote(str(target))}")

    def describe(self, *, final_in_use: bool = False) -> str:
        """``PATH (SIZE, AGE old), meant to become NAME; recover it with: ...``"""
        size = format_size(self.size_bytes).split(" (")[0]
        kind = "folder" if self.path.is_dir() else "file"
        return (f"{self.path} ({kind}, {size}, {format_age(self.age_s)} old), left by a run "
                f"that did not finish writing {self.final.name}; "
                f"{self.recovery(final_in_use=final_in_use)}")


def _is_rosbag2(folder: Path) -> bool:
    """A rosbag2 folder: its metadata.yaml, or nothing but storage files (a calibration
    folder also holds a ``calibration.mcap``, beside YAML and JSON files)."""
    if (folder / "metadata.yaml").is_file():
        return True
    files = [f.name for f in folder.rglob("*") if f.is_file()]
    return bool(files) and all(name.endswith(STORAGE_FILES) for name in files)


def format_age(age_s: float) -> str:
    """``42 s``, ``5 min``, ``3 h``, ``2 days``."""
    for unit, seconds in (("days", 86_400), ("h", 3_600), ("min", 60)):
        if age_s >= seconds:
            return f"{int(age_s // seconds)} {unit}"
    return f"{int(age_s)} s"


def leftovers_of(final: Path) -> list[Leftover]:
    """Temporary outputs earlier runs left for ``final`` (``.NAME.camlog-*.tmp`` beside it)."""
    try:
        candidates = sorted(final.parent.glob(f".{glob_escape(final.name)}.camlog-*.tmp"))
    except OSError:
        return []
    return [Leftover(path, final) for path in candidates if temp_output_of(path) == final]


def leftovers_in(folder: Path) -> list[Leftover]:
    """Every camlog temporary output directly inside ``folder``, by name."""
    try:
        entries = sorted(folder.iterdir())
    except OSError:
        return []
    found = []
    for path in entries:
        final = temp_output_of(path)
        if final is not None:
            found.append(Leftover(path, final))
    return found


def glob_escape(name: str) -> str:
    """``name`` with glob's special characters matched literally."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in name)


def describe_leftovers(leftovers: list[Leftover]) -> list[str]:
    """One line per leftover (see :meth:`Leftover.describe`)."""
    return [leftover.describe() for leftover in leftovers]


def format_leftovers(folder: Path, leftovers: list[Leftover]) -> str:
    """The listing ``camlog info FOLDER`` prints (no trailing newline): per leftover its
    name, kind, size, age, the name it was meant to become and what to do with it."""
    lines = [f"folder:    {folder}",
             f"leftovers: {len(leftovers)} (temporary outputs of camlog runs that did not "
             "finish)"]
    for leftover in leftovers:
        kind = "folder" if leftover.path.is_dir() else "file"
        lines += [f"  {leftover.path.name}",
                  f"    {kind}, {format_size(leftover.size_bytes)}, "
                  f"{format_age(leftover.age_s)} old; meant to become {leftover.final.name}",
                  f"    {leftover.recovery(final_in_use=False)}"]
    return "\n".join(lines)


def warn_leftovers(final: Path) -> None:
    """Print one ``warning:`` line on stderr per earlier run's temporary output for
    ``final``, once per process: a run about to write ``final`` is the moment to learn that
    a run before it was killed and how to recover what that one wrote."""
    for leftover in leftovers_of(final):
        if leftover.path in _WARNED:
            continue
        _WARNED.add(leftover.path)
        print(f"warning: {leftover.describe(final_in_use=True)}", file=sys.stderr, flush=True)

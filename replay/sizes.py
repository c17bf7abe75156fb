"""Bytes on disk of a file or folder, and how camlog writes a size for people."""

from __future__ import annotations

from pathlib import Path

__all__ = ["bytes_on_disk", "format_size"]


def bytes_on_disk(path: Path) -> int:
    """Bytes of a file, or of all files below a directory."""
    if path.is_dir():
        return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    return path.stat().st_size


def format_size(size_bytes: int) -> str:
    """``3.9 MiB (4129654 bytes)``."""
    value = float(size_bytes)
    for unit in ("B", "KiB", "MiB", "GiB"):
        if value < 1024 or unit == "GiB":
            break
        value /= 1024
    scaled = f"{size_bytes} B" if unit == "B" else f"{value:.1f} {unit}"
    return f"{scaled} ({size_bytes} bytes)"

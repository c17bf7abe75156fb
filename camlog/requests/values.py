"""Value types of request options: text (a command-line word, a pipeline value) made a
typed value, validated (finite, in range, non-empty, sane sizes); each raises
:class:`argparse.ArgumentTypeError` with a one-line reason."""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable
from pathlib import Path

__all__ = ["ESTIMATED", "bounded_int", "name", "namespaces", "non_negative", "number",
           "offset_value", "output_path", "positive"]

#: bytes a file name may have on common file systems (ext4, xfs, btrfs, tmpfs, APFS)
NAME_MAX = 255
#: bytes camlog adds to an output's name for its temporary sibling
TEMP_NAME_ROOM = 32


def bounded_int(low: int, high: int | None) -> Callable[[str], int]:
    """A type: an integer in ``[low, high]`` (``high`` None: no upper bound)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < low or (high is not None and value > high):
            bound = f"{low}..{high}" if high is not None else f">= {low}"
            raise argparse.ArgumentTypeError(f"expected {bound}, got {value}")
        return value
    return parse


def number(low: float | None = None, high: float | None = None, *,
           above: float | None = None) -> Callable[[str], float]:
    """A type: a finite number ``>= low`` (or ``> above``) and ``<= high``."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
        if above is not None and not value > above:
            raise argparse.ArgumentTypeError(f"expected a number > {above:g}, got {text}")
        if low is not None and value < low:
            raise argparse.ArgumentTypeError(f"expected a number >= {low:g}, got {text}")
        if high is not None and value > high:
            raise argparse.ArgumentTypeError(f"expected a number <= {high:g}, got {text}")
        return value
    return parse


#: a finite number > 0
positive = number(above=0.0)
#: a finite number >= 0
non_negative = number(low=0.0)


#: ``--offset``'s word for an offset measured from the images
ESTIMATED = "estimated"
#: the largest time offset given by hand (ms)
MAX_OFFSET_MS = 10_000.0


def offset_value(text: str) -> float | str:
    """A type: a time offset in milliseconds (a number), ``estimated``, or the path of an
    offset result file (``.json``)."""
    word = text.strip()
    if word.lower() == ESTIMATED:
        return ESTIMATED
    if word.endswith(".json"):
        return word
    try:
        value = float(word)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected milliseconds, '{ESTIMATED}' or an offset file (.json), got {text!r}"
            ) from None
    if not math.isfinite(value) or abs(value) > MAX_OFFSET_MS:
        raise argparse.ArgumentTypeError(
            f"expected milliseconds within ±{MAX_OFFSET_MS:g}, got {text!r}")
    return value


def name(text: str) -> str:
    """A type: a topic or namespace name: not empty, no spaces or control
    characters."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a name, got an empty string")
    if any(c.isspace() or not c.isprintable() for c in text):
        raise argparse.ArgumentTypeError(f"{text!r} has spaces or control characters")
    return text


def output_path(text: str) -> Path:
    """A type: a path to write, whose name leaves room for camlog's temporary name."""
    if not text:
        raise argparse.ArgumentTypeError("expected a path, got an empty string")
    path = Path(text)
    size = len(os.fsencode(path.name))
    if size + TEMP_NAME_ROOM > NAME_MAX:
        raise argparse.ArgumentTypeError(
            f"the name {path.name[:40]}... is {size} bytes long; file systems allow {NAME_MAX} "
            f"and camlog needs {TEMP_NAME_ROOM} of them for its temporary name")
    return path


def namespaces(text: str) -> list[str]:
    """A type: comma-separated camera namespaces (or image topics), two or more."""
    spaces = [name(part.strip()) for part in text.split(",")]
    if len(spaces) < 2:
        raise argparse.ArgumentTypeError("a rig has two cameras or more: NS,NS,...")
    return spaces

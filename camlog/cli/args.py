"""Argument types that validate (finite, in range, non-empty, sane sizes) and argument
groups shared by the log commands (topic and time selection, viewer choice)."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable, Iterable
from pathlib import Path

from replay.format_names import WRITE_FORMATS

#: bytes a file name may have on common file systems (ext4, xfs, btrfs, tmpfs, APFS)
NAME_MAX = 255
#: bytes camlog adds to an output's name for its temporary sibling
TEMP_NAME_ROOM = 32


def bounded_int(low: int, high: int | None) -> Callable[[str], int]:
    """argparse type: an integer in ``[low, high]`` (``high`` None: no upper bound)."""
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
    """argparse type: a finite number ``>= low`` (or ``> above``) and ``<= high``."""
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


def name(text: str) -> str:
    """argparse type: a topic or namespace name: not empty, no spaces or control
    characters."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a name, got an empty string")
    if any(c.isspace() or not c.isprintable() for c in text):
        raise argparse.ArgumentTypeError(f"{text!r} has spaces or control characters")
    return text


def output_path(text: str) -> Path:
    """argparse type: a path to write, whose name leaves room for camlog's temporary name."""
    if not text:
        raise argparse.ArgumentTypeError("expected a path, got an empty string")
    path = Path(text)
    size = len(os.fsencode(path.name))
    if size + TEMP_NAME_ROOM > NAME_MAX:
        raise argparse.ArgumentTypeError(
            f"the name {path.name[:40]}... is {size} bytes long; file systems allow {NAME_MAX} "
            f"and camlog needs {TEMP_NAME_ROOM} of them for its temporary name")
    return path


def add_selection(p: argparse.ArgumentParser) -> None:
    """``--topics``, ``--start``, ``--end``."""
    p.add_argument("--topics", nargs="+", action="extend", metavar="T",
                   help="only these topics (exact names or globs such as '/cam/*'; put the "
                        "option after the log paths)")
    p.add_argument("--start", type=non_negative, metavar="S",
                   help="start S seconds after the first message")
    p.add_argument("--end", type=non_negative, metavar="S",
                   help="stop S seconds after the first message (exclusive)")


def add_viewer_destination(p: argparse.ArgumentParser, *, what: str) -> None:
    """``-o OUT | --spawn | --connect URL`` and ``--overwrite``."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("-o", "--output", type=output_path, metavar="OUT",
                       help=f"write the {what} to OUT")
    where.add_argument("--spawn", action="store_true", help="start a rerun viewer and stream to it")
    where.add_argument("--connect", metavar="URL",
                       help="stream to a running viewer (rerun+http://HOST:PORT/proxy or "
                            "HOST:PORT)")
    p.add_argument("--bind", default="127.0.0.1", metavar="ADDR", type=name,
                   help="with --spawn: the address the viewer listens on (default 127.0.0.1, "
                        "this machine only; 0.0.0.0 for every interface)")
    p.add_argument("--port", default=9876, type=bounded_int(1, 65535), metavar="N",
                   help="with --spawn: the port the viewer listens on (default 9876; a viewer "
                        "already there is used)")
    add_overwrite(p)


def print_warnings(warnings: Iterable[str]) -> None:
    """One ``warning:`` line per warning on stderr."""
    for warning in warnings:
        print(f"warning: {warning}", file=sys.stderr)


def add_format_argument(parser: argparse.ArgumentParser, *, default_from: str) -> None:
    """``--format``: the output log format, by default told from ``default_from``'s name."""
    parser.add_argument("--format", choices=sorted(WRITE_FORMATS),
                        help=f"output format (default: from {default_from})")


def add_recover(parser: argparse.ArgumentParser) -> None:
    """``--recover``: read a damaged log as far as it can be read."""
    parser.add_argument("--recover", action="store_true",
                        help="read a damaged log: past damaged chunks (MCAP, ROS1) and the "
                             "SQLite rows that still read (rosbag2), saying what was lost")


def add_overwrite(parser: argparse.ArgumentParser) -> None:
    """``--overwrite``: replace existing outputs."""
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")


def add_no_progress(parser: argparse.ArgumentParser) -> None:
    """``--no-progress``: hide progress bars."""
    parser.add_argument("--no-progress", action="store_true", help="hide progress bars")

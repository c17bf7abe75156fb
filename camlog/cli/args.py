"""Argument groups shared by the log commands (topic and time selection, viewer choice)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterable
from pathlib import Path


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


def add_selection(p: argparse.ArgumentParser) -> None:
    """``--topics``, ``--start``, ``--end``."""
    p.add_argument("--topics", nargs="+", action="extend", metavar="T",
                   help="only these topics (exact names or globs such as '/cam/*'; put the "
                        "option after the log paths)")
    p.add_argument("--start", type=float, metavar="S",
                   help="start S seconds after the first message")
    p.add_argument("--end", type=float, metavar="S",
                   help="stop S seconds after the first message (exclusive)")


def add_viewer_destination(p: argparse.ArgumentParser, *, what: str) -> None:
    """``-o OUT | --spawn | --connect URL`` and ``--overwrite``."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("-o", "--output", type=Path, metavar="OUT",
                       help=f"write the {what} to OUT")
    where.add_argument("--spawn", action="store_true", help="start a rerun viewer and stream to it")
    where.add_argument("--connect", metavar="URL",
                       help="stream to a running viewer (rerun+http://HOST:PORT/proxy or "
                            "HOST:PORT)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output")


def print_warnings(warnings: Iterable[str]) -> None:
    """One ``warning:`` line per warning on stderr."""
    for warning in warnings:
        print(f"warning: {warning}", file=sys.stderr)

"""What the command modules share: a request's arguments, the flags of the commands without a
request, warnings on stderr, and the value types (from :mod:`camlog.requests.values`)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable

from ..requests.values import (
    bounded_int,
    name,
    namespaces,
    non_negative,
    number,
    output_path,
    positive,
)

__all__ = ["add_no_progress", "add_overwrite", "add_request", "bounded_int", "name",
           "namespaces", "non_negative", "number", "output_path", "positive", "print_warnings"]


def add_request(p: argparse.ArgumentParser, request: type) -> None:
    """The arguments of a command's request, and its epilog (a class attribute) if it has
    one."""
    from ..requests.arguments import add_request_arguments

    p.epilog = getattr(request, "epilog", None)
    add_request_arguments(p, request)


def print_warnings(warnings: Iterable[str]) -> None:
    """One ``warning:`` line per warning on stderr."""
    for warning in warnings:
        print(f"warning: {warning}", file=sys.stderr)


def add_overwrite(parser: argparse.ArgumentParser) -> None:
    """``--overwrite``: replace existing outputs."""
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")


def add_no_progress(parser: argparse.ArgumentParser) -> None:
    """``--no-progress``: hide progress bars."""
    parser.add_argument("--no-progress", action="store_true", help="hide progress bars")

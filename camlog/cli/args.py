"""What the command modules share: a request's arguments and warnings on stderr."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable

__all__ = ["add_request", "print_warnings"]


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

"""``camlog golden check|update|record``: golden-log regression over the committed inputs."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.golden import GoldenRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``golden`` arguments."""
    add_request(p, GoldenRequest)


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.golden.run.run_golden` and print what it did; exit 1 when a check
    found differences."""
    from ..golden.run import MANIFEST, run_golden

    request = request_from_args(GoldenRequest, args)
    done = run_golden(request)
    if request.action == "record":
        print("\n".join(done.lines))
        print(f"wrote {done.inputs / MANIFEST}; now run camlog golden update")
        return 0
    if request.action == "update":
        print("\n".join(done.lines))
        return 0
    for difference in done.differences:
        print(difference)
        if difference.detail:
            print("\n".join(f"    {line}" for line in difference.detail.splitlines()))
    differing = len({d.artifact for d in done.differences})
    print(f"{differing} golden artifacts differ from {done.expected}" if done.differences
          else f"golden outputs match {done.expected}")
    return 1 if done.differences else 0

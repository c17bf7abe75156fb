"""``camlog demo``: the whole workflow on built-in scenarios, outputs in one folder."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.demo import DemoRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``demo`` arguments."""
    add_request(p, DemoRequest)


def run(args: argparse.Namespace) -> int:
    """Run the demo, printing where each output went."""
    from ..demo import run_demo

    request = request_from_args(DemoRequest, args)
    result = run_demo(request)
    print(f"done in {result.wall_s:.0f} s; everything is in {request.output}/")
    return 0

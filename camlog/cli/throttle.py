"""``camlog throttle LOG -o OUT --topic T (--rate HZ | --every N)``: thin topics of a log.

The registry's ``throttle`` processor chooses the frames; they are copied as stored (no
decode of pixels, no re-encoding), and every other topic is copied whole.
"""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.processing import ThrottleRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``throttle`` arguments."""
    add_request(p, ThrottleRequest)


def run(args: argparse.Namespace) -> int:
    """Thin the topics with the throttle the command line configured."""
    from ..processing.process_log import process_log

    request = request_from_args(ThrottleRequest, args)
    result = process_log(request.processing())
    print(f"kept {result.frames_processed} of {result.frames_read} messages of "
          f"{', '.join(request.topic)} in {result.wall_s:.2f} s")
    print(f"wrote {result.output}")
    return 0

"""``camlog process LOG --topic T ...``: run image processors over image topics of a log.

The processor flags are fields of the request, made from :mod:`processors.registry`.
"""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.processing import ProcessRequest
from .args import add_request, print_warnings


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``process`` arguments: the request's, the processors' among them."""
    add_request(p, ProcessRequest)


def run(args: argparse.Namespace) -> int:
    """Run the processors the command line chose over the log."""
    from ..processing.process_log import process_log

    request = request_from_args(ProcessRequest, args)
    result = process_log(request)
    names = ", ".join(c.name for c in request.processors)
    print(f"processed {result.frames_processed} of {result.frames_read} frames of "
          f"{', '.join(request.topic)} ({names}) in {result.wall_s:.2f} s "
          f"({result.fps:.0f} frames/s)")
    for output in result.outputs:
        print(f"  {output.topic}: {output.label}")
    print(f"wrote {result.output}")
    print_warnings(result.warnings)
    return 0

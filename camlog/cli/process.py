"""``camlog process LOG --topic T ...``: run image processors over image topics of a log.

The processor flags are generated from :mod:`processors.registry`.
"""

from __future__ import annotations

import argparse
import dataclasses

from processors.registry import SPECS

from ..errors import UsageError
from ..requests.arguments import request_from_args
from ..requests.processing import ProcessRequest
from .args import add_request, print_warnings
from .processor_args import add_processor_arguments, chosen_processors, worded


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``process`` arguments: the request's, then the processors'."""
    add_request(p, ProcessRequest)
    add_processor_arguments(p, SPECS)


def run(args: argparse.Namespace) -> int:
    """Build the processors named on the command line and run them over the log."""
    from ..processing.process_log import process_log

    processors = chosen_processors(args, SPECS)
    if not any(not c.spec.selects for c in processors):
        names = ", ".join(s.cli_flag for s in SPECS if s.flag)
        raise UsageError(f"choose at least one of {names}")
    request = dataclasses.replace(request_from_args(ProcessRequest, args),
                                  processors=tuple(processors))
    with worded({c.name: c.spec for c in processors}):
        result = process_log(request)
    names = ", ".join(c.name for c in processors)
    print(f"processed {result.frames_processed} of {result.frames_read} frames of "
          f"{', '.join(request.topic)} ({names}) in {result.wall_s:.2f} s "
          f"({result.fps:.0f} frames/s)")
    for output in result.outputs:
        print(f"  {output.topic}: {output.label}")
    print(f"wrote {result.output}")
    print_warnings(result.warnings)
    return 0

"""``camlog play LOG``: replay a log in (scaled) real time to a viewer, an .rrd or a log."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.play import PlayRequest
from .args import add_request, print_warnings


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``play`` arguments."""
    add_request(p, PlayRequest)


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.logs.play.play_log` and report the pacing."""
    from camlog.logs.play import play_log

    request = request_from_args(PlayRequest, args)
    result = play_log(request)
    print(f"played {result.messages} messages ({result.loops} loop(s) of "
          f"{result.log_span_s:.3f} s at {request.rate:g}x) in {result.wall_s:.2f} s; "
          f"latest message {result.late_s * 1e3:.1f} ms late")
    print_warnings(result.warnings)
    if result.output:
        print(f"wrote {result.output}")
    return 0

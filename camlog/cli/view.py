"""``camlog view LOG [LOG...]``: logs as a rerun recording (.rrd) or in a live viewer."""

from __future__ import annotations

import argparse

from ..lean import without_pandas
from ..requests.arguments import request_from_args
from ..requests.play import ViewRequest
from .args import add_request, print_warnings


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``view`` arguments."""
    add_request(p, ViewRequest)


def run(args: argparse.Namespace) -> int:
    """Call :func:`rerun_export.view_logs` and print what it logged."""
    from rerun_export.paths import refuse_output

    request = request_from_args(ViewRequest, args)
    refuse_output(list(request.logs), request.output,
                  live=request.spawn or request.connect is not None, overwrite=request.overwrite)
    if getattr(args, "as_program", False):
        without_pandas()
    from rerun_export import LoggerOptions, view_logs

    options = LoggerOptions(every=request.every, jpeg_quality=request.jpeg_quality,
                            residual_scale=request.residual_scale,
                            ground_truth=request.ground_truth,
                            undistorted_scale=request.undistorted_scale
                            if request.undistort else None)
    result = view_logs(
        request.logs, output=request.output, spawn=request.spawn, connect=request.connect,
        bind=request.bind, port=request.port, overwrite=request.overwrite,
        topics=request.topics, start_s=request.start, end_s=request.end,
        recover=request.recover, options=options, progress=request.progress, say=print)
    remapped = f", {result.remapped} of pinhole views" if result.remapped else ""
    print(f"logged {result.messages} messages ({result.images} images{remapped}, "
          f"{len(result.cameras)} cameras: {', '.join(result.cameras) or 'none'}) in "
          f"{result.wall_s:.2f} s")
    if result.recordings > 1:
        print(f"{result.recordings} recordings: the logs are unrelated (no shared camera at a "
              "shared time), each keeps its own timeline")
    for topic, why in sorted(result.skipped.items()):
        print(f"not shown: {topic}: {why}")
    if result.duplicates:
        shown = ", ".join(result.duplicates[:3]) + (", ..." if len(result.duplicates) > 3 else "")
        print(f"{len(result.duplicates)} topics repeated by a later log were read from the "
              f"first: {shown}")
    print_warnings(result.warnings)
    print(f"wrote {result.output}" if result.output else "sent to the viewer")
    return 0

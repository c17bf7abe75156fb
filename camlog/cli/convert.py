"""``camlog convert IN OUT``: between MCAP, rosbag2 and ROS1, filtered, images re-encoded."""

from __future__ import annotations

import argparse
from pathlib import Path

from replay.atomic import refuse_existing

from ..requests.arguments import request_from_args
from ..requests.logs import ConvertRequest
from .args import add_request, print_warnings


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``convert`` arguments."""
    add_request(p, ConvertRequest)


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.logs.convert.convert_log`."""
    request = request_from_args(ConvertRequest, args)
    refuse_existing(request.output, overwrite=request.overwrite, inputs=[Path(request.input)])
    from camlog.logs.convert import convert_log

    result = convert_log(request)
    print(f"converted {result.messages} messages ({result.reencoded} images re-encoded) to "
          f"{result.format_name} in {result.wall_s:.2f} s")
    for before, after in sorted(result.renamed.items()):
        print(f"renamed {before} -> {after}")
    for topic, psnr in sorted(result.psnr_db.items()):
        print(f"{topic}: {request.compress} PSNR {psnr:.1f} dB (mean over its frames)")
    print_warnings(result.warnings)
    print(f"wrote {result.output}")
    return 0

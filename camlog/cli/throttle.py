"""``camlog throttle LOG -o OUT --topic T (--rate HZ | --every N)``: thin topics of a log.

The registry's ``throttle`` processor chooses the frames; they are copied as stored (no
decode of pixels, no re-encoding), and every other topic is copied whole.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from processors.registry import spec_of

from .args import add_format_argument, add_overwrite, add_recover
from .processor_args import add_processor_arguments, chosen_processors, worded


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``throttle`` arguments."""
    p.add_argument("log", metavar="LOG", type=Path, help="input log (never modified)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="output log: .mcap, .bag or a rosbag2 directory name")
    p.add_argument("--topic", required=True, action="append", metavar="T", dest="topics",
                   help="topic to thin (images, camera_info or other stamped messages); "
                        "repeat it for several (each is thinned by its own stamps)")
    add_processor_arguments(p, [spec_of("throttle")], required=True)
    add_format_argument(p, default_from="OUT")
    add_overwrite(p)
    add_recover(p)


def run(args: argparse.Namespace) -> int:
    """Thin the topics with the throttle the command line configured."""
    from ..processing.process_log import process_log

    spec = spec_of("throttle")
    processors = chosen_processors(args, [spec])
    with worded({spec.name: spec}):
        result = process_log(args.log, args.output, topics=args.topics, processors=processors,
                             thin=True, fmt=args.format, overwrite=args.overwrite,
                             recover=args.recover)
    print(f"kept {result.frames_processed} of {result.frames_read} messages of "
          f"{', '.join(args.topics)} in {result.wall_s:.2f} s")
    print(f"wrote {result.output}")
    return 0

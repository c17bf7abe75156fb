"""``camlog process LOG --topic T ...``: run image processors over image topics of a log.

The processor flags are generated from :mod:`processors.registry`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from processors.registry import SPECS

from ..errors import UsageError
from ..processing.outputs import CHAPTER_NS, COMPRESSIONS
from .args import (
    add_format_argument,
    add_overwrite,
    add_recover,
    bounded_int,
    name,
    output_path,
    print_warnings,
)
from .processor_args import add_processor_arguments, chosen_processors, worded


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``process`` arguments."""
    p.epilog = (
        "Every input message is copied through unchanged (unless --drop-input); outputs carry "
        "the processed frame's header and log time. Outputs of TOPIC go to NS/OUTPUT, NS "
        "being TOPIC's namespace (/cam for /cam/image_raw) unless --output-ns says otherwise; "
        "the log records which processor wrote each output and how `camlog view` shows it."
    )
    p.add_argument("log", metavar="LOG", type=Path, help="input log (never modified)")
    p.add_argument("-o", "--output", type=output_path, required=True, metavar="OUT",
                   help="output log: .mcap, .bag or a rosbag2 directory name")
    p.add_argument("--topic", type=name, required=True, action="append", metavar="T",
                   dest="topics",
                   help="image topic to process (Image or CompressedImage, e.g. "
                        "/cam/image_raw or /cam/image_raw/compressed); repeat it for "
                        "several cameras")
    p.add_argument("--output-ns", metavar="NS",
                   help="namespace of the outputs; {ns} stands for the input's (e.g. "
                        f"/processed{{ns}}); {CHAPTER_NS} gives the chapter's topic names")
    add_processor_arguments(p, SPECS)
    p.add_argument("--compress", choices=COMPRESSIONS,
                   help="write image outputs as CompressedImage on TOPIC/compressed")
    p.add_argument("--drop-input", "--topics-only", dest="drop_input", action="store_true",
                   help="write only the processors' output topics, not the input's")
    p.add_argument("--max-frames", type=bounded_int(1, None), metavar="N",
                   help="stop after N frames of each topic (quick runs)")
    p.add_argument("--workers", type=bounded_int(1, 256), metavar="N",
                   help="processing threads (default: cores)")
    add_format_argument(p, default_from="OUT")
    add_overwrite(p)
    add_recover(p)


def run(args: argparse.Namespace) -> int:
    """Build the processors named on the command line and run them over the log."""
    from ..processing.process_log import process_log

    processors = chosen_processors(args, SPECS)
    if not any(not c.spec.selects for c in processors):
        names = ", ".join(s.cli_flag for s in SPECS if s.flag)
        raise UsageError(f"choose at least one of {names}")
    with worded({c.name: c.spec for c in processors}):
        result = process_log(
            args.log, args.output, topics=args.topics, processors=processors,
            output_ns=args.output_ns, compress=args.compress, drop_input=args.drop_input,
            max_frames=args.max_frames, fmt=args.format, overwrite=args.overwrite,
            workers=args.workers, recover=args.recover,
        )
    names = ", ".join(c.name for c in processors)
    print(f"processed {result.frames_processed} of {result.frames_read} frames of "
          f"{', '.join(args.topics)} ({names}) in {result.wall_s:.2f} s "
          f"({result.fps:.0f} frames/s)")
    for output in result.outputs:
        print(f"  {output.topic}: {output.label}")
    print(f"wrote {result.output}")
    print_warnings(result.warnings)
    return 0

"""``camlog info LOG``: format, size, time span, topics, rates and image encodings of a log;
``camlog info FOLDER``: the temporary outputs unfinished runs left in it."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from .args import add_recover


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the ``info`` arguments."""
    parser.add_argument(
        "log", metavar="LOG", type=Path,
        help="MCAP file, rosbag2 directory or ROS1 .bag; or a folder, to list the temporary "
             "outputs that unfinished camlog runs left in it"
    )
    add_recover(parser)
    parser.add_argument(
        "--verify",
        action="store_true",
        help="read every message (checksums included) instead of the log's index, so that "
             "damage anywhere is found",
    )


def run(args: argparse.Namespace) -> int:
    """Print the summary of ``args.log`` on stdout and what is wrong with the log (damage,
    recovery, unfinished outputs beside it) on stderr; for a folder that is not a log, the
    unfinished outputs in it on stdout. Errors propagate as :class:`replay.ReplayError`."""
    from camlog.logs.info import format_summary, summarize
    from replay.errors import LogFormatError
    from replay.formats import detect_format, open_reader
    from replay.leftovers import describe_leftovers, format_leftovers, leftovers_in, leftovers_of

    from .args import print_warnings

    if args.log.is_dir():
        try:
            detect_format(args.log)
        except LogFormatError as err:
            leftovers = leftovers_in(args.log)
            if not leftovers:
                raise LogFormatError(f"{err}, and holds no output an unfinished camlog run "
                                     "left") from None
            print(format_leftovers(args.log, leftovers))
            return 0
    with open_reader(args.log, recover=args.recover) as reader:
        summary = summarize(reader, verify=args.verify)
    print(format_summary(dataclasses.replace(summary, warnings=())))
    print_warnings(summary.warnings)
    inside = leftovers_in(args.log) if args.log.is_dir() else []
    print_warnings(describe_leftovers(inside + leftovers_of(args.log)))
    return 0

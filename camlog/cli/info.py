"""``camlog info LOG``: format, size, time span, topics, rates and image encodings of a log."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from .args import add_recover


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the ``info`` arguments."""
    parser.add_argument(
        "log", metavar="LOG", type=Path, help="MCAP file, rosbag2 directory or ROS1 .bag"
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
    recovery) on stderr; errors propagate as :class:`replay.ReplayError`."""
    from replay.formats import open_reader
    from replay.info import format_summary, summarize

    from .args import print_warnings

    with open_reader(args.log, recover=args.recover) as reader:
        summary = summarize(reader, verify=args.verify)
    print(format_summary(dataclasses.replace(summary, warnings=())))
    print_warnings(summary.warnings)
    return 0

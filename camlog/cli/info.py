"""``camlog info LOG``: format, size, time span, topics, rates and image encodings of a log."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the ``info`` arguments."""
    parser.add_argument(
        "log", metavar="LOG", type=Path, help="MCAP file, rosbag2 directory or ROS1 .bag"
    )
    parser.add_argument(
        "--recover",
        action="store_true",
        help="read a damaged log up to the damage",
    )
    parser.add_argument(
        "--verify",
        action="store_true",
        help="read every message (checksums included) instead of the log's index, so that "
             "damage anywhere is found",
    )


def run(args: argparse.Namespace) -> int:
    """Print the summary of ``args.log``; errors propagate as :class:`replay.ReplayError`."""
    print(info_text(args.log, recover=args.recover, verify=args.verify))
    return 0


def info_text(path: Path, *, recover: bool = False, verify: bool = False) -> str:
    """The text ``camlog info`` prints for one log."""
    from replay.formats import open_reader
    from replay.info import format_summary, summarize

    with open_reader(path, recover=recover) as reader:
        return format_summary(summarize(reader, verify=verify))

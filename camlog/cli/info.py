"""``camlog info LOG``: format, size, time span, topics, rates and image encodings of a log;
``camlog info FOLDER``: the temporary outputs unfinished runs left in it."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from ..requests.arguments import request_from_args
from ..requests.logs import InfoRequest
from .args import add_request


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the ``info`` arguments."""
    add_request(parser, InfoRequest)


def run(args: argparse.Namespace) -> int:
    """Print the summary of ``args.log`` on stdout and what is wrong with the log (damage,
    recovery, unfinished outputs beside it) on stderr; for a folder that is not a log, the
    unfinished outputs in it on stdout. Errors propagate as :class:`replay.ReplayError`."""
    from camlog.logs.info import format_summary, summarize
    from replay.errors import LogFormatError
    from replay.formats import detect_format, open_reader
    from replay.leftovers import describe_leftovers, format_leftovers, leftovers_in, leftovers_of

    from .args import print_warnings

    request = request_from_args(InfoRequest, args)
    log = Path(request.log)
    if log.is_dir():
        try:
            detect_format(log)
        except LogFormatError as err:
            leftovers = leftovers_in(log)
            if not leftovers:
                raise LogFormatError(f"{err}, and holds no output an unfinished camlog run "
                                     "left") from None
            print(format_leftovers(log, leftovers))
            return 0
    with open_reader(log, recover=request.recover) as reader:
        summary = summarize(reader, verify=request.verify)
    print(format_summary(dataclasses.replace(summary, warnings=())))
    print_warnings(summary.warnings)
    inside = leftovers_in(log) if log.is_dir() else []
    print_warnings(describe_leftovers(inside + leftovers_of(log)))
    return 0

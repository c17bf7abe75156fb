"""``camlog info LOG``: format, size, time span, topics, rates and image encodings of a log;
``camlog info FOLDER``: the temporary outputs unfinished runs left in it."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.logs import InfoRequest
from .args import add_request, print_warnings


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the ``info`` arguments."""
    add_request(parser, InfoRequest)


def run(args: argparse.Namespace) -> int:
    """Print the summary of the log on stdout and what is wrong with it on stderr
    (:func:`camlog.logs.info.describe_log`)."""
    from camlog.logs.info import describe_log

    report = describe_log(request_from_args(InfoRequest, args))
    print(report.text)
    print_warnings(report.warnings)
    return 0

"""``camlog check LOG…``: is every log still calibrated? Drift checks window by window."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.check import CheckRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``check`` arguments."""
    add_request(p, CheckRequest)


def run(args: argparse.Namespace) -> int:
    """Check every log, write the report and print one line per log; the exit status says
    whether any drifted (:func:`camlog.check.flow.exit_status`)."""
    from ..check.flow import check_drift, exit_status, options_of
    from ..check.report import write_report

    request = request_from_args(CheckRequest, args)
    options = options_of(request)
    checks = []
    for log in request.logs:
        checked = check_drift(log, options)
        print(checked.summary(), flush=True)
        checks.append(checked)
    write_report(checks, request.output)
    print(f"wrote {request.output / 'check.csv'}, {request.output / 'report.md'} and "
          f"{request.output / 'check.rrd'}")
    return exit_status(checks)

"""``camlog check``'s flow: every log of a request checked in turn, then one report over
them all (:mod:`camlog.check.report`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..requests.check import CheckRequest
from .flow import LogCheck, check_drift, options_of
from .report import write_report

__all__ = ["CheckRun", "check_logs"]


@dataclass(frozen=True)
class CheckRun:
    """Every log's check, in the request's order, and the report's files."""

    checks: list[LogCheck]
    files: list[Path]


def check_logs(request: CheckRequest, *,
               on_log: Callable[[LogCheck], None] | None = None) -> CheckRun:
    """Check the request's logs (``on_log`` hears of each as it is done) and write the report
    into its ``output`` folder."""
    options = options_of(request)
    checks = []
    for log in request.logs:
        checked = check_drift(log, options, progress=request.progress)
        if on_log is not None:
            on_log(checked)
        checks.append(checked)
    return CheckRun(checks, write_report(checks, request.output))

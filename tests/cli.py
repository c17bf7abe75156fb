"""The one runner of camlog's command line for the tests that check it: the command runs in
this process, and its exit status and what it printed come back.

Tests of what a command computes call its flow with a request instead (e.g.
``calibrate_log(CalibrateRequest(...))``); tests that start camlog as a separate process
(Ctrl-C, crashes, import times) run ``python -m camlog`` themselves.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass
from pathlib import Path

from camlog.cli import main

__all__ = ["CliRun", "cli", "run_cli"]


@dataclass(frozen=True)
class CliRun:
    """A command's exit status and what it printed on stdout and stderr."""

    code: int
    out: str
    err: str


def run_cli(*argv: str | Path) -> CliRun:
    """``camlog ARGV`` with its output captured (usable in session and module fixtures,
    where ``capsys`` is not)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return CliRun(code, out.getvalue(), err.getvalue())


def cli(*argv: str | Path) -> CliRun:
    """``camlog ARGV``, which must succeed."""
    run = run_cli(*argv)
    assert run.code == 0, (argv, run.err)
    return run

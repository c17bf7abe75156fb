"""``camlog check LOG…``: is every log still calibrated? Drift checks window by window."""

from __future__ import annotations

import argparse
from pathlib import Path

from processors.calibration.patterns import PATTERNS

from .args import number, positive


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``check`` arguments."""
    p.epilog = (
        "Stereo pairs are checked by the right camera's rotation relative to the left that "
        "explains the vertical error of natural features matched across the rectified "
        "pair; cameras that see a board (--size, --square) by its reprojection error. A "
        "pair is flagged from the window where its rotation, from there on, passes 5 "
        "sigmas of the log's own noise and the calibration's uncertainty; a board's window "
        "when its error passes their median by as much (--threshold replaces the limit). "
        "Writes OUTDIR/check.csv, OUTDIR/report.md, one PNG per log and OUTDIR/check.rrd; "
        "prints one line per log: clean, drifted from when and by how much, or not judged "
        "and why. Exit status: 0 every log clean, 3 a log drifted, 4 none drifted but one "
        "could not be judged (too few windows, nothing checkable), 1 an error, 2 a usage "
        "error.")
    p.add_argument("logs", nargs="+", metavar="LOG", help="logs to check (paths or URIs)")
    p.add_argument("-o", "--output", type=Path, default=Path("check"), metavar="OUTDIR",
                   help="report folder (default ./check)")
    p.add_argument("--window", type=number(above=0.0, high=3600.0), default=2.0, metavar="SEC",
                   help="window length in seconds (default 2)")
    p.add_argument("--rate", type=number(above=0.0, high=1000.0), default=5.0, metavar="HZ",
                   help="frames (stereo pairs) looked at per second of log (default 5)")
    p.add_argument("--threshold", type=positive, metavar="X",
                   help="flag windows above X (px: vertical error, reprojection error) "
                        "instead of the measured limit")
    p.add_argument("--calibration", type=Path, metavar="DIR|YAML",
                   help="check this calibration instead of the log's camera_info: a "
                        "calibrate output folder (left.yaml + right.yaml, or ost.yaml) or a "
                        "YAML file")
    p.add_argument("--camera", action="append", default=[], metavar="NS",
                   help="check only this camera (namespace or image topic); repeatable")
    p.add_argument("-s", "--size", metavar="COLSxROWS",
                   help="a board in view: its size in inner corners, e.g. 7x6")
    p.add_argument("-q", "--square", type=positive, metavar="M",
                   help="a board in view: its square side in metres")
    p.add_argument("-p", "--pattern", default="chessboard", choices=PATTERNS,
                   help="the board's kind (default chessboard)")


def run(args: argparse.Namespace) -> int:
    """Check every log, write the report and print one line per log; the exit status says
    whether any drifted (:func:`camlog.check.flow.exit_status`)."""
    from processors.calibration.board import make_board

    from ..check.flow import CheckOptions, check_log, exit_status
    from ..check.report import write_report
    from ..errors import UsageError

    if (args.size is None) != (args.square is None):
        raise UsageError("a board needs both --size and --square")
    board = make_board(args.size, args.square, args.pattern) if args.size else None
    options = CheckOptions(window_s=args.window, rate_hz=args.rate, board=board,
                           calibration=args.calibration, cameras=args.camera,
                           threshold=args.threshold)
    checks = []
    for log in args.logs:
        checked = check_log(log, options)
        print(checked.summary(), flush=True)
        checks.append(checked)
    write_report(checks, args.output)
    print(f"wrote {args.output / 'check.csv'}, {args.output / 'report.md'} and "
          f"{args.output / 'check.rrd'}")
    return exit_status(checks)

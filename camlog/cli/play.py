"""``camlog play LOG``: replay a log in (scaled) real time to a viewer, an .rrd or a log."""

from __future__ import annotations

import argparse
from pathlib import Path

from replay.format_names import LOG_TIMES, WRITE_FORMATS

from .args import (
    add_no_progress,
    add_recover,
    add_selection,
    add_viewer_destination,
    bounded_int,
    number,
    print_warnings,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``play`` arguments."""
    p.epilog = (
        "Messages are emitted when due: (log time - first log time) / RATE after the start. "
        "-o OUT.rrd records the replay for rerun (timelines log_time, header_stamp and "
        "replay_time); any other -o OUT is a log that receives the messages as they are "
        "played, bytes and header stamps unchanged, log time = the wall-clock time of "
        "emission (--log-time original keeps the input's). An endless --loop ends with "
        "Ctrl-C, keeping what was played."
    )
    p.add_argument("logs", metavar="LOG", type=Path, nargs="+",
                   help="log(s) to replay (several are merged in log time)")
    p.add_argument("--rate", type=number(low=1e-3, high=1e6), default=1.0, metavar="R",
                   help="speed factor (default 1: real time; 2: twice as fast)")
    add_selection(p)
    p.add_argument("--loop", nargs="?", const=0, default=1, type=bounded_int(1, None),
                   metavar="N", help="replay N times, or until interrupted without N")
    add_viewer_destination(p, what="replay (.rrd: rerun recording; else a log)")
    p.add_argument("--log-time", choices=LOG_TIMES, default="replay",
                   help="log time written to a log output (default: replay wall clock)")
    p.add_argument("--format", choices=sorted(WRITE_FORMATS),
                   help="log output format (default: from OUT)")
    add_recover(p)
    add_no_progress(p)


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.logs.play.play_log` and report the pacing."""
    from camlog.logs.play import play_log

    result = play_log(
        args.logs, rate=args.rate, start_s=args.start, end_s=args.end, topics=args.topics,
        loops=args.loop, output=args.output, spawn=args.spawn, connect=args.connect,
        bind=args.bind, port=args.port,
        log_time=args.log_time, fmt=args.format, overwrite=args.overwrite,
        recover=args.recover, progress=False if args.no_progress else None)
    print(f"played {result.messages} messages ({result.loops} loop(s) of "
          f"{result.log_span_s:.3f} s at {args.rate:g}x) in {result.wall_s:.2f} s; "
          f"latest message {result.late_s * 1e3:.1f} ms late")
    print_warnings(result.warnings)
    if result.output:
        print(f"wrote {result.output}")
    return 0

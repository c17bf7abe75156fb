"""``camlog demo``: the whole workflow on built-in scenarios, outputs in one folder."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import UsageError
from .args import add_no_progress, positive


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``demo`` arguments."""
    p.epilog = ("Records stereo_unsynced, resyncs the unsynchronised pair and calibrates it; "
                "meanwhile records red_block and runs red pixels + edges on it; then writes "
                "one rerun recording of the results. Each step prints what it wrote and its "
                "size. Re-running replaces the folder's files.")
    p.add_argument("-o", "--output", type=Path, default=Path("demo"), metavar="OUTDIR",
                   help="folder for every output (default ./demo)")
    p.add_argument("--duration", type=positive, default=8.0, metavar="S",
                   help="length of the stereo recording in seconds (default 8)")
    p.add_argument("--seed", type=int, default=0, help="random seed of both scenarios")
    add_no_progress(p)


def run(args: argparse.Namespace) -> int:
    """Run the demo, printing where each output went."""
    from ..demo import run_demo

    if args.duration <= 0:
        raise UsageError(f"--duration must be positive, got {args.duration:g}")
    result = run_demo(args.output, duration_s=args.duration, seed=args.seed,
                      progress=False if args.no_progress else None)
    print(f"done in {result.wall_s:.0f} s; everything is in {args.output}/")
    return 0

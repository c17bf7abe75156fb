"""``camlog golden check|update|record``: golden-log regression over the committed inputs."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import GoldenError
from .args import bounded_int


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``golden`` arguments."""
    p.epilog = (
        "check: verify the inputs' sha256 against manifest.json, run every job (calibrate, "
        "resync, process) over them and compare with the expected outputs (exit 1 on a "
        "difference; image failures write expected/actual/difference PNGs to --diff-dir). "
        "update: rewrite the expected outputs that changed and print what changed. "
        "record: re-render the inputs and rewrite manifest.json (rendering depends on the GL "
        "stack: commit new inputs together with `camlog golden update`)."
    )
    p.add_argument("action", choices=("check", "update", "record"),
                   help="compare with, regenerate, or re-record the goldens")
    p.add_argument("--only", action="append", metavar="INPUT",
                   help="one golden input, by file stem or scenario (repeatable)")
    p.add_argument("--inputs", type=Path, metavar="DIR",
                   help="golden inputs and manifest.json (default datasets/golden)")
    p.add_argument("--expected", type=Path, metavar="DIR",
                   help="expected outputs (default: INPUTS/expected)")
    p.add_argument("--diff-dir", type=Path, default=Path("golden_diff"), metavar="DIR",
                   help="where check writes images that differ (default ./golden_diff)")
    p.add_argument("--work-dir", type=Path, metavar="DIR",
                   help="keep the jobs' output logs here (default: a temporary folder)")
    p.add_argument("--workers", type=bounded_int(1, 64), default=1, metavar="N",
                   help="threads per job (outputs must not depend on it; default 1)")


def run(args: argparse.Namespace) -> int:
    """Call :func:`golden.check`, :func:`golden.regenerate` or :func:`golden.record_inputs`."""
    from ..golden import run as golden

    if args.action != "check" and args.inputs is None and not golden.in_checkout():
        raise GoldenError(
            f"camlog golden {args.action} rewrites the committed golden files: run it in a "
            "camlog checkout (they live in datasets/golden there), or give --inputs DIR")
    inputs = args.inputs or golden.golden_dir()
    expected = args.expected or inputs / "expected"
    if args.action == "record":
        print("\n".join(golden.record_inputs(inputs, args.only)))
        print(f"wrote {inputs / golden.MANIFEST}; now run camlog golden update")
        return 0
    if args.action == "update":
        print("\n".join(golden.regenerate(inputs, expected, work_dir=args.work_dir,
                                          workers=args.workers, only=args.only)))
        return 0
    differences = golden.check(inputs, expected, diff_dir=args.diff_dir,
                               work_dir=args.work_dir, workers=args.workers, only=args.only)
    for difference in differences:
        print(difference)
        if difference.detail:
            print("\n".join(f"    {line}" for line in difference.detail.splitlines()))
    differing = len({d.artifact for d in differences})
    print(f"{differing} golden artifacts differ from {expected}" if differences
          else f"golden outputs match {expected}")
    return 1 if differences else 0

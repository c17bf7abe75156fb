"""``camlog batch PIPELINE LOG…``: run a pipeline over many logs in parallel."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..batch.pipeline import STEPS
from ..batch.run import ENGINES


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``batch`` arguments."""
    p.epilog = (
        f"PIPELINE is a .toml or .yaml file with [[steps]] tables; step kinds: "
        f"{', '.join(STEPS)}. Each log's outputs go to OUTDIR/<log name>/NN_<step>/; logs "
        "whose outputs are complete for the same input and pipeline are skipped. The exit "
        "status is 1 when any log failed."
    )
    p.add_argument("pipeline", type=Path, metavar="PIPELINE", help="pipeline file")
    p.add_argument("logs", type=Path, nargs="+", metavar="LOG", help="input logs")
    p.add_argument("-j", "--jobs", type=int, default=2, metavar="N",
                   help="logs processed at once (default 2)")
    p.add_argument("-o", "--output", type=Path, default=Path("batch_out"), metavar="OUTDIR",
                   help="output folder (default batch_out)")
    p.add_argument("--engine", choices=ENGINES, default="process",
                   help="local processes (default) or a Ray cluster (pip install 'camlog[ray]'; "
                        "set RAY_ADDRESS to use an existing cluster)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def run(args: argparse.Namespace) -> int:
    """Run the batch and print its summary table."""
    from ..batch.pipeline import load_pipeline
    from ..batch.run import run_batch, summary_table

    pipeline = load_pipeline(args.pipeline)
    result = run_batch(pipeline, list(args.logs), args.output, jobs=args.jobs,
                       engine=args.engine, progress=False if args.no_progress else None)
    print(summary_table(result))
    return 1 if result.failed else 0

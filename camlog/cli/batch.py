"""``camlog batch PIPELINE LOG…``: run a pipeline over many logs in parallel."""

from __future__ import annotations

import argparse
import os
import sys

from ..batch.pipeline import STEPS
from ..batch.run import ENGINES
from .args import add_no_progress


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``batch`` arguments."""
    p.epilog = (
        f"PIPELINE is a .toml or .yaml file with [[steps]] tables; step kinds: "
        f"{', '.join(STEPS)}. LOG and OUTDIR are paths or URIs (file://, s3://, gs://, ...; "
        "a quoted URI pattern such as 's3://bucket/logs/*.mcap' is expanded). Each log's "
        "outputs go to OUTDIR/<log name>/NN_<step>/; logs whose outputs are complete for "
        "the same input and pipeline are skipped. The exit status is 1 when any log failed."
    )
    p.add_argument("pipeline", type=str, metavar="PIPELINE", help="pipeline file")
    p.add_argument("logs", nargs="+", metavar="LOG", help="input logs (paths or URIs)")
    p.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help="logs processed at once (default 2; on an existing Ray cluster, as "
                        "many as its CPUs hold)")
    p.add_argument("-o", "--output", default="batch_out", metavar="OUTDIR",
                   help="output folder or URI (default batch_out)")
    p.add_argument("--engine", choices=ENGINES, default="process",
                   help="local processes (default) or Ray (pip install 'camlog[ray]')")
    p.add_argument("--address", metavar="HOST:PORT",
                   help="an existing Ray cluster, or 'auto' (default: RAY_ADDRESS; without "
                        "either, --engine ray starts a local instance)")
    p.add_argument("--cpus-per-log", type=float, default=1.0, metavar="N",
                   help="CPUs each log's task asks of Ray (default 1)")
    p.add_argument("--retries", type=int, default=2, metavar="N",
                   help="runs again a log whose worker or node died, up to N times "
                        "(default 2)")
    add_no_progress(p)


def run(args: argparse.Namespace) -> int:
    """Run the batch and print its summary table."""
    from pathlib import Path

    from ..batch.pipeline import load_pipeline
    from ..batch.run import Engine, run_batch, summary_table
    from ..errors import UsageError

    pipeline = load_pipeline(Path(args.pipeline))
    if args.address and args.engine != "ray":
        raise UsageError("--address needs --engine ray")
    address = (args.address or os.environ.get("RAY_ADDRESS") or None) \
        if args.engine == "ray" else None
    engine = Engine(args.engine, address=address, cpus_per_log=args.cpus_per_log,
                    retries=args.retries)
    result = run_batch(pipeline, list(args.logs), args.output, jobs=args.jobs, engine=engine,
                       progress=False if args.no_progress else None)
    for note in result.notes:
        print(f"camlog batch: note: {note}", file=sys.stderr)
    print(summary_table(result))
    return 1 if result.failed else 0

"""``camlog batch PIPELINE LOG…``: run a pipeline over many logs in parallel."""

from __future__ import annotations

import argparse
import sys

from ..requests.arguments import request_from_args
from ..requests.batch import BatchRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``batch`` arguments."""
    add_request(p, BatchRequest)


def run(args: argparse.Namespace) -> int:
    """Run the batch and print its summary table."""
    from ..batch.run import run_batch, summary_table

    result = run_batch(request_from_args(BatchRequest, args))
    for note in result.notes:
        print(f"camlog batch: note: {note}", file=sys.stderr)
    print(summary_table(result))
    return 1 if result.failed else 0

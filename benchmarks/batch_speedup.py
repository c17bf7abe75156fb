"""Batch speed-up: the same pipeline over 6 logs with -j 1 and -j 2, in one run.

Pipeline: resync -> stereo calibration -> edges on the left camera, over six
stereo_unsynced recordings (different seeds). Target: -j 2 at least 1.6x faster than -j 1
on 2 cores.

    python -m benchmarks.batch_speedup [--logs N] [--frames F]
"""

from __future__ import annotations

import argparse
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from camlog.batch.pipeline import Pipeline, parse_pipeline
from camlog.batch.run import run_batch
from recorder.record import record
from recorder.scenario import load_scenario

from .docs import add_write_docs
from .report import emit, write_summary_rows

PIPELINE = {
    "steps": [
        {"run": "resync"},
        {"run": "calibrate", "size": "7x6", "square": 0.01, "left": "/stereo_sync/left",
         "right": "/stereo_sync/right"},
        {"run": "process", "input": "log", "topic": "/unsynced/left/image_raw", "edges": True},
    ]
}


@dataclass(frozen=True)
class BatchInputs:
    """A batch benchmark's command line, its pipeline, and the logs recorded for it in a
    temporary ``folder``."""

    args: argparse.Namespace
    pipeline: Pipeline
    folder: Path
    logs: list[str | Path]


@contextmanager
def batch_inputs(doc: str | None, name: str) -> Iterator[BatchInputs]:
    """Parse ``--logs``/``--frames``, record that many stereo_unsynced logs (seeds 0, 1, ...)
    into a temporary folder, and remove it afterwards."""
    parser = argparse.ArgumentParser(description=(doc or "").splitlines()[0])
    parser.add_argument("--logs", type=int, default=6)
    parser.add_argument("--frames", type=int, default=450, help="frames per camera per log")
    add_write_docs(parser)
    args = parser.parse_args()
    pipeline = parse_pipeline(PIPELINE, name)
    with tempfile.TemporaryDirectory() as tmp_name:
        folder = Path(tmp_name)
        logs: list[str | Path] = []
        for seed in range(args.logs):
            path = folder / f"unsynced_{seed}.mcap"
            record(load_scenario("stereo_unsynced", {"frames": args.frames, "seed": seed}),
                   path, progress=False)
            logs.append(path)
        yield BatchInputs(args, pipeline, folder, logs)


def main() -> None:
    with batch_inputs(__doc__, "batch_speedup") as inputs:
        walls = {}
        for jobs in (1, 2):
            result = run_batch(inputs.pipeline, inputs.logs, inputs.folder / f"out_j{jobs}",
                               jobs=jobs, progress=False)
            assert not result.failed, result.failed
            walls[jobs] = result.wall_s
    args = inputs.args
    emit(f"batch {args.logs} logs, -j 2 vs -j 1", baseline="-j 1", baseline_value=walls[1],
         measured="-j 2", measured_value=walls[2], unit="s", ratio=walls[1] / walls[2],
         target=">= 1.6 (speed-up)")
    print(f"batch of {args.logs} logs ({args.frames} frames per camera): -j 1 {walls[1]:.1f} s, "
          f"-j 2 {walls[2]:.1f} s, speed-up {walls[1] / walls[2]:.2f}x (target >= 1.6)")
    write_summary_rows("batch_speedup", args)


if __name__ == "__main__":
    main()

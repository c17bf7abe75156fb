"""Ray engine against the process engine: the same 6 logs at -j 2, in one run.

Pipeline and logs as batch_speedup (resync -> stereo calibration -> edges, six
stereo_unsynced recordings). The Ray run starts its own local instance, and that start-up
is part of its wall time, as it is of a user's. Reports the overhead ratio (Ray wall /
process wall; target <= 1.25) and each engine's time to its first finished log.

    python -m benchmarks.batch_ray [--logs N] [--frames F]
"""

from __future__ import annotations

from camlog.batch.run import BatchResult, Engine, run_batch

from .batch_speedup import batch_inputs
from .report import emit, write_summary_rows


def main() -> None:
    with batch_inputs(__doc__, "batch_ray") as inputs:
        runs: dict[str, BatchResult] = {}
        for engine in ("process", "ray"):
            runs[engine] = run_batch(inputs.pipeline, inputs.logs, inputs.folder / f"out_{engine}",
                                     jobs=2, engine=Engine(engine), progress=False)
            assert not runs[engine].failed, runs[engine].failed
    args = inputs.args
    process, ray = runs["process"], runs["ray"]
    emit(f"batch {args.logs} logs -j 2, Ray vs processes", baseline="processes",
         baseline_value=process.wall_s, measured="ray", measured_value=ray.wall_s, unit="s",
         ratio=ray.wall_s / process.wall_s, target="<= 1.25 (overhead)")
    print(f"batch of {args.logs} logs ({args.frames} frames per camera) at -j 2: processes "
          f"{process.wall_s:.1f} s (first log after {process.first_result_s:.1f} s), Ray "
          f"{ray.wall_s:.1f} s with its start-up (first log after {ray.first_result_s:.1f} s); "
          f"overhead {ray.wall_s / process.wall_s:.2f}x")
    write_summary_rows("batch_ray", args)


if __name__ == "__main__":
    main()

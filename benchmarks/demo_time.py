"""The quick-start demo: its wall time and CPU time from outside, and its .rrd size.

Baseline (same run): recording the demo's stereo log alone (the one step no speed-up can
skip), also from outside. Targets: the demo within 30 s on 2 cores, its .rrd within 100 MB.
CPU seconds (the demo's and its children's) are printed too: on a busy machine the wall
time measures the load as much as the demo.

    python -m benchmarks.demo_time [--duration S]
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .docs import add_write_docs
from .report import emit, write_summary_rows


def timed(argv: list[str]) -> tuple[float, float]:
    """(wall s, CPU s of the child processes) of ``camlog ARGV…`` in a fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "camlog", *argv], check=True, capture_output=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_write_docs(parser)
    parser.add_argument("--duration", type=float, default=8.0,
                        help="the demo's stereo recording in seconds (its default: 8)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        record_wall, record_cpu = timed(
            ["record", "stereo_unsynced", "--duration", str(args.duration), "-o",
             str(tmp / "alone.mcap"), "--no-progress"])
        demo_wall, demo_cpu = timed(["demo", "-o", str(tmp / "demo"), "--duration",
                                     str(args.duration), "--no-progress"])
        rrd_mb = (tmp / "demo" / "demo.rrd").stat().st_size / 1e6
        inputs_mb = sum((tmp / "demo" / name).stat().st_size for name in (
            "calibration/calibration.mcap", "red_block_processed.mcap")) / 1e6
    emit("demo wall time", baseline="stereo record alone", baseline_value=record_wall,
         measured="camlog demo", measured_value=demo_wall, unit="s",
         ratio=demo_wall / record_wall, target="demo <= 30 s")
    emit("demo .rrd size", baseline="logs it shows", baseline_value=inputs_mb,
         measured="demo.rrd", measured_value=rrd_mb, unit="MB", ratio=rrd_mb / inputs_mb,
         target=".rrd <= 100 MB")
    print(f"demo: {demo_wall:.1f} s wall, {demo_cpu:.1f} CPU s (stereo record alone "
          f"{record_wall:.1f} s wall, {record_cpu:.1f} CPU s); demo.rrd {rrd_mb:.1f} MB")
    write_summary_rows("demo_time", args)


if __name__ == "__main__":
    main()

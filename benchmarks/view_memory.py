"""Peak memory of ``camlog view`` against the length of the log, and of ``camlog demo``.

A 30 s ``stereo_checkerboard`` recording (640x480 rgb8) is repeated back to back
(:mod:`benchmarks.longlog`) into a 1-minute and a 10-minute log; ``camlog view`` of each
runs as its own process, its peak resident memory read from the operating system (``wait4``),
median of ``runs``, the two lengths alternated. Targets: the 10-minute log's peak within 1.2x
the 1-minute log's (memory flat in log length), and ``camlog demo`` (its two recordings
combined into one ``.rrd``) within 500 MB in its largest process.

    python -m benchmarks.view_memory [--runs N] [--keep DIR]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

from .processes import Run, clear, run_once, tool
from .report import emit

#: log lengths compared, in repetitions of the 30 s recording
LENGTHS = {"1 min": 2, "10 min": 20}
DEMO_TARGET_MB = 500.0
FLAT_TARGET = 1.2


def view_peaks(tmp: Path, runs: int) -> dict[str, Run]:
    """Median view run per log length (peak MB, wall and CPU s)."""
    camlog = tool("camlog")
    short = tmp / "memory_30s.mcap"
    if not short.is_file():
        run_once([*camlog, "record", "stereo_checkerboard", "--duration", "30", "-o",
                  str(short), "--no-progress", "--overwrite"])
    logs = {}
    for name, times in LENGTHS.items():
        logs[name] = tmp / f"memory_{times}x30s.mcap"
        if not logs[name].is_file():
            run_once([sys.executable, "-m", "benchmarks.longlog", str(short), str(logs[name]),
                      "--times", str(times)])
    out = tmp / "memory.rrd"
    found: dict[str, list[Run]] = {name: [] for name in logs}
    for _ in range(runs):
        for name, log in logs.items():
            clear([out])
            found[name].append(run_once([*camlog, "view", str(log), "-o", str(out),
                                         "--no-progress"]))
    clear([out])
    return {name: Run(statistics.median(r.wall_s for r in got),
                      statistics.median(r.cpu_s for r in got),
                      statistics.median(r.peak_mb for r in got), 0)
            for name, got in found.items()}


def demo_peak(tmp: Path) -> Run:
    """One ``camlog demo`` run: its largest process's peak."""
    out = tmp / "memory_demo"
    run = run_once([*tool("camlog"), "demo", "-o", str(out), "--no-progress"])
    clear([out])
    return run


def measure_memory(tmp: Path, runs: int = 3) -> None:
    """Print and report view's peak per log length and the demo's."""
    peaks = view_peaks(tmp, runs)
    demo = demo_peak(tmp)
    print(f"peak memory (median of {runs}; wall s, CPU s):")
    for name, run in peaks.items():
        print(f"  camlog view, {name} stereo log: {run.peak_mb:.0f} MB "
              f"({run.wall_s:.1f} s, {run.cpu_s:.1f} s)")
    print(f"  camlog demo, largest process: {demo.peak_mb:.0f} MB "
          f"({demo.wall_s:.1f} s, {demo.cpu_s:.1f} s)")
    first, last = (peaks[name] for name in LENGTHS)
    emit("view_memory: view peak, 10-minute log", baseline="1-minute log",
         baseline_value=first.peak_mb, measured="10-minute log",
         measured_value=last.peak_mb, unit="MB", ratio=last.peak_mb / first.peak_mb,
         target=f"<= {FLAT_TARGET}x")
    emit("view_memory: camlog demo, largest process", baseline="target",
         baseline_value=DEMO_TARGET_MB, measured="camlog demo", measured_value=demo.peak_mb,
         unit="MB", ratio=demo.peak_mb / DEMO_TARGET_MB, target=f"<= {DEMO_TARGET_MB:.0f} MB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per log length (3)")
    parser.add_argument("--keep", type=Path, help="work in this folder and keep the logs")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="camlog-memory-") as tmp_name:
        tmp = args.keep or Path(tmp_name)
        tmp.mkdir(parents=True, exist_ok=True)
        measure_memory(tmp, args.runs)


if __name__ == "__main__":
    main()

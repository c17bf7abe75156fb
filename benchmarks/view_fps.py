"""``camlog view`` throughput against a bare rr.Image export of the same images, in one run.

On a recorded stereo_checkerboard log (60 s at 30 Hz, two 640x480 cameras, unless
--duration says otherwise) the benchmark measures, in images per second:

* ``baseline``: read and decode every image and log it with ``rr.Image`` into an .rrd,
  nothing else (one entity per topic, one timeline);
* ``view``: ``camlog view`` with every annotation on (Pinholes, rig transforms, ground
  truth projected, both timelines, the blueprint);
* ``view --jpeg-quality 90``: the same, images stored as JPEG.

Target: view >= 0.7 x baseline. Peak resident memory (VmHWM of a fresh ``camlog view``
process) on a short and the full log shows whether memory grows with the log's length.

    python -m benchmarks.view_fps [--duration S] [--repeats R] [--log LOG]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import rerun as rr

from replay import open_reader
from rerun_export import LoggerOptions, view_logs
from rerun_export.images import COLOR_MODELS

from .docs import add_write_docs
from .report import cli_peak_rss_mb, emit, write_summary_rows


def record_log(path: Path, duration_s: float) -> None:
    from recorder.record import record
    from recorder.scenario import load_scenario

    scenario = load_scenario("stereo_checkerboard", {"duration_s": duration_s})
    record(scenario, path, overwrite=True, progress=False)


def baseline_s(log: Path, out: Path) -> tuple[float, int]:
    """Wall time and image count of the hand-written export: images only."""
    started = time.perf_counter()
    rec = rr.RecordingStream("camlog_baseline")
    rec.set_log_time_enabled(False)  # the log's time goes on "log_time", as in camlog view
    rec.set_log_tick_enabled(False)
    rec.save(out)
    images = 0
    with open_reader(log) as reader:
        for record in reader.frames():
            rec.set_time("log_time", timestamp=np.datetime64(record.log_time_ns, "ns"))
            frame = record.message
            rec.log(record.topic, rr.Image(frame.pixels, color_model=COLOR_MODELS[frame.color]))
            images += 1
    rec.flush()
    rec.disconnect()
    return time.perf_counter() - started, images


def view_s(log: Path, out: Path, jpeg_quality: int | None) -> tuple[float, int]:
    """Wall time and images logged by ``view_logs``."""
    started = time.perf_counter()
    result = view_logs([log], output=out, overwrite=True, progress=False,
                       options=LoggerOptions(jpeg_quality=jpeg_quality))
    images = sum(n for entity, n in result.counts.items() if entity.endswith("/image"))
    return time.perf_counter() - started, images


def peak_rss_mb(log: Path, out: Path) -> float:
    """Peak resident memory (MB) of ``camlog view`` in a fresh process."""
    return cli_peak_rss_mb(["view", str(log), "-o", str(out), "--overwrite", "--no-progress"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_write_docs(parser)
    parser.add_argument("--duration", type=float, default=60.0, help="log length in s (60)")
    parser.add_argument("--repeats", type=int, default=2, help="best of R interleaved runs")
    parser.add_argument("--log", type=Path, help="use this stereo log instead of recording")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        log = args.log or tmp / "stereo.mcap"
        short = tmp / "short.mcap"
        started = time.perf_counter()
        if args.log is None:
            record_log(log, args.duration)
        record_log(short, max(args.duration / 6, 1.0))
        print(f"recorded the logs in {time.perf_counter() - started:.0f} s")
        times: dict[str, list[float]] = {"baseline": [], "view": [], "jpeg": []}
        counts: dict[str, int] = {}
        sizes: dict[str, float] = {}
        for _ in range(args.repeats):  # interleaved so that drifting load hits all three
            runs: tuple[tuple[str, Callable[[Path], tuple[float, int]]], ...] = (
                ("baseline", lambda o: baseline_s(log, o)),
                ("view", lambda o: view_s(log, o, None)),
                ("jpeg", lambda o: view_s(log, o, 90)))
            for name, run in runs:
                out = tmp / f"{name}.rrd"
                out.unlink(missing_ok=True)
                seconds, counts[name] = run(out)
                times[name].append(seconds)
                sizes[name] = out.stat().st_size / 1e6
        fps = {name: counts[name] / min(t) for name, t in times.items()}
        peak_short = peak_rss_mb(short, tmp / "short.rrd")
        peak_long = peak_rss_mb(log, tmp / "long.rrd")
        with open_reader(log) as reader:
            span_s = ((reader.end_ns or 0) - (reader.start_ns or 0)) / 1e9
    print(f"log: stereo_checkerboard {span_s:.0f} s, {counts['baseline']} images 640x480 rgb8, "
          f"best of {args.repeats}")
    print(f"baseline rr.Image only:  {fps['baseline']:7.0f} images/s  "
          f"({sizes['baseline']:.0f} MB .rrd)")
    for name, label in (("view", "camlog view:           "), ("jpeg", "view --jpeg-quality 90:")):
        print(f"{label}  {fps[name]:7.0f} images/s  ({sizes[name]:.0f} MB .rrd) = "
              f"{fps[name] / fps['baseline']:.2f} x baseline (target >= 0.7)")
    print(f"peak RSS of camlog view: {peak_short:.0f} MB on a {span_s / 6:.0f} s log, "
          f"{peak_long:.0f} MB on the {span_s:.0f} s log")
    for name, label in (("view", "view, all annotations"), ("jpeg", "view --jpeg-quality 90")):
        emit(f"{label} ({span_s:.0f} s stereo)", baseline="rr.Image only",
             baseline_value=fps["baseline"], measured="view", measured_value=fps[name],
             unit="images/s", ratio=fps[name] / fps["baseline"], target=">= 0.7")
    emit("view peak RSS, long vs short log", baseline=f"{span_s / 6:.0f} s log",
         baseline_value=peak_short, measured=f"{span_s:.0f} s log", measured_value=peak_long,
         unit="MB", ratio=peak_long / peak_short, target="flat (~1.0)")
    write_summary_rows("view_fps", args)


if __name__ == "__main__":
    main()

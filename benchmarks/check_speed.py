"""Drift-check throughput: seconds of a 30 Hz stereo log checked per second of wall time.

On one recorded ``stereo_checkerboard`` log (640x480 by default, the right camera pitched
0.1° half-way) the benchmark times ``check_drift`` with its defaults (2 s windows, 5 pairs
looked at per second) and reports the log's duration over the wall time: a multiple of real
time. As a reference it also times reading and decoding every frame of both cameras.

Target: >= 5 x real time on 2 cores.

    python -m benchmarks.check_speed [--duration S] [--resolution WxH] [--repeats R]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from camlog.check.flow import CheckOptions, check_drift
from replay import open_reader
from replay.frames import FrameStream

from .docs import add_write_docs
from .report import emit, write_summary_rows


def record_log(path: Path, duration_s: float, resolution: tuple[int, int]) -> None:
    """The benchmark's log: stereo_checkerboard, the right camera pitched 0.1° half-way."""
    from recorder.record import record
    from recorder.scenario import load_scenario

    width, height = resolution
    scenario = load_scenario("stereo_checkerboard", {
        "duration_s": duration_s, "width": width, "height": height,
        "drifts": [{"camera": "right", "axis": "pitch", "degrees": 0.1,
                    "start_s": duration_s / 2}]})
    record(scenario, path, overwrite=True, progress=False)


def decode_s(log: Path) -> float:
    """Wall time to read and decode every image of the log."""
    started = time.perf_counter()
    with open_reader(log) as reader:
        topics = [t for t in reader.topics if t.endswith("/image_raw")]
        stream = FrameStream()
        for raw in reader.raw_messages(topics):
            stream.decode(reader.decode(raw))
    return time.perf_counter() - started


def check_s(log: Path) -> tuple[float, str]:
    """Wall time of the check and its verdict."""
    started = time.perf_counter()
    checked = check_drift(log, CheckOptions())
    return time.perf_counter() - started, checked.summary()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_write_docs(parser)
    parser.add_argument("--duration", type=float, default=20.0, help="log length in s (20)")
    parser.add_argument("--resolution", default="640x480", help="WxH (640x480)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    width, height = (int(v) for v in args.resolution.split("x"))
    with tempfile.TemporaryDirectory() as tmp_dir:
        log = Path(tmp_dir) / "stereo.mcap"
        record_log(log, args.duration, (width, height))
        decode, check = [], []
        verdict = ""
        for _ in range(args.repeats):
            decode.append(decode_s(log))
            seconds, verdict = check_s(log)
            check.append(seconds)
    decode_x, check_x = args.duration / min(decode), args.duration / min(check)
    print(f"log: stereo_checkerboard {args.duration:g} s at 30 Hz, {width}x{height}, "
          f"best of {args.repeats}")
    print(f"read + decode every frame: {decode_x:6.1f} x real time")
    print(f"check:                     {check_x:6.1f} x real time (target >= 5)")
    print(f"verdict: {verdict.split(': ', 1)[1]}")
    emit("check: stereo drift", baseline="real time", baseline_value=1.0,
         measured="check", measured_value=check_x, unit="x real time", ratio=check_x,
         target=">= 5")
    emit("check: read + decode (reference)", baseline="read + decode",
         baseline_value=decode_x, measured="check", measured_value=check_x,
         unit="x real time", ratio=check_x / decode_x, target="(reference)")
    write_summary_rows("check_speed", args)


if __name__ == "__main__":
    main()

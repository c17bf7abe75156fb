"""What the pinhole views of distorted cameras cost ``camlog view``, in one run.

Two recorded stereo logs (30 s at 30 Hz, two 640x480 cameras, unless --duration says
otherwise): ``stereo_heldout`` (plumb_bob lenses: each raw image is remapped to an
undistorted view on the worker threads) and ``stereo_checkerboard`` (ideal cameras: no
views). Each is viewed, into an .rrd, in interleaved repeats:

* ``views``: ``camlog view`` as it is;
* ``no views``: ``camlog view --no-undistort``, the raw images under a Pinhole of their K
  (what view drew before the views; the baseline).

Targets: the distorted log's view at most 1.3 x its baseline's wall time; the ideal log's
within noise of its baseline (no view is made for an ideal camera: both runs do the same
work). Medians of the repeats.

    python -m benchmarks.view_undistort [--duration S] [--repeats R] [--distorted LOG]
                                        [--ideal LOG] [--scale S]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from rerun_export import LoggerOptions, view_logs

from .report import emit

#: scenario -> what its cameras are
LOGS = {"distorted": "stereo_heldout", "ideal": "stereo_checkerboard"}


def record_log(scenario: str, path: Path, duration_s: float) -> None:
    from recorder.record import record
    from recorder.scenario import load_scenario

    record(load_scenario(scenario, {"duration_s": duration_s}), path, overwrite=True,
           progress=False)


def view_s(log: Path, out: Path, scale: float | None) -> tuple[float, int, int]:
    """Wall time, raw images and view images of one ``view_logs`` run."""
    started = time.perf_counter()
    result = view_logs([log], output=out, overwrite=True, progress=False,
                       options=LoggerOptions(undistorted_scale=scale))
    return time.perf_counter() - started, result.images, result.remapped


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=30.0, help="log length in s (30)")
    parser.add_argument("--repeats", type=int, default=3, help="median of R interleaved runs")
    parser.add_argument("--distorted", type=Path, help="a stereo_heldout log to use")
    parser.add_argument("--ideal", type=Path, help="a stereo_checkerboard log to use")
    parser.add_argument("--scale", type=float, default=1.0,
                        help="the views' size relative to the raw images (1)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        logs = {"distorted": args.distorted, "ideal": args.ideal}
        for kind, scenario in LOGS.items():
            if logs[kind] is None:
                logs[kind] = tmp / f"{scenario}.mcap"
                started = time.perf_counter()
                record_log(scenario, logs[kind], args.duration)
                print(f"recorded {scenario} in {time.perf_counter() - started:.0f} s")
        times: dict[tuple[str, str], list[float]] = {}
        counts: dict[tuple[str, str], tuple[int, int]] = {}
        sizes: dict[tuple[str, str], float] = {}
        for _ in range(args.repeats):  # interleaved, so that drifting load hits every run
            for kind, log in logs.items():
                assert log is not None
                for mode, scale in (("views", args.scale), ("no views", None)):
                    out = tmp / "out.rrd"
                    seconds, images, remapped = view_s(log, out, scale)
                    times.setdefault((kind, mode), []).append(seconds)
                    counts[kind, mode] = (images, remapped)
                    sizes[kind, mode] = out.stat().st_size / 1e6
    wall = {key: statistics.median(values) for key, values in times.items()}
    print(f"median of {args.repeats} runs each")
    for kind, scenario in LOGS.items():
        views, plain = wall[kind, "views"], wall[kind, "no views"]
        images, remapped = counts[kind, "views"]
        print(f"{scenario} ({kind}): {images} images, {remapped} view images; view "
              f"{views:.2f} s ({sizes[kind, 'views']:.0f} MB .rrd), --no-undistort "
              f"{plain:.2f} s ({sizes[kind, 'no views']:.0f} MB): {views / plain:.2f} x "
              f"(runs: {', '.join(f'{t:.2f}' for t in times[kind, 'views'])} / "
              f"{', '.join(f'{t:.2f}' for t in times[kind, 'no views'])})")
    for kind, target in (("distorted", "<= 1.3"), ("ideal", "~1.0 (noise)")):
        views, plain = wall[kind, "views"], wall[kind, "no views"]
        emit(f"view of a {args.duration:.0f} s stereo log, {kind} lenses ({LOGS[kind]})",
             baseline="view --no-undistort", baseline_value=plain,
             measured="view (pinhole views)", measured_value=views, unit="s",
             ratio=views / plain, target=target)


if __name__ == "__main__":
    main()

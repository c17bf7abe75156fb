"""What the pinhole views of distorted cameras cost ``camlog view``, in one run.

Three recorded stereo logs (30 s at 30 Hz, two 640x480 cameras, unless --duration says
otherwise): ``stereo_heldout`` (plumb_bob lenses: each raw image is remapped to an
undistorted view on the worker threads) as the simulator records it (a held pose repeats
its frames byte for byte: they need no view image of their own), the same with sensor noise
(sigma 2 levels: no two frames alike, as a real camera's), and ``stereo_checkerboard``
(ideal cameras: no views). Each is viewed into an .rrd, in interleaved repeats:

* ``views``: ``camlog view`` as it is (its views --scale times the raw images' width and
  height, by default view's own);
* ``no views``: ``camlog view --no-undistort``, the raw images under a Pinhole of their K
  (what view drew before the views; the baseline).

Each log's two runs take turns at going first (the first read of a log after another's may
find less of it in the page cache). Wall time and the process's CPU time (every thread's)
are medians of the repeats; on a
machine whose other jobs leave no core idle, the CPU ratio is what the wall ratio comes to.
Targets: a distorted log's view at most 1.3 x its baseline's wall time; the ideal log's
within noise of its baseline (no view is made for an ideal camera: both runs do the same
work).

    python -m benchmarks.view_undistort [--duration S] [--repeats R] [--scale S]
        [--distorted LOG] [--noisy LOG] [--ideal LOG] [--write-docs]
"""

from __future__ import annotations

import argparse
import resource
import statistics
import tempfile
import time
from pathlib import Path

from rerun_export import LoggerOptions, view_logs
from rerun_export.options import UNDISTORTED_SCALE

from .docs import add_write_docs
from .report import emit, write_summary_rows

#: log -> (scenario, sensor noise in 8-bit levels, what it shows)
LOGS = {
    "distorted": ("stereo_heldout", 0.0, "distorted lenses, held poses repeat their frames"),
    "noisy": ("stereo_heldout", 2.0, "distorted lenses, sensor noise σ = 2 (no frame repeats)"),
    "ideal": ("stereo_checkerboard", 0.0, "ideal lenses"),
}


def record_log(scenario: str, noise: float, path: Path, duration_s: float) -> None:
    from recorder.record import record
    from recorder.scenario import load_scenario

    overrides: dict[str, object] = {"duration_s": duration_s}
    if noise:
        overrides["noise_std"] = noise
    record(load_scenario(scenario, overrides), path, overwrite=True, progress=False)


def _cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def view_s(log: Path, out: Path, scale: float | None) -> tuple[float, float, int, int]:
    """Wall time, CPU time, raw images and view images of one ``view_logs`` run."""
    started, cpu = time.perf_counter(), _cpu_s()
    result = view_logs([log], output=out, overwrite=True, progress=False,
                       options=LoggerOptions(undistorted_scale=scale))
    return time.perf_counter() - started, _cpu_s() - cpu, result.images, result.remapped


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=30.0, help="log length in s (30)")
    parser.add_argument("--repeats", type=int, default=3, help="median of R interleaved runs")
    parser.add_argument("--scale", type=float, default=UNDISTORTED_SCALE,
                        help=f"the views' size relative to the raw images ({UNDISTORTED_SCALE:g}, "
                             "view's default)")
    for kind, (scenario, _, what) in LOGS.items():
        parser.add_argument(f"--{kind}", type=Path, metavar="LOG",
                            help=f"a {scenario} log to use ({what})")
    add_write_docs(parser)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        logs: dict[str, Path] = {}
        for kind, (scenario, noise, _) in LOGS.items():
            given = getattr(args, kind)
            logs[kind] = given or tmp / f"{kind}.mcap"
            if given is None:
                started = time.perf_counter()
                record_log(scenario, noise, logs[kind], args.duration)
                print(f"recorded {kind} ({scenario}) in {time.perf_counter() - started:.0f} s")
        runs: dict[tuple[str, str], list[tuple[float, float]]] = {}
        counts: dict[str, tuple[int, int]] = {}
        modes: tuple[tuple[str, float | None], ...] = (("views", args.scale),
                                                       ("no views", None))
        for repeat in range(args.repeats):  # interleaved, so that drifting load hits all
            for kind, log in logs.items():
                for mode, scale in modes if repeat % 2 == 0 else modes[::-1]:
                    wall, cpu, images, remapped = view_s(log, tmp / "out.rrd", scale)
                    runs.setdefault((kind, mode), []).append((wall, cpu))
                    if mode == "views":
                        counts[kind] = (images, remapped)
    median = {key: (statistics.median(w for w, _ in values),
                    statistics.median(c for _, c in values)) for key, values in runs.items()}
    print(f"median of {args.repeats} runs each; views {args.scale:g} x the raw images")
    for kind, (scenario, _, what) in LOGS.items():
        (wall, cpu), (base_wall, base_cpu) = median[kind, "views"], median[kind, "no views"]
        images, remapped = counts[kind]
        print(f"{scenario}, {what}: {images} images, {remapped} view images; view {wall:.2f} s "
              f"wall / {cpu:.2f} s CPU, --no-undistort {base_wall:.2f} / {base_cpu:.2f} s: "
              f"{wall / base_wall:.2f} x wall, {cpu / base_cpu:.2f} x CPU (runs, wall: "
              f"{', '.join(f'{w:.2f}' for w, _ in runs[kind, 'views'])} / "
              f"{', '.join(f'{w:.2f}' for w, _ in runs[kind, 'no views'])})")
        emit(f"view, {args.duration:g} s stereo, {what} ({remapped} view images, CPU "
             f"{cpu / base_cpu:.2f} x)", baseline="view --no-undistort",
             baseline_value=base_wall, measured="view", measured_value=wall, unit="s",
             ratio=wall / base_wall, target="~1.0 (noise)" if kind == "ideal" else "<= 1.3")
    write_summary_rows("view_undistort", args)


if __name__ == "__main__":
    main()

"""camlog against the tools a user would run instead: the same inputs, whole processes, one run.

Every command is its own process, timed from outside (wall clock from its start to its exit,
start-up included) with its CPU time and peak resident memory from the operating system
(``wait4``). camlog and its peer run in turn (camlog, peer, camlog, peer, ...) so that
drifting load hits both; figures are medians, ratios the median of the pairs' ratios.

* start-up: ``camlog --help``, ``camlog info`` on the stereo log and an argument error,
  beside a bare ``python -c pass`` (targets: <= 0.15 s and <= 50 MB);
* convert: ROS1 bag -> rosbag2 and rosbag2 (MCAP storage) -> ROS1 against
  ``rosbags-convert`` writing the same storage with the same compression as camlog's default
  (zstd MCAP chunks, lz4 ROS1 chunks; targets: <= 1.0x the time, <= 1.5x the memory);
* view: ``camlog view -o OUT.rrd`` against ``rerun mcap convert`` on the stereo log (target
  <= 2.0x, start-up included) and on a ``--view-duration`` log (30 s, 1800 images; target
  <= 1.3x, throughput);
* calibrate: the real 12-pair wide-angle stereo sample (``shared/realdata/ros_wide_stereo``,
  imported with ``camlog import --stereo``) against ``benchmarks/opencv_stereo.py``, a plain
  OpenCV script (target <= 1.5x with the full report; also ``--no-report``).

The stereo log is ``stereo_checkerboard`` recorded for ``--duration`` s (4) at 640x480.
``--growth 4,40,400`` also runs convert, view and calibrate on stereo logs of those lengths
(320x240 mono8 to keep the uncompressed outputs small on disk; the recording repeated back to
back, see :mod:`benchmarks.longlog`) to show time linear and memory flat in log length.

camlog's own modules are compiled to bytecode first, as installing its wheel does (an editable
checkout compiles them on first use, or never where ``PYTHONDONTWRITEBYTECODE`` is set, which
would add that compilation to every start-up measured).

``--memory`` adds the peak memory of ``view`` on 1- and 10-minute logs and of ``camlog demo``
(:mod:`benchmarks.view_memory`).

    python -m benchmarks.peers [--duration S] [--view-duration S] [--runs N] [--memory]
                               [--growth 4,40,400] [--keep DIR]
"""

from __future__ import annotations

import argparse
import compileall
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from .docs import add_write_docs, markdown_table, write_table
from .processes import Run, clear, run_once, tool
from .report import emit

REPO = Path(__file__).resolve().parent.parent
BOARD_WIDE = ["--size", "8x6", "--square", "0.108"]
BOARD_SIM = ["--size", "7x6", "--square", "0.01"]
STEREO_SIM = ["--left", "/stereo_camera/left", "--right", "/stereo_camera/right"]
#: rosbags-convert told to compress as camlog convert does by default (rosbag2: zstd MCAP
#: chunks; ROS1: lz4 chunks), so that both tools do the same work
PEER_TO_ROSBAG2 = ["--dst-storage", "mcap", "--compress", "zstd", "--compress-mode", "storage"]
PEER_TO_ROS1 = ["--compress", "lz4"]


def realdata_dir() -> Path:
    """Third-party data: ``$CAMLOG_REALDATA`` or ``../shared/realdata`` beside the repo."""
    override = os.environ.get("CAMLOG_REALDATA")
    return Path(override) if override else REPO.parent / "shared" / "realdata"


@dataclass(frozen=True)
class Case:
    """One piece of work done by camlog and by its peer (None: camlog alone)."""

    name: str
    camlog: list[str]
    peer_name: str
    peer: list[str] | None
    outputs: list[Path]
    target: str
    expect: int = 0


@dataclass(frozen=True)
class Result:
    """Medians of a case's runs and the median of the pairs' ratios."""

    case: Case
    camlog: Run
    peer: Run | None
    time_ratio: float | None
    memory_ratio: float | None


def median_run(runs: list[Run]) -> Run:
    return Run(statistics.median(r.wall_s for r in runs), statistics.median(r.cpu_s for r in runs),
               statistics.median(r.peak_mb for r in runs), runs[0].status)


def measure(case: Case, runs: int) -> Result:
    """Run camlog and its peer in turn ``runs`` times (after one warm-up each)."""
    mine: list[Run] = []
    theirs: list[Run] = []
    for index in range(runs + 1):
        clear(case.outputs)
        camlog = run_once(case.camlog, expect=case.expect)
        peer = None
        if case.peer is not None:
            clear(case.outputs)
            peer = run_once(case.peer)
        if index:  # the first round warms the page cache and Python's bytecode cache
            mine.append(camlog)
            if peer is not None:
                theirs.append(peer)
    clear(case.outputs)
    if not theirs:
        return Result(case, median_run(mine), None, None, None)
    time_ratio = statistics.median(a.wall_s / b.wall_s for a, b in zip(mine, theirs, strict=True))
    memory_ratio = statistics.median(a.peak_mb / b.peak_mb
                                     for a, b in zip(mine, theirs, strict=True))
    return Result(case, median_run(mine), median_run(theirs), time_ratio, memory_ratio)


def make_inputs(tmp: Path, duration_s: float, view_s: float = 0) -> dict[str, Path]:
    """The stereo log as MCAP, ROS1 bag and rosbag2, a ``view_s`` stereo log for view's
    throughput (none for 0), and the real stereo sample as MCAP."""
    camlog = tool("camlog")
    paths = {"mcap": tmp / "stereo.mcap", "ros1": tmp / "stereo.bag", "rosbag2": tmp / "stereo_r2"}
    run_once([*camlog, "record", "stereo_checkerboard", "--duration", str(duration_s),
              "-o", str(paths["mcap"]), "--no-progress", "--overwrite"])
    if view_s > 0:
        paths["long"] = tmp / "stereo_long.mcap"
        run_once([*camlog, "record", "stereo_checkerboard", "--duration", str(view_s),
                  "-o", str(paths["long"]), "--no-progress", "--overwrite"])
    for fmt in ("ros1", "rosbag2"):
        run_once([*camlog, "convert", str(paths["mcap"]), str(paths[fmt]), "--no-progress",
                  "--overwrite"])
    wide = realdata_dir() / "ros_wide_stereo"
    if (wide / "left0003.pgm").is_file():
        paths["wide"] = tmp / "wide.mcap"
        paths["wide_folder"] = wide
        run_once([*camlog, "import", str(wide), "--stereo", "-o", str(paths["wide"]),
                  "--no-progress", "--overwrite"])
    else:
        print(f"real stereo sample not found at {wide} (set CAMLOG_REALDATA): no calibrate row")
    return paths


def cases(inputs: dict[str, Path], tmp: Path) -> list[Case]:
    """The side-by-side comparisons on one set of inputs."""
    camlog, rosbags, rerun = tool("camlog"), tool("rosbags-convert"), tool("rerun")
    python = [sys.executable, "-c", "pass"]
    out_r2, out_bag, out_rrd, out_cal = (tmp / "out_r2", tmp / "out.bag", tmp / "out.rrd",
                                         tmp / "out_cal")
    startup = "<= 0.15 s, <= 50 MB"
    found = [
        Case("camlog --help (start-up)", [*camlog, "--help"], "python -c pass", python, [],
             startup),
        Case("camlog info (stereo log)", [*camlog, "info", str(inputs["mcap"])],
             "python -c pass", python, [], startup),
        Case("argument error (convert, no OUT)", [*camlog, "convert", str(inputs["mcap"])],
             "python -c pass", python, [], startup, expect=2),
        Case("convert ROS1 bag -> rosbag2",
             [*camlog, "convert", str(inputs["ros1"]), str(out_r2), "--no-progress"],
             "rosbags-convert",
             [*rosbags, "--src", str(inputs["ros1"]), "--dst", str(out_r2),
              *PEER_TO_ROSBAG2], [out_r2], "<= 1.0x time, <= 1.5x memory"),
        Case("convert rosbag2 (MCAP) -> ROS1 bag",
             [*camlog, "convert", str(inputs["rosbag2"]), str(out_bag), "--no-progress"],
             "rosbags-convert", [*rosbags, "--src", str(inputs["rosbag2"]), "--dst", str(out_bag),
                                 *PEER_TO_ROS1], [out_bag], "<= 1.0x time, <= 1.5x memory"),
        Case("view: MCAP -> .rrd",
             [*camlog, "view", str(inputs["mcap"]), "-o", str(out_rrd), "--no-progress"],
             "rerun mcap convert", [*rerun, "mcap", "convert", str(inputs["mcap"]), "-o",
                                    str(out_rrd)], [out_rrd], "<= 2.0x"),
    ]
    if "long" in inputs:
        found.append(Case(
            "view: a longer stereo log (throughput)",
            [*camlog, "view", str(inputs["long"]), "-o", str(out_rrd), "--no-progress"],
            "rerun mcap convert", [*rerun, "mcap", "convert", str(inputs["long"]), "-o",
                                   str(out_rrd)], [out_rrd], "<= 1.3x"))
    if "wide" in inputs:
        opencv = [sys.executable, str(REPO / "benchmarks" / "opencv_stereo.py"),
                  str(inputs["wide_folder"]), "8x6", "0.108"]
        calibrate = [*camlog, "calibrate", str(inputs["wide"]), "--left", "/stereo/left",
                     "--right", "/stereo/right", *BOARD_WIDE, "-o", str(out_cal), "--no-progress"]
        found += [
            Case("calibrate: real 12-pair stereo sample, full report", calibrate,
                 "OpenCV script", opencv, [out_cal], "<= 1.5x"),
            Case("calibrate: the same, --no-report", [*calibrate, "--no-report"],
                 "OpenCV script", opencv, [out_cal], "(scripts)"),
        ]
    return found


def growth_cases(tmp: Path, seconds: Sequence[int]) -> Iterator[tuple[int, list[Case]]]:
    """Convert, view and calibrate on stereo logs of the given lengths (4 s repeated); each
    length's inputs are made when it is its turn."""
    camlog, rosbags, rerun = tool("camlog"), tool("rosbags-convert"), tool("rerun")
    short = tmp / "growth_4s.mcap"
    run_once([*camlog, "record", "stereo_checkerboard", "--duration", "4", "--resolution",
              "320x240", "--encoding", "mono8", "-o", str(short), "--no-progress", "--overwrite"])
    for length_s in seconds:
        log = tmp / f"growth_{length_s}s.mcap"
        if length_s != 4:
            run_once([sys.executable, "-m", "benchmarks.longlog", str(short), str(log),
                      "--times", str(max(1, round(length_s / 4)))])
        bag, r2 = log.with_suffix(".bag"), log.with_suffix("")
        for path in (bag, r2):
            run_once([*camlog, "convert", str(log), str(path), "--no-progress", "--overwrite"])
        out_r2, out_bag, out_rrd, out_cal = (tmp / "g_r2", tmp / "g.bag", tmp / "g.rrd",
                                             tmp / "g_cal")
        yield length_s, [
            Case("convert ROS1 -> rosbag2", [*camlog, "convert", str(bag), str(out_r2),
                                             "--no-progress"], "rosbags-convert",
                 [*rosbags, "--src", str(bag), "--dst", str(out_r2), *PEER_TO_ROSBAG2],
                 [out_r2], ""),
            Case("convert rosbag2 -> ROS1", [*camlog, "convert", str(r2), str(out_bag),
                                             "--no-progress"], "rosbags-convert",
                 [*rosbags, "--src", str(r2), "--dst", str(out_bag), *PEER_TO_ROS1], [out_bag],
                 ""),
            Case("view", [*camlog, "view", str(log), "-o", str(out_rrd), "--no-progress"],
                 "rerun mcap convert", [*rerun, "mcap", "convert", str(log), "-o", str(out_rrd)],
                 [out_rrd], ""),
            Case("calibrate stereo", [*camlog, "calibrate", str(log), *STEREO_SIM, *BOARD_SIM,
                                      "-o", str(out_cal), "--no-progress"], "", None,
                 [out_cal], ""),
        ]


def print_results(results: list[Result]) -> None:
    print(f"{'same work':52} {'peer':>28} {'camlog':>22} {'time':>6} {'memory':>6}  target")
    for r in results:
        peer = "" if r.peer is None else (f"{r.case.peer_name} {r.peer.wall_s:.2f} s "
                                          f"{r.peer.peak_mb:.0f} MB")
        mine = f"{r.camlog.wall_s:.2f} s {r.camlog.peak_mb:.0f} MB"
        ratios = ("" if r.time_ratio is None else f"{r.time_ratio:6.2f}x",
                  "" if r.memory_ratio is None else f"{r.memory_ratio:6.2f}x")
        print(f"{r.case.name:52} {peer:>28} {mine:>22} {ratios[0]:>6} {ratios[1]:>6}  "
              f"{r.case.target}", flush=True)
    print("(CPU seconds, camlog / peer: " + ", ".join(
        f"{r.camlog.cpu_s:.2f}" + ("" if r.peer is None else f"/{r.peer.cpu_s:.2f}")
        for r in results) + ")")


def markdown_rows(results: list[Result]) -> list[str]:
    """The docs' table of the peers: wall, CPU and peak memory of each side, the ratios."""
    def side(run: Run) -> str:
        return f"{run.wall_s:.2f} s, {run.cpu_s:.2f} s, {run.peak_mb:.0f} MB"
    rows = []
    for r in results:
        peer = "" if r.peer is None else f"{r.case.peer_name}: {side(r.peer)}"
        cpu = "" if r.peer is None else f"{r.camlog.cpu_s / r.peer.cpu_s:.2f}"
        rows.append([r.case.name, peer, side(r.camlog),
                     "" if r.time_ratio is None else f"{r.time_ratio:.2f}", cpu,
                     "" if r.memory_ratio is None else f"{r.memory_ratio:.2f}", r.case.target])
    return markdown_table(["same work", "peer: wall, CPU, peak", "camlog: wall, CPU, peak",
                           "wall ratio", "CPU ratio", "memory ratio", "target"], rows)


def compare_peers(tmp: Path, duration_s: float, runs: int, view_s: float, *,
                  write_docs: bool = False) -> None:
    """camlog and each peer on the same inputs, side by side (and, with ``write_docs``, as
    the docs' table)."""
    started = time.perf_counter()
    inputs = make_inputs(tmp, duration_s, view_s)
    floor = run_once(["true"]).peak_mb
    print(f"inputs made in {time.perf_counter() - started:.0f} s; {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}; peak memory reads no lower than "
          f"{floor:.0f} MB here (this process's size at the child's start)")
    results = [measure(case, runs) for case in cases(inputs, tmp)]
    print(f"median of {runs} runs each, load average now {os.getloadavg()[0]:.1f}")
    print_results(results)
    if write_docs:
        write_table("peers", markdown_rows(results))
    for r in results:
        if r.peer is not None and r.time_ratio is not None:
            emit(f"peers: {r.case.name}", baseline=r.case.peer_name,
                 baseline_value=r.peer.wall_s, measured=f"camlog ({r.camlog.peak_mb:.0f} MB)",
                 measured_value=r.camlog.wall_s, unit="s", ratio=r.time_ratio,
                 target=r.case.target)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=4.0, help="stereo log length in s (4)")
    parser.add_argument("--runs", type=int, default=5,
                        help="measured runs per command (5; 0: only the cost growth)")
    parser.add_argument("--growth", default="", metavar="S,S,...",
                        help="also measure cost growth on logs of these lengths in s")
    parser.add_argument("--growth-runs", type=int, default=3, help="runs per growth command")
    parser.add_argument("--view-duration", type=float, default=30.0, metavar="S",
                        help="length of the log for view's throughput row in s (30; 0: none)")
    parser.add_argument("--memory", action="store_true",
                        help="also measure peak memory: view on 1- and 10-minute logs, demo")
    parser.add_argument("--keep", type=Path, help="work in this folder and keep the inputs")
    add_write_docs(parser)
    args = parser.parse_args()
    for package in ("camlog", "replay", "processors", "recorder", "rerun_export"):
        compileall.compile_dir(REPO / package, quiet=1)
    with tempfile.TemporaryDirectory(prefix="camlog-peers-") as tmp_name:
        tmp = args.keep or Path(tmp_name)
        tmp.mkdir(parents=True, exist_ok=True)
        if args.runs > 0:
            compare_peers(tmp, args.duration, args.runs, args.view_duration,
                          write_docs=args.write_docs)
        if args.memory:
            from .view_memory import measure_memory

            measure_memory(tmp)
        if args.growth:
            print_growth(tmp, [int(s) for s in args.growth.split(",")], args.growth_runs,
                         write_docs=args.write_docs)


def print_growth(tmp: Path, seconds: list[int], runs: int, *, write_docs: bool = False) -> None:
    """Cost growth: each command's time and peak per log length (and, with ``write_docs``,
    the docs' table: wall seconds and peak memory per length, the peer in brackets, and the
    cost of each extra minute of log between the two longest)."""
    rows: dict[str, dict[int, Result]] = {}
    for length_s, found in growth_cases(tmp, seconds):
        for case in found:
            rows.setdefault(case.name, {})[length_s] = measure(case, runs)
        for path in tmp.glob(f"growth_{length_s}s*"):
            if length_s != 4:
                clear([path])
    print(f"cost growth (320x240 mono8 stereo, median of {runs}; wall s, CPU s, peak MB; peer "
          f"in brackets; load average now {os.getloadavg()[0]:.1f})")
    print(f"{'command':26}" + "".join(f"{f'{s} s log':>50}" for s in seconds))
    for name, by_length in rows.items():
        cells = []
        for s in seconds:
            r = by_length[s]
            cell = f"{r.camlog.wall_s:.2f} s {r.camlog.cpu_s:.2f} s {r.camlog.peak_mb:.0f} MB"
            if r.peer is not None:
                cell += f" ({r.peer.wall_s:.2f} s {r.peer.cpu_s:.2f} s {r.peer.peak_mb:.0f} MB)"
            cells.append(f"{cell:>50}")
        print(f"{name:26}" + "".join(cells), flush=True)
    if write_docs:
        write_table("peers_growth", growth_rows(rows, seconds))


def growth_rows(rows: dict[str, dict[int, Result]], seconds: list[int]) -> list[str]:
    """The docs' cost-growth table (see :func:`print_growth`)."""
    def cell(run: Run) -> str:
        return f"{run.wall_s:.2f} s, {run.peak_mb:.0f} MB"
    def per_minute(by_length: dict[int, Result], *, peer: bool) -> float:
        long, longer = sorted(seconds)[-2:]
        first, last = (by_length[s].peer if peer else by_length[s].camlog for s in (long, longer))
        assert first is not None and last is not None
        return (last.wall_s - first.wall_s) / (longer - long) * 60
    table = []
    for name, by_length in rows.items():
        cells = []
        for s in seconds:
            r = by_length[s]
            cells.append(cell(r.camlog) + ("" if r.peer is None else f" ({cell(r.peer)})"))
        minute = f"{per_minute(by_length, peer=False):.2f} s"
        if all(by_length[s].peer is not None for s in seconds):
            minute += f" ({per_minute(by_length, peer=True):.2f} s)"
        table.append([name, *cells, minute])
    return markdown_table(["command", *(f"{s} s log" for s in seconds),
                           "per extra minute of log"], table)


if __name__ == "__main__":
    main()

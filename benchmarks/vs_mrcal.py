"""camlog, mrcal and a plain OpenCV script on the same recordings, over many seeds.

Each case records its scenario for every seed (kept in ``--cache`` and reused), calibrates it
with ``camlog calibrate``, then gives camlog's detections (every distinct frame whose board
passed detection; for a pair, the pairs camlog made) to a plain OpenCV script
(``cv2.calibrateCamera`` with default flags, ``cv2.stereoCalibrate`` for a pair;
``cv2.fisheye.calibrate`` for the fisheye) and to mrcal 2.5 (``mrcal-calibrate-cameras`` with
its defaults: outlier rejection, regularisation and the board's flatness estimated). Both are
started from the true fx to the nearest 100 px (mrcal's ``--focal``; OpenCV's fisheye with
``CALIB_USE_INTRINSIC_GUESS``, the principal point at the image centre: without a start OpenCV
5 takes fx = max(W, H) / 2). For a stereo pair, ``OpenCV script`` is a user's whole script on
the log (:mod:`.opencv_stereo_log`: its own detection, pairing by stamp within the slop, the
board still in both cameras). All of them fit the
scenario's true lens model: plumb_bob as k1 k2 p1 p2 k3 (camlog ``-k 3 --tangent-dist``, mrcal
LENSMODEL_OPENCV5), rational_polynomial as its eight coefficients (camlog ``--tangent-dist``,
mrcal LENSMODEL_OPENCV8). mrcal's fisheye models are not OpenCV's, so the fisheye case
compares camlog with ``cv2.fisheye`` only. A fourth column, ``camlog default``, is camlog
with the flags a user gives it (its default lens model: k1 k2 of plumb_bob, k1..k6 of the
rational model, and p1 p2 only when a likelihood-ratio test finds them in the views).

Against the simulator's truth it prints, per case, figure and tool, the median and the 80th
percentile over the seeds of |error|: fx and fy (%), principal point distance (px), the max
projection difference over the image (px; 16 px margin, camera frames aligned by the best
rotation, as mrcal's implied transform; the fisheye within 80° of its axis) and for a stereo
pair the rotation between the cameras (°) and the baseline (%); figures of a pair are the
worse camera's.

mrcal runs under its own Python (its wheels need ≥ 3.12): ``--mrcal-python`` (default
``~/.cache/camlog/mrcal-venv/bin/python``); without one, mrcal is skipped with one line.
Seeds run in turn over every case, so ``--minutes`` (stop starting seeds after that long)
leaves every case with about as many seeds.

    python -m benchmarks.vs_mrcal [--seeds 40] [--cases heldout,stereo,...] [--cache DIR]
        [--mrcal-python PATH] [--minutes M] [--keep FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from camlog.calibrate.flow import CalibrationRun
from camlog.errors import CalibrationError
from processors.calibration.board import Board
from recorder.record import record
from recorder.scenario import load_scenario
from replay.camera import CameraModel
from replay.messages import F64

from .calibrate_speed import Case, calibrate, parse_flags, run_board
from .calibration_truth import (
    Accuracy,
    accuracy,
    camlog_accuracy,
    opencv_models,
    true_models,
    true_right_from_left,
)
from .docs import add_write_docs, markdown_row, write_rows
from .mrcal_run import DEFAULT_VENV, MrcalError, mrcal_available, run_mrcal
from .opencv_stereo_log import calibrate_pair
from .spread import TOOLS, Results, markdown_rows, table

#: the moving board seen through a distorted lens whose k3 is not zero (k1 k2 p1 p2 k3)
MOVING_BLUR_K3_LENS = (-0.25, 0.1, 0.0, 0.0, -0.018)
#: 10 s of each scenario (half its default: 20-40 held poses) at its 30 Hz; the fisheye, which
#: renders up to 26 views a frame, as benchmarks.calibrate_speed records it: 30 s at 4 Hz
CASES = [
    Case("heldout", "mono_heldout",
         "--camera /heldout_camera -s 7x6 -q 0.01 -k 3 --tangent-dist", {"duration_s": 10.0}),
    Case("stereo", "stereo_heldout",
         "--left /heldout/left --right /heldout/right -s 7x6 -q 0.01 --approximate 0.02 "
         "-k 3 --tangent-dist", {"duration_s": 10.0}),
    Case("charuco", "mono_charuco",
         "--camera /charuco_camera -s 8x6 -q 0.011 -p charuco --marker 0.008 "
         "--dictionary DICT_5X5_100 --model rational_polynomial --tangent-dist",
         {"duration_s": 10.0}),
    Case("moving_blur", "mono_moving_blur",
         "--camera /simple_camera -s 7x6 -q 0.01 -k 3 --tangent-dist", {"duration_s": 10.0}),
    Case("moving_blur_k3", "mono_moving_blur",
         "--camera /simple_camera -s 7x6 -q 0.01 -k 3 --tangent-dist",
         {"duration_s": 10.0, "distortion_model": "plumb_bob",
          "distortion": list(MOVING_BLUR_K3_LENS)}),
    Case("fisheye", "mono_fisheye", "--camera /fisheye_camera -s 7x6 -q 0.015 --model fisheye",
         {"duration_s": 30.0, "rate_hz": 4.0}),
]
CASE_NAMES = [c.name for c in CASES]
DEFAULT_CACHE = Path.home() / ".cache" / "camlog" / "vs_mrcal"


@dataclass
class Progress:
    """Every tool's accuracy per case, and the seeds each tool failed on; with ``kept``, each
    case's seed is appended there as one JSON line once it is done, and a later run given
    the same file reads those back instead of running them again."""

    results: Results = field(default_factory=dict)
    failures: dict[tuple[str, str], list[str]] = field(default_factory=dict)
    kept: Path | None = None
    done: set[tuple[str, int]] = field(default_factory=set)
    _seed: dict[str, Any] = field(default_factory=dict)

    def add(self, case: str, tool: str, a: Accuracy) -> None:
        """Keep one result."""
        self.results.setdefault(case, {}).setdefault(tool, []).append(a)
        self._seed.setdefault("results", {})[tool] = asdict(a)

    def fail(self, case: str, tool: str, seed: int, why: str) -> None:
        """Note a failure (printed at once, counted in the table)."""
        self.failures.setdefault((case, tool), []).append(f"seed {seed}: {why}")
        self._seed.setdefault("failures", {})[tool] = why
        print(f"  {case} seed {seed}: {tool} failed: {why}", flush=True)

    def finish(self, case: str, seed: int) -> None:
        """A case's seed is done: append it to the kept file."""
        line, self._seed = {"case": case, "seed": seed, **self._seed}, {}
        self.done.add((case, seed))
        if self.kept is not None:
            with self.kept.open("a", encoding="utf-8") as out:
                out.write(json.dumps(line) + "\n")

    @classmethod
    def resumed(cls, kept: Path | None) -> Progress:
        """The progress kept in ``kept`` by earlier runs (a line cut short by a killed run is
        left out: that seed runs again)."""
        progress = cls(kept=kept)
        if kept is None or not kept.exists():
            return progress
        for text in kept.read_text(encoding="utf-8").splitlines():
            try:
                line = json.loads(text)
            except json.JSONDecodeError:
                continue
            case, seed = line["case"], int(line["seed"])
            for tool, a in line.get("results", {}).items():
                progress.results.setdefault(case, {}).setdefault(tool, []).append(Accuracy(**a))
            for tool, why in line.get("failures", {}).items():
                progress.failures.setdefault((case, tool), []).append(f"seed {seed}: {why}")
            progress.done.add((case, seed))
        return progress


def recording(case: Case, seed: int, cache: Path, duration_s: float | None) -> Path:
    """The case's recording for ``seed``, rendered into ``cache`` unless already there."""
    overrides = {**case.overrides, "seed": seed}
    if duration_s is not None:
        overrides["duration_s"] = duration_s
    rate = f"_{overrides['rate_hz']:g}hz" if "rate_hz" in overrides else ""
    stem = case.scenario if "distortion" not in overrides else f"{case.scenario}-{case.name}"
    path = cache / f"{stem}_{seed}_{overrides['duration_s']:g}s{rate}.mcap"
    if not path.exists():
        partial = path.with_suffix(".partial.mcap")  # an interrupted run's is rendered again
        partial.unlink(missing_ok=True)
        record(load_scenario(case.scenario, overrides), partial, progress=False)
        partial.rename(path)
    return path


def default_flags(flags: str) -> str:
    """A case's flags without those that make camlog fit the whole true lens model: the lens
    model camlog picks by default (k1 k2, k1..k6 rational; p1 p2 when the views show them)."""
    return " ".join(f for f in flags.replace("-k 3", "").split() if f != "--tangent-dist")


def one_seed(case: Case, seed: int, path: Path, *, mrcal_python: Path | None, tmp: Path,
             progress: Progress) -> None:
    """Calibrate one recording with the three tools; keep and print their accuracy."""
    try:
        run = calibrate(path, case.flags, tmp / "out", report=False)
    except CalibrationError as err:
        progress.fail(case.name, "camlog", seed, str(err))
        progress.finish(case.name, seed)
        return
    got = {"camlog": camlog_accuracy(run)}
    if (defaults := default_flags(case.flags)) != case.flags:
        try:
            got["camlog default"] = camlog_accuracy(calibrate(path, defaults, tmp / "default",
                                                              report=False))
        except CalibrationError as err:
            progress.fail(case.name, "camlog default", seed, str(err))
    board = run_board(case, path)
    truths, true_rfl = true_models(run), true_right_from_left(run)
    try:
        models, rfl = opencv_models(run, board)
        got["OpenCV"] = accuracy(models, truths, rfl, true_rfl)
    except cv2.error as err:
        progress.fail(case.name, "OpenCV", seed, str(err).strip().splitlines()[-1])
    if true_rfl is not None:
        try:
            models, rfl = script_models(run, board, path, case)
            got["OpenCV script"] = accuracy(models, truths, rfl, true_rfl)
        except cv2.error as err:
            progress.fail(case.name, "OpenCV script", seed, str(err).strip().splitlines()[-1])
    if mrcal_python is not None and not truths[0].is_fisheye:
        try:
            solved = run_mrcal(mrcal_python, run, board)
            got["mrcal"] = accuracy(solved.models, truths, solved.right_from_left, true_rfl)
        except MrcalError as err:
            progress.fail(case.name, "mrcal", seed, str(err))
    for tool, a in got.items():
        progress.add(case.name, tool, a)
    progress.finish(case.name, seed)
    print(f"  {case.name} seed {seed}: max projection difference px "
          + ", ".join(f"{t} {max(a.max_difference_px):.3f}" for t, a in got.items()),
          flush=True)


def script_models(run: CalibrationRun, board: Board, path: Path, case: Case
                  ) -> tuple[list[CameraModel], F64]:
    """A user's whole OpenCV script on a stereo log (:mod:`.opencv_stereo_log`: its own
    detection, pairing within the case's slop, still boards only): the models and
    ``right_from_left`` (4, 4)."""
    slop = parse_flags(path, case.flags).approximate
    left, right = (c.views for c in run.cameras)
    found = calibrate_pair(path, left_topic=left.source.image_topic,
                           right_topic=right.source.image_topic, size=board.pattern_size,
                           square_m=board.square_m, slop_s=slop if slop is not None else 0.0)
    width, height = left.size
    models = [CameraModel(width, height, k, "plumb_bob", d[:5])
              for k, d in ((found.k_left, found.d_left), (found.k_right, found.d_right))]
    right_from_left = np.eye(4)
    right_from_left[:3, :3], right_from_left[:3, 3] = found.rotation, found.translation
    return models, right_from_left


def models_line(case: Case, mrcal: bool) -> str:
    """Which lens model each tool fitted in a case."""
    if "--model fisheye" in case.flags:
        return (f"{case.name}: equidistant k1..k4: camlog --model fisheye, cv2.fisheye.calibrate"
                " (mrcal: not compared, its fisheye models differ)")
    rational = "rational_polynomial" in case.flags
    model = "rational_polynomial k1 k2 p1 p2 k3 k4 k5 k6" if rational else \
        "plumb_bob k1 k2 p1 p2 k3"
    flags = "--model rational_polynomial --tangent-dist" if rational else "-k 3 --tangent-dist"
    opencv = "CALIB_RATIONAL_MODEL" if rational else "default flags"
    lens = "LENSMODEL_OPENCV8" if rational else "LENSMODEL_OPENCV5"
    return (f"{case.name}: {model}: camlog {flags}, OpenCV {opencv}"
            + (f", mrcal {lens} + board warp" if mrcal else ", mrcal skipped"))


def compare(cases: list[Case], seeds: range, *, cache: Path, duration_s: float | None,
            mrcal_python: Path | None, minutes: float | None, kept: Path | None) -> Progress:
    """Record, calibrate and compare every case over the seeds (seed by seed); stop starting
    seeds after ``minutes``; seeds already in ``kept`` are read from it, not run again."""
    progress = Progress.resumed(kept)
    if progress.done:
        print(f"{len(progress.done)} case seeds read from {kept}", flush=True)
    started = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp_name:
        for seed in seeds:
            if minutes is not None and time.monotonic() - started > minutes * 60:
                print(f"stopped before seed {seed}: over {minutes:g} minutes", flush=True)
                break
            for case in cases:
                if (case.name, seed) in progress.done:
                    continue
                path = recording(case, seed, cache, duration_s)
                one_seed(case, seed, path, mrcal_python=mrcal_python, tmp=Path(tmp_name),
                         progress=progress)
    return progress


def add_seed_arguments(parser: argparse.ArgumentParser, *, seeds: int,
                       case_names: list[str]) -> None:
    """``--seeds``, ``--cases`` (from ``case_names``) and ``--cache``: what every many-seed
    benchmark over the cached recordings takes."""
    parser.add_argument("--seeds", type=int, default=seeds,
                        help=f"seeds per case (default {seeds})")
    parser.add_argument("--cases", default=",".join(case_names),
                        help=f"comma-separated, from {', '.join(case_names)} (default: all)")
    parser.add_argument("--cache", type=Path, default=DEFAULT_CACHE,
                        help=f"recordings are kept and reused here (default {DEFAULT_CACHE})")


def check_seed_arguments(parser: argparse.ArgumentParser, args: argparse.Namespace,
                         case_names: list[str]) -> None:
    """Usage errors (exit 2, one line) for unknown cases or fewer than one seed."""
    unknown = sorted(set(args.cases.split(",")) - set(case_names))
    if unknown:
        parser.error(f"unknown cases {', '.join(unknown)} (known: {', '.join(case_names)})")
    if args.seeds < 1:
        parser.error(f"--seeds must be at least 1, not {args.seeds}")


def parse_arguments(argv: Sequence[str] | None) -> argparse.Namespace:
    """The command line (usage errors exit 2 with one line)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_seed_arguments(parser, seeds=40, case_names=CASE_NAMES)
    parser.add_argument("--duration", type=float, default=None,
                        help="seconds per recording (default: 10, the fisheye 30 at 4 Hz)")
    parser.add_argument("--mrcal-python", type=Path, default=DEFAULT_VENV / "bin" / "python",
                        help="a Python (>= 3.12) that imports mrcal (default: "
                             f"{DEFAULT_VENV}/bin/python)")
    parser.add_argument("--minutes", type=float, default=None,
                        help="start no seed after this many minutes (default: run them all)")
    parser.add_argument("--keep", type=Path, default=None, metavar="FILE",
                        help="append each case's seed to this JSON-lines file when done; seeds "
                             "already in it are read back, not run again (resumes a run)")
    add_write_docs(parser)
    args = parser.parse_args(argv)
    check_seed_arguments(parser, args, CASE_NAMES)
    if args.duration is not None and args.duration <= 0:
        parser.error(f"--duration must be positive, not {args.duration:g}")
    return args


def main(argv: Sequence[str] | None = None) -> None:
    args = parse_arguments(argv)
    chosen = args.cases.split(",")
    cases = [c for c in CASES if c.name in chosen]
    why_not = mrcal_available(args.mrcal_python)
    if why_not is not None:
        print(f"mrcal skipped: {why_not}", flush=True)
    mrcal_python = None if why_not is not None else args.mrcal_python
    args.cache.mkdir(parents=True, exist_ok=True)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    for case in cases:
        print(models_line(case, mrcal_python is not None), flush=True)
    progress = compare(cases, range(args.seeds), cache=args.cache, duration_s=args.duration,
                       mrcal_python=mrcal_python, minutes=args.minutes, kept=args.keep)
    print(f"load average {os.getloadavg()[0]:.1f} at the end", flush=True)
    failed = {key: len(v) for key, v in progress.failures.items()}
    tools = [t for t in TOOLS if mrcal_python is not None or t != "mrcal"]
    print("\n".join(table(progress.results, tools, failed)))
    if args.write_docs:
        write_docs(progress.results, failed)


def write_docs(results: Results, failed: dict[tuple[str, str], int]) -> None:
    """Each case's rows of the docs' table (the cases not run keep theirs)."""
    labels = {c.name: f"`{c.name}`: {c.scenario}" for c in CASES}
    for case, rows in markdown_rows(results, TOOLS, labels, failed).items():
        write_rows("vs_mrcal", f"`{case}`:", [markdown_row(row) for row in rows])


if __name__ == "__main__":
    main()

"""Calibration accuracy on every calibration scenario and calibration speed, in one run.

Accuracy: each case records its scenario for seeds 0, 1, 2 (``--seeds``), calibrates it with
the ``camlog calibrate`` flags a user would give for it (lens model, target, stereo pairing)
and prints, against the simulator's truth: fx, fy error (%), cx, cy error (px), the max
projection difference over the image (16 px margin, camera frames aligned by a rotation; a
fisheye within 80° of its axis; stereo: left / right), stereo rotation (°) and baseline (%)
errors, the worst error/sigma over every estimated parameter (≤ 3: the truth lies inside the
reported 3-sigma intervals; and per case and over every case, how error/sigma is spread: RMS 1
and 4.6 % beyond 2 sigma when the reported sigma is right), and how the projection uncertainty
and the cross-validation compare with the true error (ratios of their medians over the image,
for rays; the true error measured as they predict it, through the estimated board poses and
back through the true ones). A plain
OpenCV script on the same detections (``cv2.calibrateCamera`` / ``cv2.fisheye.calibrate`` with every
detected frame and default flags, ``cv2.stereoCalibrate`` with default flags) follows each
case as a reference row, with the ratio of the max projection differences.

Recordings last the scenarios' 20 s (``--duration`` to change) at 30 Hz, except the fisheye:
it renders 19-26 pinhole views a frame (about 0.5-1.4 fps on 2 cores), so it is recorded at
``--fisheye-rate`` 4 Hz for ``--fisheye-duration`` 30 s: 120 frames, two or three a held pose
of 0.5 s, 60 poses (about 2-4 minutes a seed). Cases run cheapest first; ``--cases`` picks
some; ``--logs DIR`` keeps the recordings there and reuses them in later runs.

Speed of a waved board (case ``moving_speed``): ``mono_moving_blur`` recorded for
``--moving-duration`` (40 s) at 30 Hz, a distinct view in every frame, kept with ``--logs``;
``calibrate`` by default (full report) and with ``--no-report`` against a plain OpenCV script
(``findChessboardCorners`` and ``cornerSubPix`` on every frame, ``calibrateCamera`` with
default flags), each ``--repeats`` times in turn in the same run, medians and their ratios.

Speed (case ``speed``): ``mono_checkerboard`` and ``stereo_checkerboard`` recorded for
``--speed-duration`` (60 s) at 30 Hz, decode-only (read and decode every image, the floor of
any offline calibrator) against ``calibrate`` with its full report, and the peak memory of the
command on a log a third as long and on the full one (flat in log length).

    python -m benchmarks.calibrate_speed [--cases mono,stereo,speed] [--seeds N] [--logs DIR]
        [--quick]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from camlog.calibrate.flow import CalibrationRun, MeasureAgain, calibrate_log, cameras_of
from camlog.cli.calibrate import add_arguments
from camlog.requests.arguments import request_from_args
from camlog.requests.calibrate import CalibrateRequest
from processors.calibration.board import Board
from recorder.record import record
from recorder.scenario import load_scenario
from replay import open_reader

from .calibration_truth import Accuracy, camlog_accuracy, opencv_reference
from .docs import add_write_docs, markdown_row, write_rows
from .report import cli_peak_rss_mb, emit, write_summary_rows


@dataclass(frozen=True)
class Case:
    """A scenario and the ``camlog calibrate`` flags for it."""

    name: str
    scenario: str
    flags: str
    overrides: dict[str, Any] = field(default_factory=dict)


#: cheapest first (recording dominates: fisheye and moving board render several images a frame)
CASES = [
    Case("mono", "mono_checkerboard", "--camera /simple_camera -s 7x6 -q 0.01"),
    Case("mono_tangent", "mono_checkerboard",
         "--camera /simple_camera -s 7x6 -q 0.01 --tangent-dist"),
    Case("heldout", "mono_heldout", "--camera /heldout_camera -s 7x6 -q 0.01"),
    Case("circles", "mono_circles", "--camera /simple_camera -s 4x11 -q 0.01 -p acircles"),
    Case("stereo", "stereo_checkerboard",
         "--left /stereo_camera/left --right /stereo_camera/right -s 7x6 -q 0.01"),
    Case("stereo_unsynced", "stereo_unsynced",
         "--left /unsynced/left --right /unsynced/right -s 7x6 -q 0.01 --approximate 0.02"),
    Case("stereo_heldout", "stereo_heldout",
         "--left /heldout/left --right /heldout/right -s 7x6 -q 0.01 --approximate 0.02"),
    Case("charuco", "mono_charuco", "--camera /charuco_camera -s 8x6 -q 0.011 -p charuco "
         "--marker 0.008 --dictionary DICT_5X5_100 --model rational_polynomial"),
    Case("moving_blur", "mono_moving_blur", "--camera /simple_camera -s 7x6 -q 0.01"),
    Case("fisheye", "mono_fisheye", "--camera /fisheye_camera -s 7x6 -q 0.015 --model fisheye"),
]
CASE_NAMES = [c.name for c in CASES]


def decode_only_s(path: Path, topics: list[str]) -> float:
    """Seconds to read and decode every image of ``topics``."""
    started = time.perf_counter()
    with open_reader(path) as reader:
        for _ in reader.frames(topics):
            pass
    return time.perf_counter() - started


def parse_flags(path: Path, flags: str) -> CalibrateRequest:
    """``camlog calibrate PATH FLAGS`` parsed as the command parses it."""
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    return request_from_args(CalibrateRequest, parser.parse_args([str(path), *flags.split()]))


def calibrate(path: Path, flags: str, out: Path, *, report: bool,
              measure_again: MeasureAgain | None = None) -> CalibrationRun:
    """``camlog calibrate PATH FLAGS`` as a function call (no printout); ``measure_again``
    as :func:`~camlog.calibrate.flow.calibrate_log` takes it."""
    request = dataclasses.replace(parse_flags(path, flags), output=out, overwrite=True,
                                  progress=False, report=report)
    return calibrate_log(request, measure_again=measure_again)


def z_scores(run: CalibrationRun) -> list[float]:
    """(estimate - truth) / sigma of every estimated parameter of every camera."""
    return [q.error / q.std for c in run.summary.cameras
            for q in c.parameters.values() if q.std > 0 and q.error is not None]


def sigma_ratio(run: CalibrationRun) -> float:
    """The worst |estimate - truth| / sigma over every estimated parameter of every camera."""
    return max(abs(z) for z in z_scores(run))


def z_line(label: str, zs: list[float]) -> str:
    """How error/sigma is spread over many estimates, against a normal distribution's
    (what it is when the reported sigma is right)."""
    if not zs:
        return f"{label}: no estimates"
    magnitudes = np.abs(np.asarray(zs))
    rms = float(np.sqrt(np.mean(magnitudes ** 2)))
    return (f"{label}: error/σ over {len(zs)} estimates: RMS {rms:.2f}"
            f" (1 when σ is right), beyond 2σ {np.mean(magnitudes > 2) * 100:.1f} % (4.6 %), "
            f"beyond 3σ {np.mean(magnitudes > 3) * 100:.1f} % (0.27 %)")


def agreement(run: CalibrationRun) -> tuple[float, float]:
    """Projection uncertainty (rays, 1 sigma) and cross-validation over the true error (rays,
    measured as both predict it: through the estimated board poses and back through the true
    ones), ratios of their medians over the image; the one furthest from 1 over the cameras."""
    unc, cv = [], []
    for camera in run.summary.cameras:
        u = camera.uncertainty
        if u is None or not u.rays_true_error_median_px:
            continue
        unc.append(u.rays_median_px / u.rays_true_error_median_px)
        if u.cross_validation_median_px is not None:
            cv.append(u.cross_validation_median_px / u.rays_true_error_median_px)

    def furthest(values: list[float]) -> float:
        return max(values, key=lambda r: max(r, 1 / r)) if values else float("nan")
    return furthest(unc), furthest(cv)


def row(label: str, seed: int, a: Accuracy, extra: str) -> str:
    """One printed line of accuracy figures."""
    stereo = ""
    if a.rotation_deg is not None and a.baseline_percent is not None:
        stereo = f"{a.rotation_deg:7.4f} {a.baseline_percent:+8.4f}"
    diff = " / ".join(f"{d:.3f}" for d in a.max_difference_px)
    return (f"{label:20} {seed:4d} {a.focal_percent:+8.4f} {a.cx_px:+7.3f} {a.cy_px:+7.3f} "
            f"{diff:>13} {stereo:>16} {extra}")


@dataclass
class Worst:
    """The worst figures of one case over its seeds (for the camlog and the OpenCV rows)."""

    values: dict[str, float] = field(default_factory=dict)

    def add(self, **figures: float | None) -> None:
        """Keep the larger magnitude of each figure."""
        for key, value in figures.items():
            if value is not None:
                self.values[key] = max(self.values.get(key, 0.0), abs(value))

    def line(self) -> str:
        """The worst figures in one line."""
        return "  ".join(f"{k} {v:.4g}" for k, v in self.values.items())


def docs_row(case: Case, mine: Worst, theirs: Worst, ratios: list[float],
             failures: list[str]) -> list[str]:
    """The case's row of the docs' accuracy table: camlog's worst figures over the seeds and
    the plain OpenCV script's, with camlog's ratio to it per seed."""
    v, ref = mine.values, theirs.values
    maxdiff = (f"{v['maxdiff_left_px']:.3f} / {v['maxdiff_right_px']:.3f} px"
               if "maxdiff_left_px" in v else f"{v['maxdiff_px']:.3f} px")
    stereo = f"{v['rot_deg']:.3f}°, {v['baseline_pct']:.3f} %" if "rot_deg" in v else ""
    opencv = ""
    if "maxdiff_px" in ref:
        opencv = f"{ref['maxdiff_px']:.2f} px"
        if "rot_deg" in ref:
            opencv += f", {ref['rot_deg']:.3f}°, {ref['baseline_pct']:.3f} %"
        opencv += f" (camlog {', '.join(f'{r:.2f}×' for r in ratios)})"
    if failures:
        opencv += ("; " if opencv else "") + (f"fails at {len(failures)} seeds "
                                               f"({failures[-1]})")
    return [f"`{case.name}`: {case.scenario} (`{case.flags}`)", f"{v['fx_fy_pct']:.2g} %",
            f"{v['cx_px']:.3f} px", f"{v['cy_px']:.3f} px", maxdiff, stereo,
            f"{v['err_sigma']:.2f}", f"{v['unc_ratio']:.1f}×, {v['cv_ratio']:.1f}×", opencv]


def accuracy_case(case: Case, seeds: range, duration: float | None, *, logs: Path,
                  tmp: Path, fisheye: dict[str, float], write_docs: bool = False) -> list[float]:
    """Record (into ``logs``, unless there already), calibrate and compare one case over the
    seeds; print its rows and its worst (with ``write_docs``, into the docs' accuracy table
    too); return every parameter's error/sigma."""
    mine, theirs = Worst(), Worst()
    ratios: list[float] = []
    failures: list[str] = []
    zs: list[float] = []
    for seed in seeds:
        overrides: dict[str, Any] = {"seed": seed, **case.overrides}
        if case.scenario == "mono_fisheye":
            overrides.update(fisheye)
        elif duration is not None:
            overrides["duration_s"] = duration
        tag = "" if case.scenario == "mono_fisheye" or duration is None else f"_{duration:g}s"
        path = logs / f"{case.scenario}_{seed}{tag}.mcap"
        if not path.exists():
            record(load_scenario(case.scenario, overrides), path, progress=False)
        started = time.perf_counter()
        run = calibrate(path, case.flags, tmp / "out", report=False)
        wall = time.perf_counter() - started
        a = camlog_accuracy(run)
        sigmas = sigma_ratio(run)
        zs += z_scores(run)
        unc, cv = agreement(run)
        used = sum(c.evidence.frames_used for c in run.summary.cameras
                   if c.evidence is not None)
        print(row(case.name, seed, a, f"{sigmas:5.2f} {unc:5.2f} {cv:5.2f} {used:6d} "
                                      f"{wall:6.1f}"), flush=True)
        try:
            ref = opencv_reference(run, run_board(case, path))
        except cv2.error as err:  # a plain script stops here too
            failures.append(str(err).strip().splitlines()[-1])
            print(f"{'  plain OpenCV':20} {seed:4d} failed: {failures[-1]}", flush=True)
            ref = None
        if ref is not None:
            ratio = max(a.max_difference_px) / max(ref.max_difference_px)
            ratios.append(ratio)
            print(row("  plain OpenCV", seed, ref, f"camlog/OpenCV max difference {ratio:.2f}"),
                  flush=True)
            theirs.add(fx_fy_pct=ref.focal_percent, cx_px=ref.cx_px, cy_px=ref.cy_px,
                       maxdiff_px=max(ref.max_difference_px), rot_deg=ref.rotation_deg,
                       baseline_pct=ref.baseline_percent)
        mine.add(fx_fy_pct=a.focal_percent, cx_px=a.cx_px, cy_px=a.cy_px,
                 maxdiff_px=max(a.max_difference_px), rot_deg=a.rotation_deg,
                 baseline_pct=a.baseline_percent, err_sigma=sigmas,
                 unc_ratio=max(unc, 1 / unc), cv_ratio=max(cv, 1 / cv))
        if len(a.max_difference_px) == 2:
            mine.add(maxdiff_left_px=a.max_difference_px[0],
                     maxdiff_right_px=a.max_difference_px[1])
    print(f"worst over seeds {list(seeds)}: {case.name}: {mine.line()}")
    print(f"{'':>25}plain OpenCV: {theirs.line()}", flush=True)
    print(z_line(case.name, zs), flush=True)
    if write_docs:
        write_rows("calibration_accuracy", f"`{case.name}`:",
                   [markdown_row(docs_row(case, mine, theirs, ratios, failures))])
    return zs


def add_kept_logs_arguments(parser: argparse.ArgumentParser, default_cases: str) -> None:
    """``--logs``, ``--cases`` and ``--seeds`` of a benchmark that reads the recordings this
    one keeps (``--logs DIR``)."""
    parser.add_argument("--logs", type=Path, required=True,
                        help="recordings kept by python -m benchmarks.calibrate_speed --logs "
                             "(<scenario>_<seed>.mcap)")
    parser.add_argument("--cases", default=default_cases,
                        help=f"comma-separated, from {', '.join(CASE_NAMES)}")
    parser.add_argument("--seeds", type=int, default=3, help="seeds per case (default 3)")


def kept_cases(parser: argparse.ArgumentParser, args: argparse.Namespace) -> list[str]:
    """The cases ``args`` chose (see :func:`add_kept_logs_arguments`); an unknown case or a
    missing recording is a usage error."""
    chosen: list[str] = args.cases.split(",")
    unknown = sorted(set(chosen) - set(CASE_NAMES))
    if unknown:
        parser.error(f"unknown cases {', '.join(unknown)} (known: {', '.join(CASE_NAMES)})")
    missing = [p for c in CASES if c.name in chosen for s in range(args.seeds)
               if not (p := args.logs / f"{c.scenario}_{s}.mcap").exists()]
    if missing:
        parser.error(f"no recording {missing[0]} (record it with benchmarks.calibrate_speed "
                     "--logs)")
    return chosen


def run_board(case: Case, path: Path) -> Any:
    """The case's board (from its flags)."""
    return parse_flags(path, case.flags).board()


def speed(duration: float, tmp: Path) -> None:
    """Calibrate time against decode-only on long mono and stereo logs, and peak memory."""
    for name, scenario in (("mono", "mono_checkerboard"), ("stereo", "stereo_checkerboard")):
        case = next(c for c in CASES if c.name == name)
        path = tmp / f"speed_{scenario}.mcap"
        record(load_scenario(scenario, {"duration_s": duration, "seed": 0}), path,
               progress=False)
        cameras = cameras_of(parse_flags(path, case.flags))
        decode = decode_only_s(path, [f"{c}/image_raw" for c in cameras])
        started = time.perf_counter()
        calibrate(path, case.flags, tmp / "speed_out", report=True)
        wall = time.perf_counter() - started
        emit(f"calibrate {name} ({duration:.0f} s log, full report)", baseline="decode only",
             baseline_value=decode, measured="calibrate", measured_value=wall, unit="s",
             ratio=wall / decode,
             target=f"<= {10 if name == 'mono' else 20} s for a 60 s log "
                    f"(here {wall / duration * 60:.1f} s per minute)")
        if name == "mono":
            short = tmp / "speed_short.mcap"
            record(load_scenario(scenario, {"duration_s": duration / 3, "seed": 0}), short,
                   progress=False)
            flags = [*case.flags.split(), "--overwrite", "--no-progress", "-o"]
            rss_short = cli_peak_rss_mb(["calibrate", str(short), *flags, str(tmp / "rss_short")])
            rss_long = cli_peak_rss_mb(["calibrate", str(path), *flags, str(tmp / "rss_long")])
            print(f"peak memory of camlog calibrate: {rss_short:.0f} MB for "
                  f"{duration / 3:.0f} s, {rss_long:.0f} MB for {duration:.0f} s of log",
                  flush=True)


def plain_script_s(path: Path, topic: str, board: Board) -> float:
    """Seconds a plain OpenCV script takes: every frame decoded, ``findChessboardCorners``
    and ``cornerSubPix`` on each, ``calibrateCamera`` with default flags on every board
    found."""
    started = time.perf_counter()
    objects, images, size = [], [], (0, 0)
    points = board.points_in_board().astype(np.float32)
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    with open_reader(path) as reader:
        for record in reader.frames([topic]):
            gray = record.message.mono8()
            size = (gray.shape[1], gray.shape[0])
            found, corners = cv2.findChessboardCorners(gray, board.pattern_size)
            if found:
                images.append(cv2.cornerSubPix(gray, corners, (11, 11), (-1, -1), criteria))
                objects.append(points)
    cv2.calibrateCamera(objects, images, size, None, None)
    return time.perf_counter() - started


def moving_speed(duration: float, logs: Path, tmp: Path, *, repeats: int) -> None:
    """A waved board (``mono_moving_blur``, ``duration`` s at 30 Hz: a distinct view in every
    frame): camlog's default, with and without its report, against the plain OpenCV script,
    each ``repeats`` times in turn; the medians and their ratios."""
    case = next(c for c in CASES if c.name == "moving_blur")
    path = logs / f"{case.scenario}_0_{duration:g}s.mcap"
    if not path.exists():
        record(load_scenario(case.scenario, {"duration_s": duration, "seed": 0}), path,
               progress=False)
    board = run_board(case, path)
    plain: list[float] = []
    full: list[float] = []
    bare: list[float] = []
    for _ in range(repeats):
        plain.append(plain_script_s(path, "/simple_camera/image_raw", board))
        for report, times in ((True, full), (False, bare)):
            started = time.perf_counter()
            calibrate(path, case.flags, tmp / "moving_out", report=report)
            times.append(time.perf_counter() - started)
    script = float(np.median(plain))
    for label, times, most in (("default, full report", full, 2.0),
                               ("--no-report", bare, 1.5)):
        wall = float(np.median(times))
        emit(f"calibrate waved board ({duration:.0f} s log, {label})",
             baseline="plain OpenCV script", baseline_value=script, measured="calibrate",
             measured_value=wall, unit="s", ratio=wall / script,
             target=f"<= {most:g}x the plain script (median of {repeats})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default=",".join([*CASE_NAMES, "speed", "moving_speed"]),
                        help=f"comma-separated, from {', '.join(CASE_NAMES)}, speed, "
                             "moving_speed (default: all)")
    parser.add_argument("--duration", type=float, default=None,
                        help="seconds per recording (default: the scenario's, 20 s)")
    parser.add_argument("--fisheye-duration", type=float, default=30.0,
                        help="seconds of the fisheye recording (default 30)")
    parser.add_argument("--fisheye-rate", type=float, default=4.0,
                        help="frame rate of the fisheye recording (default 4 Hz)")
    parser.add_argument("--speed-duration", type=float, default=60.0,
                        help="seconds of the speed case's recordings (default 60)")
    parser.add_argument("--moving-duration", type=float, default=40.0,
                        help="seconds of the moving_speed case's waved board (default 40)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="runs of each side of the moving_speed case (default 3)")
    parser.add_argument("--seeds", type=int, default=3, help="seeds per case (default 3)")
    parser.add_argument("--logs", type=Path, default=None,
                        help="keep the recordings in this folder and reuse those already "
                             "there (default: a temporary folder)")
    parser.add_argument("--quick", action="store_true",
                        help="one seed, 10 s recordings, mono, stereo and speed (smoke test)")
    add_write_docs(parser)
    args = parser.parse_args()
    chosen = args.cases.split(",")
    unknown = sorted(set(chosen) - {*CASE_NAMES, "speed", "moving_speed"})
    if unknown:
        parser.error(f"unknown cases {', '.join(unknown)} (known: {', '.join(CASE_NAMES)}, "
                     "speed, moving_speed)")
    duration, speed_duration = args.duration, args.speed_duration
    seeds = range(args.seeds)
    if args.quick and args.write_docs:
        parser.error("--write-docs writes measured figures: not with --quick")
    if args.quick:
        chosen, duration, speed_duration, seeds = \
            ["mono", "stereo", "speed", "moving_speed"], 10.0, 10.0, range(1)
    fisheye = {"duration_s": args.fisheye_duration, "rate_hz": args.fisheye_rate}
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    print(f"{'case':20} {'seed':>4} {'fx,fy %':>8} {'cx px':>7} {'cy px':>7} "
          f"{'maxdiff px':>13} {'rot °':>7} {'base %':>8} err/σ unc/t  cv/t frames calib s")
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        logs = args.logs or tmp
        logs.mkdir(parents=True, exist_ok=True)
        every_z: list[float] = []
        for case in CASES:
            if case.name in chosen:
                every_z += accuracy_case(case, seeds, duration, logs=logs, tmp=tmp,
                                         fisheye=fisheye, write_docs=args.write_docs)
        if every_z:
            print(z_line("every case", every_z), flush=True)
        if "speed" in chosen:
            speed(speed_duration, tmp)
        if "moving_speed" in chosen:
            moving_speed(10.0 if args.quick else args.moving_duration, logs, tmp,
                         repeats=1 if args.quick else args.repeats)
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    write_summary_rows("calibrate_speed", args)
    print("maxdiff: max projection difference against the true model over the image (16 px "
          "margin; fisheye within 80° of the axis), camera frames aligned by a rotation; "
          "unc/t, cv/t: projection uncertainty (rays, 1σ) and cross-validation over the true "
          "error (rays, through the estimated board poses and back through the true ones), "
          "medians over the image")


if __name__ == "__main__":
    main()

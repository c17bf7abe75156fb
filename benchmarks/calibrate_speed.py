"""Calibration speed and accuracy on full-length default recordings, in one run.

Records the default scenarios (60 s at 30 Hz unless --duration says otherwise) for several
seeds, then for each log measures a decode-only pass (read and decode every image: the floor
any offline calibrator pays) and ``camlog calibrate``, and prints wall time, the ratio to
decode-only, and the result against the simulator's ground truth, with the worst error over
the seeds. Peak memory of the calibrate command is measured on a short and a full-length
log to show that it does not grow with length.

    python -m benchmarks.calibrate_speed [--duration S] [--seeds N] [--quick]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from camlog.calibrate.flow import CalibrationRun, calibrate_log
from processors.calibration.board import Board, make_board
from processors.calibration.solve import CalibrationOptions, max_projection_difference
from recorder.record import record
from recorder.scenario import load_scenario
from replay import open_reader
from replay.camera import CameraModel
from replay.records import ParameterEstimate

from .report import cli_peak_rss_mb, emit

CASES: list[tuple[str, str, dict[str, object], list[str], CalibrationOptions]] = [
    # label, scenario, overrides, cameras, options
    ("mono", "mono_checkerboard", {}, ["/simple_camera"], CalibrationOptions()),
    ("mono --tangent-dist", "mono_checkerboard", {}, ["/simple_camera"],
     CalibrationOptions(tangential="estimate")),
    ("mono plumb_bob k1=-0.2", "mono_checkerboard",
     {"distortion": [-0.2, 0.05, 0.0, 0.0, 0.0]}, ["/simple_camera"], CalibrationOptions()),
    ("stereo", "stereo_checkerboard", {}, ["/stereo_camera/left", "/stereo_camera/right"],
     CalibrationOptions()),
]


def decode_only_s(path: Path, topics: list[str]) -> float:
    started = time.perf_counter()
    with open_reader(path) as reader:
        for _ in reader.frames(topics):
            pass
    return time.perf_counter() - started


def error(estimate: ParameterEstimate) -> float:
    """Estimate - truth (the benchmark's logs always have the simulator's truth)."""
    assert estimate.error is not None, "the log has no ground truth"
    return estimate.error


def relative(estimate: ParameterEstimate) -> float:
    """(estimate - truth) / truth."""
    assert estimate.truth is not None, "the log has no ground truth"
    return error(estimate) / estimate.truth


def opencv_reference(run: CalibrationRun, board: Board) -> float | None:
    """A plain OpenCV script's result on the same detections: ``cv2.calibrateCamera`` (or
    ``cv2.fisheye.calibrate``) with default flags on every detected view; its max projection
    difference against the truth over the image, camera frames aligned (px)."""
    camera = run.cameras[0]
    if camera.truth is None:
        return None
    views = camera.views
    frames = [f for f in views.frames if f.candidate]
    points = board.points_in_board()
    objects = [points[f.detection.ids].reshape(1, -1, 3) for f in frames if f.detection]
    images = [f.detection.corners_px.reshape(1, -1, 2) for f in frames if f.detection]
    true_model = camera.truth.model()
    if true_model.is_fisheye:
        _rms, k, d, _r, _t = cv2.fisheye.calibrate(
            objects, images, views.size, np.zeros((3, 3)), np.zeros(4),
            flags=cv2.CALIB_RECOMPUTE_EXTRINSIC | cv2.CALIB_FIX_SKEW)
        model = CameraModel(views.size[0], views.size[1], np.asarray(k, dtype=np.float64),
                            "equidistant", np.asarray(d, dtype=np.float64).reshape(-1)[:4])
    else:
        rational = true_model.distortion_model == "rational_polynomial"
        _rms, k, d, _r, _t = cv2.calibrateCamera(
            [o.astype(np.float32) for o in objects], [i.astype(np.float32) for i in images],
            views.size, None, None, flags=cv2.CALIB_RATIONAL_MODEL if rational else 0)
        model = CameraModel(views.size[0], views.size[1], np.asarray(k, dtype=np.float64),
                            true_model.distortion_model,
                            np.asarray(d, dtype=np.float64).reshape(-1)[:8 if rational else 5])
    return max_projection_difference(model, true_model, align_rotation=True)


def peak_rss_mb(path: Path, camera: str, out: Path) -> float:
    """Peak resident memory (MB) of ``camlog calibrate`` in a fresh process."""
    return cli_peak_rss_mb(["calibrate", str(path), "--size", "7x6", "--square", "0.01",
                            "--camera", camera, "-o", str(out), "--overwrite", "--no-progress"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=60.0, help="seconds per recording")
    parser.add_argument("--seeds", type=int, default=3,
                        help="scenario seeds per case for the accuracy table (default 3)")
    parser.add_argument("--quick", action="store_true", help="10 s recordings (CI smoke mode)")
    args = parser.parse_args()
    duration = 10.0 if args.quick else args.duration
    seeds = range(1 if args.quick else args.seeds)
    board = make_board("7x6", 0.01)
    print(f"{'case':24} {'seed':>4} {'frames':>6} {'decode s':>8} {'calib s':>8} "
          f"{'fx err %':>9} {'fy err %':>9} {'cx err':>13} {'cy err':>13} {'maxdiff':>13} "
          f"{'err/σ':>5} {'stereo':>26}")
    worst: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        logs: dict[tuple[str, str, int], Path] = {}
        for seed in seeds:
            for label, scenario_name, overrides, cameras, options in CASES:
                key = (scenario_name, json.dumps(overrides, sort_keys=True), seed)
                if key not in logs:
                    logs[key] = tmp / f"{scenario_name}_{len(logs)}.mcap"
                    scenario = load_scenario(scenario_name, {"duration_s": duration,
                                                             "seed": seed, **overrides})
                    record(scenario, logs[key], progress=False)
                path = logs[key]
                topics = [f"{c}/image_raw" for c in cameras]
                decode = decode_only_s(path, topics)
                started = time.perf_counter()
                run = calibrate_log(path, board=board, cameras=cameras,
                                    output_dir=tmp / "out", options=options,
                                    overwrite=True, progress=False)
                wall = time.perf_counter() - started
                cam = run.summary.cameras[0]
                p = cam.parameters
                frames = sum(c.frames for c in run.summary.cameras)
                aligned = cam.max_projection_difference_vs_truth_covered_aligned_px
                raw = cam.max_projection_difference_vs_truth_covered_px
                assert aligned is not None and raw is not None, "the log has no truth"
                stereo = ""
                # the worst estimated parameter's error in units of its sigma, over cameras
                sigmas = max(abs(error(q)) / q.std for c in run.summary.cameras
                             for q in c.parameters.values() if q.std > 0)
                errors = [abs(error(p["cx"])), abs(error(p["cy"])), aligned,
                          100 * max(abs(relative(p[n])) for n in ("fx", "fy")), sigmas]
                s = run.summary.stereo
                if s is not None and s.truth is not None:
                    stereo = (f"B {s.truth.baseline_error_percent:+.3f}% "
                              f"epi {s.epipolar_rms_px:.3f}px")
                    errors += [abs(s.truth.baseline_error_percent), s.epipolar_rms_px]
                worst[label] = [max(a, b) for a, b in zip(worst.get(label, errors), errors,
                                                          strict=True)]
                whole = cam.max_projection_difference_vs_truth_aligned_px
                reference = opencv_reference(run, board) if len(cameras) == 1 else None
                if reference is not None and whole is not None:
                    print(f"{'  plain OpenCV':24} {seed:4d} same detections: max difference "
                          f"{reference:.3f} px over the image (camlog {whole:.3f} px, ratio "
                          f"{whole / reference:.2f})", flush=True)
                print(f"{label:24} {seed:4d} {frames:6d} {decode:8.2f} {wall:8.2f} "
                      f"{100 * relative(p['fx']):+9.4f} {100 * relative(p['fy']):+9.4f} "
                      f"{error(p['cx']):+6.3f}±{p['cx'].std:.3f} "
                      f"{error(p['cy']):+6.3f}±{p['cy'].std:.3f} "
                      f"{aligned:6.3f}/{raw:6.3f} {sigmas:5.2f} {stereo:>26}", flush=True)
                if seed == 0 and label in ("mono", "stereo"):
                    minutes = frames / len(cameras) / 30.0 / 60.0
                    emit(f"calibrate {label} ({frames // len(cameras) / 30:.0f} s log)",
                         baseline="decode only", baseline_value=decode, measured="calibrate",
                         measured_value=wall, unit="s", ratio=wall / decode,
                         target=f"<= {20 if label == 'mono' else 40} s per minute of log "
                                f"(here {wall / minutes:.1f} s/min)")
        print(f"worst over seeds {list(seeds)}: |cx|, |cy| px, maxdiff px, |fx|,|fy| %, "
              "err/σ[, |baseline| %, epipolar px]")
        for label, values in worst.items():
            print(f"  {label:24} " + "  ".join(f"{v:.3f}" for v in values))
        short = tmp / "short.mcap"
        record(load_scenario("mono_checkerboard", {"duration_s": duration / 3}), short,
               progress=False)
        long_log = logs[("mono_checkerboard", "{}", 0)]
        rss_short = peak_rss_mb(short, "/simple_camera", tmp / "rss_short")
        rss_long = peak_rss_mb(long_log, "/simple_camera", tmp / "rss_long")
        print(f"peak memory of camlog calibrate: {rss_short:.0f} MB for {duration / 3:.0f} s, "
              f"{rss_long:.0f} MB for {duration:.0f} s of log")
    print("maxdiff: max projection difference against the true model where corners were seen, "
          "after aligning the camera frames by a rotation / without")


if __name__ == "__main__":
    main()

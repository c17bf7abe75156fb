"""camlog's defaults against a plain OpenCV script, on analytically rendered logs, many seeds.

Three cases a user brings, rendered exactly (:mod:`benchmarks.analytic_render`: every pixel's
ray through the true lens, motion blur over the exposure, Gaussian noise), each through the
lens that makes it hard beyond the boards:

* ``moving_k3``: a 9x6 board waved for ``--seconds`` at 30 Hz, 4 ms exposure, through a
  plumb_bob lens with k3 (k1 -0.285, k2 0.105, p1 0.0008, p2 -0.0011, k3 -0.018); camlog
  with its default flags;
* ``fisheye``: the 7x6 board waved over a 176° equidistant lens (``mono_fisheye``'s camera,
  4 ms exposure) at 30 Hz; camlog ``--model fisheye``;
* ``charuco``: ``mono_charuco`` (8x6 ChArUco held at poses over a rational_polynomial lens,
  a third cut by the image border) at 30 Hz; camlog ``--model rational_polynomial``.

The script detects on every frame as a user writes it (``findChessboardCorners`` +
``cornerSubPix``, or ``CharucoDetector``) and calibrates with ``calibrateCamera``'s default
flags (k1 k2 p1 p2 k3), ``CALIB_RATIONAL_MODEL`` for the rational lens, or
``cv2.fisheye.calibrate``. Per case and seed: the max projection difference from the truth
(:func:`~benchmarks.calibration_truth.max_difference_px`: 16 px margin, aligned by a rotation,
a fisheye within 80° of its axis) of camlog and of the script, camlog's stated worst
projection uncertainty (1 sigma, rays and at the working range) and its real error in units of it;
then the medians, how often camlog is at or below the script, and the worst real error / sigma.

    python -m benchmarks.vs_script [--cases moving_k3,fisheye,charuco] [--seeds 20]
        [--seconds 20] [--cache DIR]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from camlog.errors import CalibrationError
from recorder.builtin import builtin_dir
from replay import open_reader
from replay.camera import CameraModel
from replay.messages import F64
from replay.topics import CameraTopics

from .analytic_render import record_analytic, scenario_of
from .calibrate_speed import calibrate
from .calibration_truth import max_difference_px

DEFAULT_CACHE = Path.home() / ".cache" / "camlog" / "vs_script"
SUBPIX = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)


@dataclass(frozen=True)
class ScriptCase:
    """A scenario rendered analytically, camlog's flags for it and the script's target."""

    name: str
    scenario: str
    overrides: dict[str, Any]
    flags: str
    pattern: str  # chessboard or charuco
    wave: bool  # held poses aimed at the image are waved from one to the next
    target: dict[str, Any] = field(default_factory=dict)  # the target's fields replaced

    def scenario_of(self, seed: int, seconds: float) -> Any:
        """The scenario of one seed, ``seconds`` long."""
        raw = tomllib.loads((builtin_dir() / f"{self.scenario}.toml").read_text())
        raw["targets"][0].update(self.target)
        return scenario_of(raw, {**self.overrides, "seed": seed, "duration_s": seconds})


CASES = [
    ScriptCase("moving_k3", "mono_moving_blur",
               {"distortion_model": "plumb_bob",
                "distortion": [-0.285, 0.105, 0.0008, -0.0011, -0.018], "noise_std": 2.0},
               "--camera /simple_camera -s 9x6 -q 0.01", "chessboard", wave=False,
               target={"inner_corners": [9, 6]}),
    ScriptCase("fisheye", "mono_fisheye", {"exposure_s": 0.004, "noise_std": 2.0},
               "--camera /fisheye_camera -s 7x6 -q 0.015 --model fisheye", "chessboard",
               wave=True),
    ScriptCase("charuco", "mono_charuco", {"noise_std": 2.0},
               "--camera /charuco_camera -s 8x6 -q 0.011 -p charuco --marker 0.008 "
               "--dictionary DICT_5X5_100 --model rational_polynomial", "charuco", wave=False),
]
CASE_NAMES = [c.name for c in CASES]


@dataclass
class Outcome:
    """One seed of one case: camlog's and the script's max projection difference (px),
    camlog's stated worst sigma (rays, and at the working range) and the script's views."""

    camlog_px: float
    script_px: float | None
    rays_sigma_px: float
    range_sigma_px: float
    script_views: int = 0
    notes: list[str] = field(default_factory=list)

    @property
    def ratio(self) -> float:
        """camlog's real error over its smaller stated worst sigma."""
        return self.camlog_px / min(self.rays_sigma_px, self.range_sigma_px)


def _gray(pixels: np.ndarray) -> np.ndarray:
    return pixels if pixels.ndim == 2 else cv2.cvtColor(pixels, cv2.COLOR_RGB2GRAY)


def _charuco_board(case: ScriptCase, seed: int) -> cv2.aruco.CharucoBoard:
    target = case.scenario_of(seed, 1.0).targets[0]
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, target.dictionary))
    return cv2.aruco.CharucoBoard(target.squares, target.square_m, target.marker_m, dictionary)


def script_views(path: Path, case: ScriptCase, seed: int) -> list[tuple[F64, F64]]:
    """``(object points (N, 3), image points (N, 2))`` of every frame the plain script finds
    its board in."""
    scenario = case.scenario_of(seed, 1.0)
    camera, target = scenario.cameras[0], scenario.targets[0]
    topic = CameraTopics(camera.namespace).image_raw
    views = []
    if case.pattern == "charuco":
        board = _charuco_board(case, seed)
        detector = cv2.aruco.CharucoDetector(board)
        points = np.asarray(board.getChessboardCorners(), dtype=np.float64)
    else:
        cols, rows = target.inner_corners
        grid = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * target.square_m
        points = np.column_stack([grid, np.zeros(len(grid))])
    with open_reader(path) as reader:
        for record in reader.frames([topic]):
            gray = _gray(record.message.pixels)
            if case.pattern == "charuco":
                corners, ids, _m, _mi = detector.detectBoard(gray)
                if ids is not None and len(ids) >= 6:
                    views.append((points[ids.ravel()], corners.reshape(-1, 2).astype(np.float64)))
                continue
            found, corners = cv2.findChessboardCorners(gray, (cols, rows))
            if found:
                corners = cv2.cornerSubPix(gray, corners, (11, 11), (-1, -1), SUBPIX)
                views.append((points, corners.reshape(-1, 2).astype(np.float64)))
    return views


def script_model(views: list[tuple[F64, F64]], truth: CameraModel) -> CameraModel:
    """The script's calibration in the true lens model: ``calibrateCamera`` with default
    flags (``CALIB_RATIONAL_MODEL`` for a rational lens) or ``cv2.fisheye.calibrate``."""
    size = (truth.width, truth.height)
    objects = [o.astype(np.float32) for o, _ in views]
    images = [i.astype(np.float32) for _, i in views]
    if truth.is_fisheye:
        _rms, k, d, _r, _t = cv2.fisheye.calibrate(
            [o.reshape(1, -1, 3).astype(np.float64) for o in objects],
            [i.reshape(1, -1, 2).astype(np.float64) for i in images], size,
            np.zeros((3, 3)), np.zeros(4),
            flags=cv2.CALIB_RECOMPUTE_EXTRINSIC | cv2.CALIB_FIX_SKEW)
        return CameraModel(size[0], size[1], np.asarray(k, dtype=np.float64), "equidistant",
                           np.asarray(d, dtype=np.float64).reshape(-1)[:4])
    rational = truth.distortion_model == "rational_polynomial"
    _rms, k, d, _r, _t = cv2.calibrateCamera(
        objects, images, size, None, None, flags=cv2.CALIB_RATIONAL_MODEL if rational else 0)
    return CameraModel(size[0], size[1], np.asarray(k, dtype=np.float64),
                       truth.distortion_model,
                       np.asarray(d, dtype=np.float64).reshape(-1)[:8 if rational else 5])


def recording(case: ScriptCase, seed: int, seconds: float, cache: Path) -> Path:
    """The case's analytic log for ``seed``, rendered into ``cache`` unless already there."""
    path = cache / f"{case.name}_{seed}_{seconds:g}s.mcap"
    if not path.exists():
        cache.mkdir(parents=True, exist_ok=True)
        partial = path.with_suffix(".partial.mcap")
        record_analytic(case.scenario_of(seed, seconds), partial, wave=case.wave)
        partial.rename(path)
    return path


def one_seed(case: ScriptCase, seed: int, path: Path, tmp: Path) -> Outcome:
    """camlog (its flags for the case) and the script on one log."""
    run = calibrate(path, case.flags, tmp / "out", report=False)
    (camera,) = run.cameras
    assert camera.truth is not None, "the log has no ground truth"
    truth = camera.truth.model()
    mine = max_difference_px(camera.model, truth)
    u = run.summary.cameras[0].uncertainty
    assert u is not None
    outcome = Outcome(mine, None, u.rays_worst_px, u.worst_px)
    views = script_views(path, case, seed)
    outcome.script_views = len(views)
    try:
        outcome.script_px = max_difference_px(script_model(views, truth), truth)
    except cv2.error as err:
        outcome.notes.append(f"script failed: {str(err).strip().splitlines()[-1]}")
    return outcome


def summary_lines(name: str, outcomes: list[Outcome]) -> list[str]:
    """The medians and counts of one case."""
    scripted = [o for o in outcomes if o.script_px is not None]
    wins = sum(o.camlog_px <= o.script_px for o in scripted if o.script_px is not None)
    median = statistics.median
    line = (f"{name}: {len(outcomes)} seeds; max projection px median camlog "
            f"{median(o.camlog_px for o in outcomes):.4f}")
    if scripted:
        line += (f", script {median(o.script_px for o in scripted if o.script_px is not None):.4f}"
                 f" ({len(outcomes) - len(scripted)} failed); camlog at or below the script at "
                 f"{wins} of {len(scripted)}")
    ratios = [o.ratio for o in outcomes]
    return [line, f"  stated worst σ median rays {median(o.rays_sigma_px for o in outcomes):.4f}, "
                  f"working range {median(o.range_sigma_px for o in outcomes):.4f} px; real error "
                  f"/ worst σ median {median(ratios):.2f}, worst {max(ratios):.2f}"]


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default=",".join(CASE_NAMES),
                        help=f"comma-separated, from {', '.join(CASE_NAMES)}")
    parser.add_argument("--seeds", type=int, default=20, help="seeds per case (default 20)")
    parser.add_argument("--first-seed", type=int, default=0, help="first seed (default 0)")
    parser.add_argument("--seconds", type=float, default=20.0,
                        help="seconds per log at 30 Hz (default 20)")
    parser.add_argument("--cache", type=Path, default=DEFAULT_CACHE,
                        help=f"logs are kept and reused here (default {DEFAULT_CACHE})")
    args = parser.parse_args(argv)
    unknown = sorted(set(args.cases.split(",")) - set(CASE_NAMES))
    if unknown:
        parser.error(f"unknown cases {', '.join(unknown)} (known: {', '.join(CASE_NAMES)})")
    if args.seeds < 1 or args.seconds <= 0:
        parser.error("--seeds and --seconds must be positive")
    results: dict[str, list[Outcome]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            for case in (c for c in CASES if c.name in args.cases.split(",")):
                path = recording(case, seed, args.seconds, args.cache)
                try:
                    outcome = one_seed(case, seed, path, Path(tmp))
                except CalibrationError as err:
                    print(f"{case.name} seed {seed}: camlog failed: {err}", flush=True)
                    continue
                results.setdefault(case.name, []).append(outcome)
                script = "failed" if outcome.script_px is None else f"{outcome.script_px:.4f}"
                print(f"{case.name} seed {seed}: camlog {outcome.camlog_px:.4f} px "
                      f"(worst σ rays {outcome.rays_sigma_px:.4f}, range "
                      f"{outcome.range_sigma_px:.4f}: {outcome.ratio:.2f}σ), script {script} "
                      f"({outcome.script_views} views) {' '.join(outcome.notes)}", flush=True)
    for name, outcomes in results.items():
        print("\n".join(summary_lines(name, outcomes)))


if __name__ == "__main__":
    main()

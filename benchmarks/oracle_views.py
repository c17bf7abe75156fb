"""What a log's views allow: each case solved again with perfect corners plus noise.

For every case of :mod:`.calibrate_speed` (its kept recordings: ``--logs DIR``) and seed,
camlog calibrates the log as it always does up to its first solve; then the corners of every
view are replaced by the truth (the board's points through the true pose and the true model;
a circle grid's circles: the centroids of their discs' images, which the detector measures)
plus independent Gaussian noise of the corner noise that first solve measured on that log,
and the problem is solved again — ``--draws`` times, with new noise. What such an ideal
detector, as noisy as camlog's, reaches from the same views bounds what any detector can
reach from them: a target the ideal corners miss at a seed is not within that seed's views.

Printed per seed: the figures of each draw (as :mod:`.calibrate_speed` prints them); per case,
the share of the draws that meet each target of the accuracy table.

    python -m benchmarks.oracle_views --logs DIR [--cases heldout,stereo,charuco] [--seeds 3]
        [--draws 4]
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np

from camlog.calibrate.flow import MeasureAgain
from camlog.calibrate.instants import ViewsOfRig
from camlog.calibrate.truth import true_rig
from camlog.calibrate.views import CameraViews
from processors.calibration.board import Board
from processors.calibration.discs import view_centroids
from processors.calibration.joint import JointResult
from replay.records import Scenario

from .calibrate_speed import (
    CASE_NAMES,
    CASES,
    Case,
    add_kept_logs_arguments,
    calibrate,
    kept_cases,
    row,
    run_board,
)
from .calibration_noise import log_scenario
from .calibration_truth import Accuracy, camlog_accuracy

#: the accuracy table's targets: figure -> (limit, the cases it applies to; None: every case)
TARGETS: dict[str, tuple[float, set[str] | None]] = {
    "fx, fy 0.02 %": (0.02, None),
    "principal point 0.2 px": (0.2, None),
    "max difference 0.2 px": (0.2, None),
    "max difference 0.07 px": (0.07, {"fisheye", "moving_blur"}),
    "rotation 0.02°": (0.02, {"stereo", "stereo_unsynced", "stereo_heldout"}),
    "baseline 0.02 %": (0.02, {"stereo", "stereo_unsynced", "stereo_heldout"}),
}


def ideal_corners(scenario: Scenario, board: Board, rng: np.random.Generator
                  ) -> tuple[list[float], MeasureAgain]:
    """A ``measure_again`` for :func:`camlog.calibrate.flow.calibrate_log` that gives every
    view its true corners plus Gaussian noise of the first solve's sigma (recorded in the
    returned list)."""
    sigmas: list[float] = []
    diameters = [t.diameter_m for t in scenario.targets if t.diameter_m is not None]
    radius_m = diameters[0] / 2 if diameters else 0.0

    def measure(cameras: list[CameraViews], rig: ViewsOfRig, joint: JointResult
                ) -> ViewsOfRig:
        truth = [scenario.camera_for(c.source.namespace,
                                     c.log_info.frame_id if c.log_info else None)
                 for c in cameras]
        true = true_rig(rig, cameras, truth, board=board, scenario=scenario)
        if true is None or any(t is None for t in truth):
            raise SystemExit("oracle_views: the log has no simulator truth for its cameras "
                             "and board (record it with python -m benchmarks.calibrate_speed)")
        sigmas.append(joint.sigma_px)
        points = board.points_in_board()
        views = []
        for view in rig.views:
            if view.instant not in true.reference_from_board:
                views.append(view)
                continue
            pose = true.camera_from_reference[view.camera] \
                @ true.reference_from_board[view.instant]
            ids = view.point_ids if view.point_ids is not None else np.arange(len(points))
            model = truth[view.camera].model()  # type: ignore[union-attr]
            if board.circle_grid:  # what the detector sees: the centroid of each disc's image
                true_px = view_centroids(model, pose, points[ids], radius_m=radius_m)[1]
            else:
                true_px = model.project(points[ids] @ pose[:3, :3].T + pose[:3, 3])
            noisy = true_px + rng.normal(0.0, joint.sigma_px, true_px.shape)
            views.append(dataclasses.replace(view, corners_px=noisy))
        return ViewsOfRig(views, rig.frames_of, rig.pairs, rig.candidates,
                          rig.frame_scatter_px)
    return sigmas, measure


def figures(a: Accuracy) -> dict[str, float]:
    """The targets' figures of one result."""
    out = {"fx, fy 0.02 %": abs(a.focal_percent),
           "principal point 0.2 px": max(abs(a.cx_px), abs(a.cy_px)),
           "max difference 0.2 px": max(a.max_difference_px),
           "max difference 0.07 px": max(a.max_difference_px)}
    if a.rotation_deg is not None and a.baseline_percent is not None:
        out["rotation 0.02°"] = abs(a.rotation_deg)
        out["baseline 0.02 %"] = abs(a.baseline_percent)
    return out


def oracle_case(case: Case, seeds: range, draws: int, logs: Path, tmp: Path) -> None:
    """Solve every seed's views with ideal corners ``draws`` times; print each draw and the
    share of the draws that meet each target."""
    met: dict[str, list[bool]] = defaultdict(list)
    for seed in seeds:
        path = logs / f"{case.scenario}_{seed}.mcap"
        scenario, board = log_scenario(path), run_board(case, path)
        for draw in range(draws):
            sigmas, measure = ideal_corners(scenario, board, np.random.default_rng(draw))
            run = calibrate(path, case.flags, tmp / "out", report=False, measure_again=measure)
            a = camlog_accuracy(run)
            print(row(f"{case.name} ideal", seed, a, f"draw {draw}, σ {sigmas[0]:.3f} px"),
                  flush=True)
            for name, value in figures(a).items():
                limit, cases = TARGETS[name]
                if cases is None or case.name in cases:
                    met[name].append(value <= limit)
    shares = "  ".join(f"{name} {np.mean(ok) * 100:.0f} %" for name, ok in met.items()
                       if not (name == "max difference 0.2 px" and "max difference 0.07 px"
                               in met))
    print(f"{case.name}: draws that meet each target: {shares}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_kept_logs_arguments(parser, ",".join(CASE_NAMES))
    parser.add_argument("--draws", type=int, default=4, help="noise draws per seed (default 4)")
    args = parser.parse_args()
    chosen = kept_cases(parser, args)
    print(f"{'case':20} {'seed':>4} {'fx,fy %':>8} {'cx px':>7} {'cy px':>7} "
          f"{'maxdiff px':>13} {'rot °':>7} {'base %':>8}")
    with tempfile.TemporaryDirectory() as tmp_name:
        for case in CASES:
            if case.name in chosen:
                oracle_case(case, range(args.seeds), args.draws, args.logs, Path(tmp_name))


if __name__ == "__main__":
    main()

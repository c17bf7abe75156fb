"""Where a calibration's error/sigma comes from: noise, its model, or the corner refinement.

For every case (``benchmarks.calibrate_speed`` flags) and seed of kept recordings, each camera
prints:

- its worst parameter's error/sigma with the covariance camlog states (``sigma^2 (J^T J)^-1``,
  the distortion prior at its stated width, ``Problem.stated_normal``) and with a covariance
  robust to noise that differs between corners and is shared within a board pose (the cluster
  sandwich ``S^-1 M S^-1``, through the solve's own equations, the prior at the solve's weight:
  ``S`` the information of the global unknowns with the board poses eliminated, ``M`` the sum
  over board poses of ``s s^T`` for each pose's score ``s = J_global^T r``, plus the share of
  ``sigma^2 S`` the fit removes from it);
- the fitted residuals' RMS per quintile of distance from the image centre;
- for chessboards, the refinement's own error: every used view rendered without noise at its
  true pose through the true model (:mod:`.ideal_board`), its corners refined as camlog
  refines them, and that error carried through the solve (``d = (J^T J)^-1 J^T b``): its RMS,
  the RMS of the part the residuals can show (``b - J d``) and, per parameter, the actual
  error/sigma against the one this error alone predicts. Agreement means the parameter errors
  are the refinement's, deterministic given the poses, not pixel noise. Corners whose
  refinement error lies beyond the solver's outlier threshold are left out, as the solver
  would leave them out.

    python -m benchmarks.calibration_noise --logs DIR [--cases fisheye,stereo] [--seeds 3]
"""

from __future__ import annotations

import argparse
import itertools
import tempfile
from pathlib import Path

import numpy as np

from camlog.calibrate.flow import CalibrationRun
from camlog.calibrate.truth import TrueRig, true_rig
from processors.calibration import bundle
from processors.calibration.board import Board
from processors.calibration.joint import Problem, threshold_sigma
from processors.calibration.lens import INTRINSIC_NAMES
from replay import open_reader
from replay.messages import F64
from replay.records import Scenario
from replay.topics import SCENARIO

from .calibrate_speed import CASES, add_kept_logs_arguments, calibrate, kept_cases, run_board
from .ideal_board import refinement_error_px


def sandwich_covariance(problem: Problem) -> F64:
    """Covariance ``(G, G)`` of the global unknowns robust to noise shared within a board pose."""
    layout, obs = problem.layout, problem.observations
    lin = bundle.linearize(problem.state, layout, obs, problem.points_in_board)
    poses, count = len(problem.state.board_rotation), layout.global_count
    scores, information = np.zeros((poses, count)), np.zeros((poses, count, count))
    residuals = lin.residuals.reshape(obs.view_count, -1)
    for camera, (views, block) in enumerate(zip(obs.camera_slices, lin.global_blocks,
                                                strict=True)):
        columns = layout.global_columns(camera)
        per_pose = np.zeros((poses, len(columns)))
        np.add.at(per_pose, obs.instant[views], np.einsum("vrg,vr->vg", block, residuals[views]))
        scores[:, columns] += per_pose
        gram = np.zeros((poses, len(columns), len(columns)))
        np.add.at(gram, obs.instant[views], np.einsum("vrg,vrh->vgh", block, block))
        information[np.ix_(np.arange(poses), columns, columns)] += gram
    normal = problem.normal
    information -= np.einsum("pgi,pij,phj->pgh", normal.c, np.linalg.inv(normal.b), normal.c)
    inverse = normal.global_covariance()
    removed = np.einsum("pgh,hk,pkl->gl", information, inverse, information)
    meat = scores.T @ scores + problem.sigma_px ** 2 * removed
    covariance: F64 = inverse @ meat @ inverse
    return covariance


def propagate(problem: Problem, shift_px: F64) -> tuple[F64, F64]:
    """The solution's change ``(G,)`` when every observation moves by ``shift_px``
    ``(V, N, 2)`` (rows of the problem, zero where unseen), and the part of the shift the
    residuals keep ``(V, N, 2)``."""
    layout, obs = problem.layout, problem.observations
    lin = bundle.linearize(problem.state, layout, obs, problem.points_in_board)
    shift = (shift_px * obs.mask[..., None] * obs.weight[:, None, None]).reshape(
        obs.view_count, -1)
    rhs_global = np.zeros((layout.global_count, 1))
    rhs_pose = np.zeros((len(problem.state.board_rotation), 6, 1))
    for camera, (views, block) in enumerate(zip(obs.camera_slices, lin.global_blocks,
                                                strict=True)):
        rhs_global[layout.global_columns(camera), 0] += np.einsum("vrg,vr->g", block,
                                                                  shift[views])
    np.add.at(rhs_pose[:, :, 0], obs.instant, np.einsum("vri,vr->vi", lin.pose, shift))
    d_global, d_pose = problem.normal.solve(rhs_global, rhs_pose)
    fitted = np.einsum("vri,vi->vr", lin.pose, d_pose[obs.instant, :, 0])
    for camera, (views, block) in enumerate(zip(obs.camera_slices, lin.global_blocks,
                                                strict=True)):
        fitted[views] += block @ d_global[layout.global_columns(camera), 0]
    kept = (shift - fitted).reshape(shift_px.shape) / obs.weight[:, None, None]
    return d_global[:, 0], kept * obs.mask[..., None]


def refinement_errors(run: CalibrationRun, truth: TrueRig, board: Board) -> F64:
    """The refinement's error on ideal images ``(V, N, 2)`` of every used view at its true
    pose (rows of the problem; zero for views without a true pose or refused)."""
    joint = run.solved.joint
    problem = joint.problem
    out = np.zeros_like(problem.observations.observed)
    models = [c.truth.model() for c in run.cameras if c.truth is not None]
    for row, index in enumerate(problem.order):
        view = joint.views[index]
        if index in joint.rejected or view.instant not in truth.reference_from_board:
            continue
        pose = truth.camera_from_reference[view.camera] @ truth.reference_from_board[view.instant]
        error = refinement_error_px(models[view.camera], pose, board)
        if error is not None:
            out[row] = error
    return out


def _rms_by_radius(run: CalibrationRun, camera: int) -> str:
    joint = run.solved.joint
    mine = [i for i, v in enumerate(joint.views) if v.camera == camera and i not in joint.rejected]
    corners = np.concatenate([joint.views[i].corners_px[joint.inliers[i]] for i in mine])
    residuals = np.concatenate([joint.residuals_px[i][joint.inliers[i]] for i in mine])
    width, height = run.cameras[camera].views.size
    radius = np.hypot(corners[:, 0] - width / 2, corners[:, 1] - height / 2)
    edges = np.quantile(radius, np.linspace(0.0, 1.0, 6))
    cells = []
    for lo, hi in itertools.pairwise(edges):
        inside = (radius >= lo) & (radius <= hi)
        cells.append(f"{lo:.0f}-{hi:.0f} px {np.sqrt(np.mean(residuals[inside] ** 2)):.4f}")
    return ", ".join(cells)


def analyse_run(name: str, seed: int, run: CalibrationRun, board: Board,
                scenario: Scenario) -> None:
    """Print the figures of one calibration."""
    problem = run.solved.joint.problem
    layout = problem.layout
    plain, robust = problem.global_covariance(), sandwich_covariance(problem)
    predicted: F64 | None = None
    if board.pattern == "chessboard":
        truth = true_rig(run.solved.rig, [c.views for c in run.cameras],
                         [c.truth for c in run.cameras], board=board, scenario=scenario)
        assert truth is not None, "the log has no true board poses"
        error = refinement_errors(run, truth, board)
        # the solver would leave such corners out as outliers
        limit = threshold_sigma(int(problem.observations.mask.sum())) * problem.sigma_px
        outliers = np.linalg.norm(error, axis=2) > limit
        error[outliers] = 0.0
        predicted, kept = propagate(problem, error)
        seen = problem.observations.mask & (np.abs(error).sum(axis=2) > 0)
        mahalanobis = float(predicted @ np.linalg.solve(plain, predicted))
        print(f"{name} seed {seed}: refinement error on ideal images RMS "
              f"{np.sqrt(np.mean(error[seen] ** 2)):.4f} px, of which the residuals keep "
              f"{np.sqrt(np.mean(kept[seen] ** 2)):.4f} px (noise σ {problem.sigma_px:.4f} px);"
              f" the solution shift it predicts: {mahalanobis:.1f} σ² over "
              f"{layout.global_count} unknowns ({int(outliers.sum())} corners beyond the "
              f"outlier threshold left out)", flush=True)
    for camera, setup in enumerate(layout.setups):
        columns, basis = layout.intrinsic_columns[camera], layout.bases[camera]
        names = INTRINSIC_NAMES[setup.distortion_model]
        table = run.summary.cameras[camera].parameters
        stds = [np.sqrt(np.maximum(np.diag(basis @ c[np.ix_(columns, columns)] @ basis.T),
                                   0.0)) for c in (plain, robust)]
        shift = basis @ predicted[columns] if predicted is not None else None
        figures = []
        for k, n in enumerate(names):
            if stds[0][k] > 0 and table[n].error is not None:
                error_px = float(table[n].error or 0.0)
                figures.append((abs(error_px) / stds[0][k], n, error_px / stds[0][k],
                                error_px / stds[1][k],
                                None if shift is None else shift[k] / stds[0][k]))
        worst = max(figures)
        print(f"{name} seed {seed} camera {camera}: worst {worst[1]} error/σ {worst[2]:+.2f} "
              f"(robust covariance {worst[3]:+.2f}, worst robust "
              f"{max(abs(f[3]) for f in figures):.2f}); residual RMS by radius: "
              f"{_rms_by_radius(run, camera)}", flush=True)
        if shift is not None:
            print("  error/σ actual / predicted by the refinement error: " + ", ".join(
                f"{f[1]} {f[2]:+.2f}/{f[4]:+.2f}" for f in figures), flush=True)


def log_scenario(path: Path) -> Scenario:
    """The simulator's scenario record of a recording."""
    with open_reader(path) as reader:
        for raw in reader.raw_messages([SCENARIO]):
            return Scenario.from_message(reader.decode(raw))
    raise SystemExit(f"{path} has no {SCENARIO} record (not a simulated log)")


def analyse(name: str, seeds: range, logs: Path) -> None:
    """Calibrate one case at every seed and print its figures."""
    case = next(c for c in CASES if c.name == name)
    for seed in seeds:
        path = logs / f"{case.scenario}_{seed}.mcap"
        with tempfile.TemporaryDirectory() as tmp:
            run = calibrate(path, case.flags, Path(tmp) / "out", report=False)
        analyse_run(name, seed, run, run_board(case, path), log_scenario(path))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_kept_logs_arguments(parser, "fisheye,stereo")
    args = parser.parse_args()
    for name in kept_cases(parser, args):
        analyse(name, range(args.seeds), args.logs)


if __name__ == "__main__":
    main()

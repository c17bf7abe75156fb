"""The noise analysis: the ideal board image, the propagation of a shift, the robust covariance."""

from __future__ import annotations

import dataclasses

import numpy as np

from benchmarks.calibration_noise import propagate, sandwich_covariance
from benchmarks.ideal_board import DARK, ideal_image, refinement_error_px
from processors.calibration import bundle, normal
from processors.calibration.joint import BoardView, calibrate_cameras
from processors.calibration.options import CalibrationOptions
from tests.processors.calibration.synthetic import (
    BOARD,
    H,
    W,
    pinhole_model,
    pose,
    project,
    random_poses,
    true_model,
    views,
)

POINTS = BOARD.points_in_board()
ALL = np.arange(BOARD.corner_count)
POSES = random_poses(np.random.default_rng(5), 15, [true_model()])


def solve(noise_px: float, seed: int) -> object:
    observed = [BoardView(0, i, ALL, c) for i, c in
                enumerate(views(true_model(), POSES, noise_px, seed=seed))]
    return calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions())


def test_ideal_image_shows_the_squares_where_the_camera_sees_them() -> None:
    camera_from_board = pose(np.array([0.3, -0.2, 0.1]), np.array([-0.08, -0.05, 0.5]))
    image = ideal_image(pinhole_model(), camera_from_board, BOARD)
    # the centre of the square between the first four corners: the first square is dark
    centre = (POINTS[0] + POINTS[BOARD.cols + 1]) / 2
    uv = project(pinhole_model(), camera_from_board, BOARD)
    mid = pinhole_model().project((centre @ camera_from_board[:3, :3].T
                                   + camera_from_board[:3, 3])[None])[0]
    assert image[round(mid[1]), round(mid[0])] == DARK
    assert image.shape == (H, W)
    error = refinement_error_px(pinhole_model(), camera_from_board, BOARD)
    assert error is not None and error.shape == uv.shape
    assert float(np.sqrt(np.mean(error ** 2))) < 0.1  # in board order, near the truth


def test_propagate_predicts_the_change_of_a_new_solve() -> None:
    result = solve(0.0, 0)
    problem = result.problem  # type: ignore[attr-defined]
    obs = problem.observations
    # small enough for the linear model: the radial prior's pull makes the solve bend (at
    # 0.02 px the intrinsics' change departs 3 % from it, at 0.002 px 0.3 %)
    shift = np.random.default_rng(1).normal(0.0, 0.002, obs.observed.shape)
    predicted, kept = propagate(problem, shift)
    moved = dataclasses.replace(obs, observed=obs.observed + shift)
    again = normal.refine(problem.state, problem.layout, moved, POINTS)
    change = np.concatenate(again.state.intrinsics) - np.concatenate(problem.state.intrinsics)
    columns = problem.layout.intrinsic_columns[0]
    expected = problem.layout.bases[0] @ predicted[columns]
    np.testing.assert_allclose(change, expected, rtol=0.02, atol=1e-3 * np.abs(change).max())
    # the residuals' change: at the solution before the shift the prior leaves some
    before = -bundle.linearize(problem.state, problem.layout, obs, POINTS,
                               jacobian=False).residuals
    residuals = -bundle.linearize(again.state, problem.layout, moved, POINTS,
                                  jacobian=False).residuals
    np.testing.assert_allclose(kept, residuals - before, atol=1e-5)


def test_robust_covariance_agrees_with_the_plain_one_for_independent_noise() -> None:
    result = solve(0.1, 3)
    problem = result.problem  # type: ignore[attr-defined]
    ratio = np.sqrt(np.diag(sandwich_covariance(problem))
                    / np.diag(problem.global_covariance()))
    assert np.all((ratio > 0.6) & (ratio < 1.5)), ratio

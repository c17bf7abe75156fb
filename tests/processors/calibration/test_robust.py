"""The robust solve's second look at views it left out as not the board."""

from __future__ import annotations

import numpy as np

from processors.calibration import bundle
from processors.calibration.joint import BoardView, calibrate_cameras
from processors.calibration.lens import intrinsics_of
from processors.calibration.options import CalibrationOptions
from processors.calibration.robust import BoardViews, InlierSelection, Problem, robust_solve

from .synthetic import BOARD, K_TRUE, H, W, pose, project, true_model

NOISE_PX = 0.05
POINTS = BOARD.points_in_board()
ALL = np.arange(BOARD.corner_count)
CENTRED = np.eye(4)
CENTRED[:3, 3] = -np.array([(BOARD.cols - 1) * BOARD.square_m,
                            (BOARD.rows - 1) * BOARD.square_m, 0.0]) / 2


def board_at(rvec: list[float], xyz: list[float]) -> np.ndarray:
    """``camera_from_board`` of the board's centre at ``xyz`` (m), turned by ``rvec``."""
    return pose(np.array(rvec), np.array(xyz)) @ CENTRED


def mono_views(seed: int, count: int) -> tuple[list[np.ndarray], list[BoardView]]:
    """``count`` board poses around the middle of the image and their noisy views."""
    rng = np.random.default_rng(seed)
    poses = [board_at([*rng.uniform(-0.5, 0.5, 2), rng.uniform(-np.pi, np.pi)],
                      [*rng.uniform(-0.1, 0.1, 2), rng.uniform(0.45, 0.7)])
             for _ in range(count)]
    views = [BoardView(0, i, ALL, project(true_model(), p)
                       + rng.normal(0, NOISE_PX, (len(ALL), 2))) for i, p in enumerate(poses)]
    return poses, views


def solve_from(poses: list[np.ndarray], views: list[BoardView]) -> tuple[Problem, InlierSelection]:
    """The robust solve started at the true lens and the board poses ``poses``."""
    state = bundle.RigState([intrinsics_of(true_model())], np.eye(3)[None], np.zeros((1, 3)),
                            np.stack([p[:3, :3] for p in poses]),
                            np.stack([p[:3, 3] for p in poses]))
    problem, evidence, _rounds = robust_solve(BoardViews(POINTS, views, [(W, H)]),
                                              [CalibrationOptions()], state=state)
    return problem, evidence


def test_a_view_whose_seed_pose_was_wrong_is_taken_back_in() -> None:
    # PnP through a seed lens can pick the wrong one of a planar board's two poses: the
    # view's corners are then all far from where the seed puts them, it is left out of the
    # first solve, and only a fresh pose at the solution shows it was the board all along
    poses, views = mono_views(2, 15)
    wrong = poses[5] @ np.linalg.inv(CENTRED) @ pose(np.array([0.6, 0.0, 0.0]), np.zeros(3)) \
        @ CENTRED
    assert np.median(np.linalg.norm(project(true_model(), wrong) - views[5].corners_px,
                                    axis=1)) > 5

    problem, evidence = solve_from([wrong if i == 5 else p for i, p in enumerate(poses)], views)

    assert evidence.rejected == {}
    assert problem.sigma_px < 1.3 * NOISE_PX
    back = problem.state.reference_from_board(5)
    assert np.linalg.norm(back[:3, 3] - poses[5][:3, 3]) < 1e-3
    assert abs(problem.state.intrinsics[0][0] - K_TRUE[0, 0]) < 1.0


def test_a_view_with_one_corner_where_its_seed_pose_puts_it_sits_the_first_solve_out() -> None:
    # the seed pose turned about the board's first corner: that corner alone lands where it is
    # seen, and one corner cannot hold a pose (its block of the normal equations is singular)
    poses, views = mono_views(3, 12)
    turned = poses[7] @ pose(np.array([0.0, 0.0, 0.5]), np.zeros(3))
    off_px = np.linalg.norm(project(true_model(), turned) - views[7].corners_px, axis=1)
    assert off_px[0] < 0.3 and np.sort(off_px)[1] > 10

    problem, evidence = solve_from([turned if i == 7 else p for i, p in enumerate(poses)],
                                   views)

    assert evidence.rejected == {}
    assert problem.sigma_px < 1.3 * NOISE_PX


def test_a_pair_showing_two_poses_stays_out_and_changes_nothing() -> None:
    rng = np.random.default_rng(4)
    right_from_left = pose(np.array([0.0, 0.02, 0.0]), np.array([-0.1, 0.0, 0.0]))
    poses = [board_at([*rng.uniform(-0.4, 0.4, 2), rng.uniform(-np.pi, np.pi)],
                      [*rng.uniform(-0.05, 0.05, 2), rng.uniform(0.5, 0.7)]) for _ in range(15)]
    model = true_model()
    views = [BoardView(camera, i, ALL, project(model, placement @ p)
                       + rng.normal(0, NOISE_PX, (len(ALL), 2)))
             for camera, placement in enumerate([np.eye(4), right_from_left])
             for i, p in enumerate(poses)]
    # the right camera's frame of instant 3 shows the board somewhere else (a frame from
    # another moment paired with it): a board, but not at the left frame's pose
    elsewhere = right_from_left @ board_at([0.3, 0.2, 1.0], [0.04, -0.03, 0.55])
    mismatched = len(poses) + 3
    views[mismatched] = BoardView(1, 3, ALL, project(model, elsewhere))
    without = [v for i, v in enumerate(views) if i != mismatched]

    result = calibrate_cameras(POINTS, views, [(W, H)] * 2, CalibrationOptions())
    alone = calibrate_cameras(POINTS, without, [(W, H)] * 2, CalibrationOptions())

    assert list(result.rejected) == [mismatched]
    assert "outlier threshold" in result.rejected[mismatched]
    for got, reference in zip(result.models, alone.models, strict=True):
        np.testing.assert_allclose(got.k, reference.k, atol=1e-4)
        np.testing.assert_allclose(got.d, reference.d, atol=1e-6)

"""The joint least-squares problem: Jacobian against finite differences, exact convergence."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration import bundle, prior, rotation
from processors.calibration.lens import INTRINSIC_NAMES, intrinsics_of
from processors.calibration.normal import linearized_equations, normal_equations, refine
from replay.camera import CameraModel

from .synthetic import BOARD, H, W, pose, random_poses, true_model, views

RIGHT_FROM_LEFT = pose(np.array([0.01, 0.03, -0.02]), np.array([-0.12, 0.004, 0.01]))
FISHEYE = CameraModel(W, H, np.array([[260.0, 0, 318], [0, 262, 242], [0, 0, 1]]), "equidistant",
                      np.array([0.03, -0.01, 0.004, -0.001]))


def rig_problem(models: list[CameraModel], count: int, noise_px: float, seed: int, *,
                warp: bool = False
                ) -> tuple[bundle.RigState, bundle.Layout, bundle.Observations]:
    """Two cameras seeing ``count`` board poses; the true state and the observations (with
    ``warp`` the board's warp is estimated, at a state where the board bows)."""
    placements = [np.eye(4), RIGHT_FROM_LEFT]
    poses = random_poses(np.random.default_rng(seed), count, models,
                         camera_from_reference=placements)
    observed = [views(m, [p @ b for b in poses], noise_px, seed + c)
                for c, (m, p) in enumerate(zip(models, placements, strict=True))]
    state = bundle.RigState(
        [intrinsics_of(m) for m in models],
        np.stack([p[:3, :3] for p in placements]), np.stack([p[:3, 3] for p in placements]),
        np.stack([b[:3, :3] for b in poses]), np.stack([b[:3, 3] for b in poses]))
    setups = [bundle.CameraSetup(m.distortion_model, (W, H),
                                 tuple(n for n in INTRINSIC_NAMES[m.distortion_model]
                                       if n != "k3"), tie_aspect=c == 1)
              for c, m in enumerate(models)]
    obs = bundle.Observations(
        camera=np.repeat([0, 1], count), instant=np.tile(np.arange(count), 2),
        observed=np.concatenate([np.stack(o) for o in observed]),
        mask=np.ones((2 * count, BOARD.corner_count), bool), weight=np.full(2 * count, 1.5))
    if warp:
        state.board_warp_m = np.array([0.002, -0.0015])
    return state, bundle.Layout.of(setups, state, corners=obs.corners(len(setups)), warp=warp), obs


@pytest.mark.parametrize(("second", "warp"), [("plumb_bob", False), ("equidistant", False),
                                              ("plumb_bob", True)])
def test_jacobian_matches_finite_differences(second: str, warp: bool) -> None:
    models = [true_model(), true_model() if second == "plumb_bob" else FISHEYE]
    state, layout, obs = rig_problem(models, 4, 0.1, seed=3, warp=warp)
    assert len(layout.warp_columns) == (2 if warp else 0)
    obs.mask[1, 5] = False  # a masked corner has no residual and no derivative
    points = BOARD.points_in_board()
    lin = bundle.linearize(state, layout, obs, points)
    assert np.all(lin.residuals[1, 5] == 0) and np.all(lin.pose[1, 10:12] == 0)
    pose_count = len(state.board_rotation)
    for column in range(layout.global_count + 6 * pose_count):
        d_global = np.zeros(layout.global_count)
        d_pose = np.zeros((pose_count, 6))
        step = 1e-6
        if column < layout.global_count:
            d_global[column] = step
        else:
            d_pose.reshape(-1)[column - layout.global_count] = step
        plus = bundle.linearize(layout.step(state, d_global, d_pose), layout, obs, points,
                                jacobian=False).residuals
        minus = bundle.linearize(layout.step(state, -d_global, -d_pose), layout, obs, points,
                                 jacobian=False).residuals
        numeric = ((plus - minus) / (2 * step)).reshape(obs.view_count, -1)
        analytic = np.zeros_like(numeric)
        if column < layout.global_count:
            for camera, views_ in enumerate(obs.camera_slices):
                columns = list(layout.global_columns(camera))
                if column in columns:
                    analytic[views_] = lin.global_blocks[camera][:, :, columns.index(column)]
        else:
            instant, k = divmod(column - layout.global_count, 6)
            rows = obs.instant == instant
            analytic[rows] = lin.pose[rows][:, :, k]
        np.testing.assert_allclose(analytic, numeric, rtol=1e-4, atol=2e-4)


def test_refine_converges_to_the_truth_without_noise(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(prior, "PRIOR_SHARE", 0.0)  # its pull moves the optimum by 1e-6
    truth, layout, obs = rig_problem([true_model(), true_model()], 12, 0.0, seed=4)
    seed = truth.copy()
    seed.intrinsics[0] = seed.intrinsics[0] * np.array([1.01, 1.01, 1, 1, 0.9, 1.1, 1, 1, 1]) \
        + np.array([0, 0, 2.0, -1.5, 0, 0, 0, 0, 0])
    seed.rig_rotation[1] = rotation.matrices(np.array([[0.002, -0.003, 0.001]]))[0] \
        @ seed.rig_rotation[1]
    seed.rig_translation[1] += [0.002, -0.001, 0.0]
    seed.board_translation += 0.003
    refined = refine(seed, layout, obs, BOARD.points_in_board())
    assert refined.costs[0] > 1.0 and refined.linearization.cost < 1e-16
    np.testing.assert_allclose(refined.state.intrinsics[0], truth.intrinsics[0], rtol=1e-9)
    np.testing.assert_allclose(refined.state.rig_translation, truth.rig_translation, atol=1e-11)
    np.testing.assert_allclose(refined.state.board_rotation, truth.board_rotation, atol=1e-10)


def test_normal_equations_are_the_jacobian_products() -> None:
    state, layout, obs = rig_problem([true_model(), FISHEYE], 5, 0.2, seed=5)
    lin = bundle.linearize(state, layout, obs, BOARD.points_in_board())
    normal = normal_equations(lin, layout, obs, 5)
    # the dense Jacobian, assembled from the blocks
    rows = lin.residuals.size
    dense = np.zeros((rows, layout.global_count + 30))
    per_view = 2 * BOARD.corner_count
    for camera, views_ in enumerate(obs.camera_slices):
        for v in range(views_.start, views_.stop):
            dense[v * per_view:(v + 1) * per_view, layout.global_columns(camera)] = \
                lin.global_blocks[camera][v - views_.start]
            at = layout.global_count + 6 * int(obs.instant[v])
            dense[v * per_view:(v + 1) * per_view, at:at + 6] = lin.pose[v]
    g = layout.global_count
    assert np.count_nonzero(layout.prior_px) == 2  # k1, k2 of the plumb_bob camera
    jtj = dense.T @ dense + np.diag(np.concatenate([layout.prior_px ** 2, np.zeros(30)]))
    np.testing.assert_allclose(normal.a, jtj[:g, :g], rtol=1e-10)
    np.testing.assert_allclose(normal.b[2], jtj[g + 12:g + 18, g + 12:g + 18], rtol=1e-10)
    np.testing.assert_allclose(normal.global_covariance(), np.linalg.inv(jtj)[:g, :g],
                               rtol=1e-6)
    rhs = np.random.default_rng(0).normal(size=(jtj.shape[0], 3))
    x_global, x_pose = normal.solve(rhs[:g], rhs[g:].reshape(5, 6, 3))
    np.testing.assert_allclose(np.vstack([x_global, x_pose.reshape(30, 3)]),
                               np.linalg.solve(jtj, rhs), rtol=1e-6, atol=1e-12)


def test_equations_summed_over_chunks_of_views_are_the_whole_problems(
        monkeypatch: pytest.MonkeyPatch) -> None:
    state, layout, obs = rig_problem([true_model(), FISHEYE], 7, 0.2, seed=6)
    points = BOARD.points_in_board()
    whole = bundle.linearize(state, layout, obs, points)
    expected = normal_equations(whole, layout, obs, 7)
    # 14 views in chunks of 3: one chunk holds views of both cameras, others of one only
    monkeypatch.setattr(bundle, "CHUNK_VIEWS", 3)
    lin, normal = linearized_equations(state, layout, obs, points, 7)
    np.testing.assert_allclose(lin.residuals, whole.residuals, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(bundle.linearize(state, layout, obs, points,
                                                jacobian=False).residuals, whole.residuals,
                               rtol=1e-12, atol=1e-15)
    for name in ("a", "c", "b", "g_global", "g_pose"):
        np.testing.assert_allclose(getattr(normal, name), getattr(expected, name), rtol=1e-10,
                                   atol=1e-9, err_msg=name)
    assert lin.cost == pytest.approx(whole.cost, rel=1e-12)


def test_a_point_that_does_not_project_counts_for_nothing_where_unseen() -> None:
    # the board turned and moved so that its first row of corners lies in the camera's focal
    # plane (1e-300 m in front: x / z overflows and they project to NaN) while the other rows
    # stand in front: the view sees only those
    state, layout, obs = rig_problem([true_model(), true_model()], 4, 0.0, seed=5)
    points = BOARD.points_in_board()
    camera_from_board = pose(np.array([1.0, 0.0, 0.0]), np.zeros(3))
    camera_from_board[:3, 3] = -camera_from_board[:3, :3] @ points[0] + [0.0, 0.0, 1e-300]
    in_camera = points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3]
    first_row = np.arange(BOARD.cols)
    assert (in_camera[BOARD.cols:, 2] > 0.02).all()
    state.board_rotation[0] = camera_from_board[:3, :3]
    state.board_translation[0] = camera_from_board[:3, 3]
    with np.errstate(all="ignore"):
        uv = true_model().project(in_camera)
        assert np.isnan(uv[first_row[1:]]).all() and np.isfinite(uv[BOARD.cols:]).all()
        obs.observed[0] = np.nan_to_num(uv)
        obs.mask[0, first_row] = False
        lin, normal = linearized_equations(state, layout, obs, points, len(state.board_rotation))
    assert np.isfinite(lin.residuals).all() and np.isfinite(lin.cost)
    assert np.isfinite(normal.a).all() and np.isfinite(normal.b).all()
    assert np.isfinite(normal.c).all() and np.isfinite(normal.g_global).all()
    assert np.all(lin.residuals[0, first_row] == 0)

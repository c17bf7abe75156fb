"""Projection uncertainty: the true error behaves as the predicted covariance says."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration import uncertainty
from processors.calibration.joint import BoardView, Problem, calibrate_cameras
from processors.calibration.lens import project
from processors.calibration.options import CalibrationOptions
from processors.calibration.validation import cross_validate

from .synthetic import BOARD, H, W, random_poses, true_model, views
from .test_joint import POINTS as RIG_POINTS
from .test_joint import RIGHT_FROM_LEFT, board_views
from .test_rig import FAR

POINTS = BOARD.points_in_board()
ALL = np.arange(BOARD.corner_count)
POSES = random_poses(np.random.default_rng(11), 20, [true_model()])
EXACT = views(true_model(), POSES, 0.0, seed=0)
TRUTH = dict(enumerate(POSES))


def solve(noise_px: float, seed: int) -> tuple[object, uncertainty.UncertaintyMap, np.ndarray]:
    rng = np.random.default_rng(seed)
    observed = [BoardView(0, i, ALL, c + rng.normal(0.0, noise_px, c.shape))
                for i, c in enumerate(EXACT)]
    result = calibrate_cameras(POINTS, observed, [(W, H)],
                               CalibrationOptions(tangential="estimate"))
    umap = uncertainty.projection_uncertainty(result.problem, 0, step_px=80)
    error = uncertainty.error_against(result.problem, 0, true_model(),
                                      true_camera_from_reference=np.eye(4),
                                      true_reference_from_board=TRUTH, range_m=umap.range_m,
                                      pixels=umap.pixels)
    return result, umap, error


@pytest.mark.slow
def test_true_errors_follow_the_predicted_covariance() -> None:
    """Mahalanobis distance squared of the true error averages 2 (two dimensions)."""
    squared = []
    for seed in range(12):
        _result, umap, error = solve(0.05, 300 + seed)
        squared.append(np.einsum("rck,rckl,rcl->rc", error, np.linalg.inv(umap.covariance),
                                 error))
    mean = float(np.mean(squared))
    assert 1.4 < mean < 2.8, mean


@pytest.mark.slow
def test_uncertainty_and_cross_validation_match_the_true_error_over_noise_draws() -> None:
    """Over draws, the true error of rays is as large as the uncertainty says (1 sigma in the
    worst direction: the 2-D error's RMS is 1 to sqrt(2) times it) and as the cross-validation
    says (RMS over the image and the draws)."""
    over_sigma, true_squared, cross_squared = [], [], []
    for seed in range(12):
        result, _u, _e = solve(0.1, 700 + seed)
        far = uncertainty.projection_uncertainty(result.problem, 0, range_m=1e4, step_px=80)
        error = np.linalg.norm(uncertainty.error_against(
            result.problem, 0, true_model(), true_camera_from_reference=np.eye(4),
            true_reference_from_board=TRUTH, range_m=far.range_m, pixels=far.pixels), axis=2)
        over_sigma.append(error / far.sigma_px)
        found = cross_validate(POINTS, result.views, [(W, H)], result.options,
                               range_m=far.range_m, step_px=80)
        assert found is not None
        true_squared.append(np.mean(error ** 2))
        cross_squared.append(np.mean(found[0].error_px ** 2))
    assert 0.6 < np.sqrt(np.mean(np.square(over_sigma))) < 1.6
    assert 0.6 < np.sqrt(np.sum(true_squared) / np.sum(cross_squared)) < 1.6


def test_map_covers_the_image_and_scales_with_the_noise() -> None:
    _r, quiet, _e = solve(0.05, 1)
    _r, loud, _e = solve(0.1, 1)
    assert quiet.pixels.shape == (7, 9, 2)
    np.testing.assert_allclose(quiet.pixels[0, 0], [0, 0])
    np.testing.assert_allclose(quiet.pixels[-1, -1], [W - 1, H - 1])
    assert np.isfinite(quiet.sigma_px).all()
    assert loud.median_px / quiet.median_px == pytest.approx(2.0, rel=0.1)
    # least certain at the image corners, where no board was seen
    assert quiet.sigma_px[0, 0] > quiet.median_px and quiet.worst_px >= quiet.sigma_px[0, 0]
    assert 0.2 < quiet.range_m < 1.0


def test_working_range_is_where_the_boards_were() -> None:
    result, _u, _e = solve(0.05, 2)
    centre = POINTS.mean(axis=0)
    distances = [np.linalg.norm(p[:3, :3] @ centre + p[:3, 3]) for p in POSES]
    assert uncertainty.working_range_m(result.problem) == pytest.approx(np.median(distances),
                                                                       rel=1e-3)


def test_what_the_model_leaves_out_is_added_in_every_direction() -> None:
    result, umap, _e = solve(0.05, 2)
    assert result is not None
    difference = np.full(umap.sigma_px.shape, 0.1)
    difference[0, 0] = np.nan  # no figure there: nothing added
    wider = uncertainty.with_left_out(umap, difference)
    np.testing.assert_allclose(wider.sigma_px[1:], np.hypot(umap.sigma_px[1:], 0.1))
    assert wider.sigma_px[0, 0] == umap.sigma_px[0, 0]
    # the smaller direction gains as much as the larger one
    smallest = np.linalg.eigvalsh(wider.covariance[1:])[..., 0]
    np.testing.assert_allclose(smallest, np.linalg.eigvalsh(umap.covariance[1:])[..., 0] + 0.01)


def _covariance_pose_by_pose(problem: Problem, camera: int, pixels: np.ndarray,
                             range_m: float) -> np.ndarray:
    """``sigma^2 g (J^T J)^-1 g^T`` with every pose's derivative ``[lever_p x e; e]`` written
    out and solved through the normal equations: the definition the map shortens."""
    state, layout, normal = problem.state, problem.layout, problem.stated_normal
    setup = layout.setups[camera]
    flat = pixels.reshape(-1, 2)
    in_camera, in_reference, r_c = uncertainty._points_in_reference(problem, camera, flat,
                                                                     range_m)
    _uv, d_point, d_intrinsics = project(setup.distortion_model, state.intrinsics[camera],
                                         in_camera)
    m, seen = len(flat), np.flatnonzero(normal.seen)
    g_global = np.zeros((layout.global_count, m, 2))
    g_global[layout.intrinsic_columns[camera]] = np.transpose(
        np.einsum("mki,ic->mkc", d_intrinsics, layout.bases[camera]), (2, 0, 1))
    if camera:
        rig = np.concatenate([np.cross((in_reference @ r_c.T)[:, None, :], d_point), d_point],
                             axis=2)
        g_global[layout.rig_columns[camera]] = np.transpose(rig, (2, 0, 1))
    e = d_point @ r_c / len(seen)
    g_pose = np.zeros((len(state.board_rotation), 6, m, 2))
    for p in seen:
        lever = in_reference - state.board_translation[p]
        g_pose[p, :3] = np.transpose(np.cross(lever[:, None, :], e), (2, 0, 1))
        g_pose[p, 3:] = np.transpose(e, (2, 0, 1))
    x_global, x_pose = normal.solve(g_global.reshape(-1, 2 * m),
                                    g_pose.reshape(len(g_pose), 6, 2 * m))
    blocks = np.einsum("gmk,gml->mkl", g_global, x_global.reshape(-1, m, 2)) \
        + np.einsum("pimk,piml->mkl", g_pose, x_pose.reshape(len(g_pose), 6, m, 2))
    return np.asarray(problem.sigma_px ** 2 * blocks.reshape(*pixels.shape[:2], 2, 2))


@pytest.mark.parametrize("camera", [0, 1, 2])
def test_map_is_the_covariance_written_out_pose_by_pose(camera: int) -> None:
    """The per-pixel covariance, poses summed through their moments, equals the one from
    every pose's own derivative, for the reference camera and for cameras placed in a rig
    (with a warped board among the global unknowns)."""
    observed, _ = board_views([true_model()] * 3, 12, seed=8,
                              placements=[np.eye(4), RIGHT_FROM_LEFT, FAR])
    result = calibrate_cameras(RIG_POINTS, observed, [(W, H)] * 3,
                               CalibrationOptions(board_warp="on"))
    umap = uncertainty.projection_uncertainty(result.problem, camera, step_px=80)
    expected = _covariance_pose_by_pose(result.problem, camera, umap.pixels, umap.range_m)
    np.testing.assert_allclose(umap.covariance, expected, rtol=1e-9,
                               atol=1e-12 * np.abs(expected).max())

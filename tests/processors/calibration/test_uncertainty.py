"""Projection uncertainty: the true error behaves as the predicted covariance says."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration import uncertainty
from processors.calibration.joint import BoardView, calibrate_cameras
from processors.calibration.options import CalibrationOptions

from .synthetic import BOARD, H, W, random_poses, true_model, views

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


def test_true_errors_follow_the_predicted_covariance() -> None:
    """Mahalanobis distance squared of the true error averages 2 (two dimensions)."""
    squared = []
    for seed in range(12):
        _result, umap, error = solve(0.05, 300 + seed)
        squared.append(np.einsum("rck,rckl,rcl->rc", error, np.linalg.inv(umap.covariance),
                                 error))
    mean = float(np.mean(squared))
    assert 1.4 < mean < 2.8, mean


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

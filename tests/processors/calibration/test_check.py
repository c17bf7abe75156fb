"""camera_calibration's checks of a calibration: row straightness and reprojection."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.check import linearity_error, reprojection_rms

from .synthetic import BOARD, D_TRUE, pinhole_model, random_poses, true_model, views


@pytest.fixture(scope="module")
def poses() -> list[np.ndarray]:
    return random_poses(np.random.default_rng(5), 6, [true_model()])


def test_perfect_views_of_the_right_model_are_straight_and_reproject(
    poses: list[np.ndarray]
) -> None:
    for model in (pinhole_model(), true_model()):
        for corners in views(model, poses, 0.0, seed=0):
            assert linearity_error(corners, model, BOARD) < 1e-4
            assert reprojection_rms(corners, model, BOARD) < 1e-4


def test_the_wrong_distortion_bends_the_rows(poses: list[np.ndarray]) -> None:
    """Views of a k1 = -0.2 lens checked with a pinhole model: rows stay curved."""
    distorted = views(true_model(), poses, 0.0, seed=0)
    wrong = [linearity_error(c, pinhole_model(), BOARD) for c in distorted]
    right = [linearity_error(c, true_model(), BOARD) for c in distorted]
    assert min(wrong) > 0.1 and max(right) < 1e-4
    assert np.mean([reprojection_rms(c, pinhole_model(), BOARD) for c in distorted]) > 0.1
    # half the distortion bends them about half as much
    half = true_model(d=D_TRUE / 2)
    halfway = [linearity_error(c, half, BOARD) for c in distorted]
    assert np.median(np.array(halfway) / np.array(wrong)) == pytest.approx(0.5, abs=0.1)


def test_noise_sets_the_floor(poses: list[np.ndarray]) -> None:
    """Per-corner noise sigma leaves straightness and reprojection errors of order sigma."""
    noisy = views(true_model(), poses, 0.05, seed=1)
    for corners in noisy:
        assert 0.01 < linearity_error(corners, true_model(), BOARD) < 0.1
        assert 0.02 < reprojection_rms(corners, true_model(), BOARD) < 0.1

"""camera_calibration's checks of a calibration: row straightness and reprojection."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.board import Board
from processors.calibration.view_fit import fit_view, linearity_error, reprojection_rms

from .synthetic import (
    BOARD,
    D_TRUE,
    disc_views,
    pinhole_model,
    project,
    random_poses,
    true_model,
    views,
)

#: large discs close to the camera and tilted up to 57 degrees: up to 0.7 px from their centres
CIRCLES = Board(5, 4, 0.05, "circles")
DIAMETER_M = 0.04


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


def test_a_circle_grid_is_predicted_as_its_discs_centroids() -> None:
    """Noise-free detections of a circle grid, the centroids of its discs' images: compared
    with the projected centres they leave an error the pose cannot absorb; compared with the
    discs' centroids, none. The fit also gives the circles' centres, whose rows are straight."""
    model = true_model()
    poses = random_poses(np.random.default_rng(5), 6, [model], board=CIRCLES,
                         max_tilt_rad=1.0)
    seen = disc_views(model, poses, CIRCLES, DIAMETER_M / 2)
    centres = [project(model, p, CIRCLES) for p in poses]
    assert max(np.abs(s - c).max() for s, c in zip(seen, centres, strict=True)) > 0.5
    as_points = [reprojection_rms(s, model, CIRCLES) for s in seen]
    as_discs = [reprojection_rms(s, model, CIRCLES, disc_diameter_m=DIAMETER_M) for s in seen]
    assert max(as_points) > 5e-3 and max(as_discs) < 1e-6
    for s, c in zip(seen, centres, strict=True):
        fit = fit_view(s, model, CIRCLES.points_in_board(), disc_diameter_m=DIAMETER_M)
        assert fit is not None and np.abs(fit.centres_px - c).max() < 1e-6
        assert linearity_error(fit.centres_px, model, CIRCLES) < 1e-6
    assert max(linearity_error(s, model, CIRCLES) for s in seen) > 2e-3

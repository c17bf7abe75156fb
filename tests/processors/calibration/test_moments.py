"""A circle grid's discs measured from grey levels: centres at the discs' area centroids (not
at the projected circle centres) and the diameter the card is printed with."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.board import make_board
from processors.calibration.discs import disc_centroids
from processors.calibration.lens import intrinsics_of
from processors.calibration.moments import disc_moments
from processors.calibration.targets import find_board

from .synthetic import K_TRUE, circle_texture, pose, true_model, warp_texture

PX_PER_M = 4000.0
PINHOLE = intrinsics_of(true_model(k=K_TRUE, d=np.zeros(5)))
CASES = [  # pattern, size, spacing, radius, camera_from_board (rotation vector, translation)
    ("acircles", "4x11", 0.01, 0.005, [0.3, -0.5, 0.3], [-0.03, -0.05, 0.25]),
    ("circles", "6x5", 0.02, 0.005, [0.3, -0.5, 0.3], [-0.03, -0.05, 0.25]),
    ("acircles", "4x5", 0.02, 0.0068, [0.6, 0.2, 0.3], [-0.03, -0.05, 0.3]),
]


@pytest.mark.parametrize("case", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_centres_are_disc_centroids_and_the_diameter_is_measured(
        case: tuple[str, str, float, float, list[float], list[float]]) -> None:
    pattern, size, spacing_m, radius_m, rvec, tvec = case
    board = make_board(size, spacing_m, pattern)
    texture, origin = circle_texture(board, PX_PER_M, radius_m=radius_m)
    camera_from_board = pose(np.array(rvec), np.array(tvec))
    image = warp_texture(texture, PX_PER_M, origin, K_TRUE, camera_from_board)
    found = find_board(image, board)
    assert found is not None and found.accepted
    in_camera = board.points_in_board() @ camera_from_board[:3, :3].T + camera_from_board[:3, 3]
    axes = np.repeat(camera_from_board[:3, :2].T[None], len(in_camera), axis=0)
    projected, centroid = disc_centroids("plumb_bob", PINHOLE, in_camera, axes,
                                         radius_m=radius_m)
    assert np.abs(found.corners_px - centroid).max() < 0.01
    assert np.abs(found.corners_px - projected).max() > 0.1
    assert found.diameter_m is not None
    assert abs(found.diameter_m / (2 * radius_m) - 1) < 3e-3


def test_circles_whose_window_leaves_the_image_are_not_measured() -> None:
    board = make_board("6x5", 0.02, "circles")
    texture, origin = circle_texture(board, PX_PER_M, radius_m=0.005)
    camera_from_board = pose(np.array([0.1, -0.1, 0.0]), np.array([-0.05, -0.04, 0.3]))
    image = warp_texture(texture, PX_PER_M, origin, K_TRUE, camera_from_board)
    found = find_board(image, board)
    assert found is not None
    # the same grid moved so that its first column lies on the image's left edge
    moved = found.corners_px - [found.corners_px[:, 0].min() - 2.0, 0.0]
    discs = disc_moments(image, moved, board)
    first_column = np.arange(board.corner_count) % board.cols == 0
    assert not discs.measured[first_column].any()
    assert np.isnan(discs.centroid_px[first_column]).all()


def test_a_blank_image_measures_nothing() -> None:
    board = make_board("4x11", 0.01, "acircles")
    centres = board.points_in_board()[:, :2] * 2000 + [100, 60]
    discs = disc_moments(np.full((480, 640), 200, np.uint8), centres, board)
    assert not discs.measured.any()

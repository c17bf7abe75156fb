"""ChArUco and circle grids found by OpenCV's detectors where the truth says, partial
ChArUco views included."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from processors.calibration.board import Board, make_board
from processors.calibration.targets import find_board
from processors.errors import ProcessorError
from replay.camera import CameraModel

from .synthetic import K_TRUE, circle_texture, pose, warp_texture

CHARUCO = make_board("8x6", 0.02, "charuco", marker_m=0.015)
PX_PER_M = 4000.0  # texture resolution: 80 px per square


def charuco_view(camera_from_board: np.ndarray, board: Board = CHARUCO
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Image of the ChArUco board and the true pixels of its inner corners."""
    squares = (board.cols + 1, board.rows + 1)
    side = board.square_m * PX_PER_M
    texture = board.charuco().generateImage((round(squares[0] * side),
                                             round(squares[1] * side)), marginSize=0)
    # the first inner corner is one square in from the board's outer corner
    image = warp_texture(texture, PX_PER_M, (side - 0.5, side - 0.5), K_TRUE, camera_from_board)
    points = board.points_in_board()
    in_camera = points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3]
    truth = in_camera[:, :2] / in_camera[:, 2:] * np.diag(K_TRUE)[:2] + K_TRUE[:2, 2]
    return image, truth


def test_charuco_corners_where_the_truth_says() -> None:
    camera_from_board = pose(np.array([0.3, -0.2, 0.1]), np.array([-0.07, -0.05, 0.45]))
    image, truth = charuco_view(camera_from_board)
    found = find_board(image, CHARUCO)
    assert found is not None and found.accepted
    assert found.ids.tolist() == list(range(CHARUCO.corner_count))
    # this warp samples the texture bilinearly: chessboard corners come out within 0.11 px
    error = np.linalg.norm(found.corners_px - truth[found.ids], axis=1)
    assert error.max() < 0.15, error.max()


def test_a_charuco_board_cut_by_the_border_gives_the_corners_it_shows() -> None:
    camera_from_board = pose(np.array([0.1, 0.4, 0.0]), np.array([0.09, -0.02, 0.4]))
    image, truth = charuco_view(camera_from_board)
    found = find_board(image, CHARUCO)
    assert found is not None and found.accepted
    inside = ((truth > 10) & (truth < [630, 470])).all(axis=1)
    assert 6 <= len(found.ids) < CHARUCO.corner_count
    assert set(found.ids.tolist()) <= set(np.flatnonzero(inside).tolist())
    assert np.linalg.norm(found.corners_px - truth[found.ids], axis=1).max() < 0.15


def test_a_legacy_charuco_board_is_found_only_in_its_own_layout() -> None:
    # 8x6 squares: an even number of rows, where OpenCV before 4.6 put the markers in the
    # other squares; the markers are found either way, the corners only in the legacy layout
    legacy = dataclasses.replace(CHARUCO, legacy_pattern=True)
    camera_from_board = pose(np.array([0.3, -0.2, 0.1]), np.array([-0.07, -0.05, 0.45]))
    image, truth = charuco_view(camera_from_board, legacy)
    found = find_board(image, legacy)
    assert found is not None and found.accepted
    assert found.ids.tolist() == list(range(legacy.corner_count))
    assert np.linalg.norm(found.corners_px - truth, axis=1).max() < 0.15
    assert find_board(image, CHARUCO) is None


def test_no_charuco_board_in_a_blank_image() -> None:
    assert find_board(np.full((480, 640), 128, np.uint8), CHARUCO) is None


@pytest.mark.parametrize("pattern", ["circles", "acircles"])
def test_circle_grid_centres(pattern: str) -> None:
    board = make_board("4x5" if pattern == "acircles" else "6x5", 0.02, pattern)
    texture, origin = circle_texture(board, PX_PER_M, radius_m=0.005)
    camera_from_board = pose(np.array([0.15, -0.1, 0.05]), np.array([-0.06, -0.05, 0.45]))
    image = warp_texture(texture, PX_PER_M, origin, K_TRUE, camera_from_board)
    found = find_board(image, board)
    assert found is not None and found.accepted
    points = board.points_in_board()
    in_camera = points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3]
    truth = in_camera[:, :2] / in_camera[:, 2:] * np.diag(K_TRUE)[:2] + K_TRUE[:2, 2]
    # blob centroids sit off the projected centres by the perspective of each disc
    assert np.linalg.norm(found.corners_px - truth, axis=1).max() < 0.2


def test_a_camera_model_guides_charuco_corners_beside_a_single_marker() -> None:
    camera_from_board = pose(np.array([0.0, 0.0, 0.3]), np.array([0.13, 0.0, 0.45]))
    image, truth = charuco_view(camera_from_board)
    model = CameraModel(640, 480, K_TRUE, "plumb_bob", np.zeros(5))
    unguided = find_board(image, CHARUCO)
    guided = find_board(image, CHARUCO, model)
    assert unguided is not None and guided is not None and guided.accepted
    # the border cuts the second marker of some corners: only the guided detection has them
    assert set(unguided.ids.tolist()) < set(guided.ids.tolist())
    assert np.linalg.norm(guided.corners_px - truth[guided.ids], axis=1).max() < 0.15


def test_a_fisheye_model_cannot_guide_a_charuco_detection() -> None:
    image, _ = charuco_view(pose(np.array([0.3, -0.2, 0.1]), np.array([-0.07, -0.05, 0.45])))
    fisheye = CameraModel(640, 480, K_TRUE, "equidistant", np.zeros(4))
    with pytest.raises(ProcessorError, match="equidistant"):
        find_board(image, CHARUCO, fisheye)

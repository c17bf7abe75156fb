"""Chessboard detection on rendered boards: exact corners, and grids that are not the board."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.board import Board
from processors.calibration.detect import (
    canonical_order,
    check_detection,
    find_chessboard,
    track_chessboard,
)

from .synthetic import render_board

BOARD = Board(7, 6, 0.01)
SQUARE_PX = 30.0
ORIGIN_PX = (170.0, 130.0)


@pytest.fixture(scope="module")
def rendered() -> tuple[np.ndarray, np.ndarray]:
    return render_board(BOARD, ORIGIN_PX, SQUARE_PX)


def test_finds_the_rendered_corners(rendered: tuple[np.ndarray, np.ndarray]) -> None:
    image, truth = rendered
    detection = find_chessboard(image, BOARD)
    assert detection is not None
    assert detection.accepted, detection.reason
    # a fronto-parallel board is found in either direction; compare as a set and in order
    corners = canonical_order(detection.corners_px, BOARD)
    same = np.abs(corners - truth).max()
    turned = np.abs(corners - truth[::-1]).max()
    assert min(same, turned) < 0.05, f"{same:.3f} / {turned:.3f} px"


def test_no_board_in_a_blank_image() -> None:
    assert find_chessboard(np.full((480, 640), 128, np.uint8), BOARD) is None


def test_the_true_grid_is_accepted(rendered: tuple[np.ndarray, np.ndarray]) -> None:
    image, truth = rendered
    detection = check_detection(image, truth, BOARD)
    assert detection.accepted and detection.reason == ""
    np.testing.assert_array_equal(detection.corners_px, truth)


@pytest.mark.parametrize("shift", [(0, -1), (0, 1), (-1, 0), (1, 0)],
                         ids=["up", "down", "left", "right"])
def test_a_grid_shifted_by_one_square_is_rejected(
    rendered: tuple[np.ndarray, np.ndarray], shift: tuple[int, int]
) -> None:
    """OpenCV can report a cut board one row off: its outer row then lies on the board's edge,
    where one dark square meets three bright patches (two of them the white margin)."""
    image, truth = rendered
    shifted = truth + np.array(shift) * SQUARE_PX
    detection = check_detection(image, shifted, BOARD)
    assert not detection.accepted
    assert "do not alternate" in detection.reason and "shifted" in detection.reason


def test_corners_at_the_image_border_are_rejected() -> None:
    # the first inner corner 3 px from the left edge: its squares run out of the image
    image, truth = render_board(BOARD, (3.0, 130.0), SQUARE_PX)
    detection = check_detection(image, truth, BOARD)
    assert not detection.accepted
    assert "border" in detection.reason
    # the same board well inside passes
    image, truth = render_board(BOARD, (40.0, 130.0), SQUARE_PX)
    assert check_detection(image, truth, BOARD).accepted


def test_canonical_order_undoes_a_reversed_detection(
    rendered: tuple[np.ndarray, np.ndarray]
) -> None:
    _, truth = rendered
    tilted = truth + np.column_stack([np.zeros(len(truth)), 0.1 * truth[:, 0]])
    forward = canonical_order(tilted, BOARD)
    np.testing.assert_array_equal(forward, tilted)  # already starts at the top
    np.testing.assert_array_equal(canonical_order(tilted[::-1].copy(), BOARD), forward)
    assert forward[0, 1] <= forward[-1, 1]


def test_tracking_refines_a_nearby_prediction(rendered: tuple[np.ndarray, np.ndarray]) -> None:
    image, truth = rendered
    tracked = track_chessboard(image, truth + np.array([2.5, -1.5]), BOARD)
    assert tracked is not None and tracked.accepted
    assert np.abs(canonical_order(tracked.corners_px, BOARD) - canonical_order(truth, BOARD)
                  ).max() < 0.05


def test_tracking_gives_up_rather_than_slide_a_square(
    rendered: tuple[np.ndarray, np.ndarray]
) -> None:
    image, truth = rendered
    # predicted 0.6 squares off: the nearest saddle is the neighbouring corner
    assert track_chessboard(image, truth + np.array([0.6 * SQUARE_PX, 0.0]), BOARD) is None
    assert track_chessboard(np.full((480, 640), 128, np.uint8), truth, BOARD) is None

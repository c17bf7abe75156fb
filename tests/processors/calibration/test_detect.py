"""Chessboard detection on rendered boards: exact corners, and grids that are not the board."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from processors.calibration.board import Board
from processors.calibration.detect import (
    MAX_TRACKED_BEND,
    bend_squares,
    canonical_order,
    check_detection,
    find_chessboard,
    track_chessboard,
)
from processors.calibration.targets import detect_segment

from .synthetic import project, random_poses, render_board, true_model

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


def test_corners_at_the_image_border_are_left_out_one_by_one() -> None:
    # the first column of inner corners 3 px from the left edge: their refinement windows
    # run out of the image, so they leave the view and the rest of the board stays
    image, truth = render_board(BOARD, (3.0, 130.0), SQUARE_PX)
    detection = check_detection(image, truth, BOARD)
    assert detection.accepted and detection.point_ids is not None
    kept = np.setdiff1d(np.arange(BOARD.corner_count), np.arange(0, BOARD.corner_count,
                                                                 BOARD.cols))
    np.testing.assert_array_equal(detection.point_ids, kept)
    np.testing.assert_array_equal(detection.corners_px, truth[kept])
    # the same board well inside keeps every corner
    image, truth = render_board(BOARD, (40.0, 130.0), SQUARE_PX)
    inside = check_detection(image, truth, BOARD)
    assert inside.accepted and inside.point_ids is None


def test_a_board_with_one_line_inside_the_border_is_rejected() -> None:
    # a two-row board whose first row lies 3 px from the top: one row is left, on one line
    narrow = Board(7, 2, 0.01)
    image, truth = render_board(narrow, (40.0, 3.0), SQUARE_PX)
    detection = check_detection(image, truth, narrow)
    assert not detection.accepted
    assert "border" in detection.reason and "7 corners inside" in detection.reason


def test_tracking_a_board_leaving_the_image_hands_over_to_detection() -> None:
    # the previous frames' motion carries the predicted corners past the left border, where
    # cornerSubPix refuses to start: tracking gives up and the frame is searched afresh
    image, truth = render_board(BOARD, (20.0, 130.0), SQUARE_PX)
    assert track_chessboard(image, truth - [25.0, 0.0], BOARD) is None
    found = detect_segment([image, image], BOARD)
    assert all(d is not None and d.accepted for d in found)


def test_tracking_hands_over_when_a_corner_slid_off_the_grid(
    rendered: tuple[np.ndarray, np.ndarray]
) -> None:
    # the junction at the end of the first row moved 8 px along it (0.27 squares), as a
    # corner tracked through blur slides along the board's edge: cornerSubPix follows it,
    # every square still alternates, and only the grid's shape tells the corner is wrong
    image, truth = rendered
    x, y = truth[BOARD.cols - 1].astype(int)
    slid = image.copy()
    slid[y - 12:y + 13, x - 12:x + 13] = image[y - 12:y + 13, x - 20:x + 5]
    refined = cv2.cornerSubPix(slid, truth.astype(np.float32).reshape(-1, 1, 2), (11, 11),
                               (-1, -1), (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT,
                                          60, 0.001)).reshape(-1, 2)
    np.testing.assert_allclose(refined[BOARD.cols - 1] - truth[BOARD.cols - 1], [8, 0],
                               atol=0.05)
    assert check_detection(slid, refined.astype(np.float64), BOARD).accepted
    assert bend_squares(refined.astype(np.float64), BOARD) == pytest.approx(8 / SQUARE_PX,
                                                                           abs=0.01)
    assert track_chessboard(slid, truth, BOARD) is None
    assert track_chessboard(image, truth, BOARD) is not None


def test_a_lens_and_a_tilted_board_bend_the_grid_less_than_the_tracking_limit() -> None:
    # k1 -0.2 at 800 px, boards tilted up to 0.8 rad anywhere in the image: the bend of a
    # true grid stays well below the limit that sends a tracked board back to detection
    rng = np.random.default_rng(3)
    model = true_model()
    board = Board(7, 6, 0.025)
    bends = [bend_squares(project(model, pose, board), board)
             for pose in random_poses(rng, 200, [model], board=board, max_tilt_rad=0.8)]
    assert max(bends) < MAX_TRACKED_BEND / 2, max(bends)


def test_a_frame_opencv_cannot_handle_is_rejected_with_its_reason() -> None:
    # a 1-pixel-wide image: OpenCV's detector raises; the frame is rejected, the run goes on
    image, _truth = render_board(BOARD, ORIGIN_PX, SQUARE_PX)
    found = detect_segment([np.zeros((480, 0), np.uint8), image], BOARD)
    assert found[0] is not None and not found[0].accepted
    assert found[0].reason.startswith("OpenCV failed: ")
    assert found[1] is not None and found[1].accepted

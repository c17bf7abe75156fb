"""Chessboard detection on rendered boards: exact corners, and grids that are not the board."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.ideal_board import ideal_image, tilted_pose
from processors.calibration.board import Board
from processors.calibration.detect import (
    MAX_UNSETTLED,
    _min_spacing,
    canonical_order,
    check_detection,
    find_chessboard,
    track_chessboard,
    unsettled_px,
)
from processors.calibration.targets import detect_segment
from replay.camera import CameraModel

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


def test_true_corners_settle_back_and_a_slid_one_does_not(
    rendered: tuple[np.ndarray, np.ndarray]
) -> None:
    # cornerSubPix started at the straight continuation of each corner's neighbours comes
    # back to every junction; a corner 0.2 squares off the junction (where tracking through
    # blur leaves one on the board's edge) is 0.2 squares from where it settles
    image, truth = rendered
    assert unsettled_px(image, truth, BOARD, radius=11).max() < 0.01
    slid = truth.copy()
    slid[BOARD.cols - 1] += [0.0, 0.2 * SQUARE_PX]
    off = unsettled_px(image, slid, BOARD, radius=11)
    assert off[BOARD.cols - 1] == pytest.approx(0.2 * SQUARE_PX, abs=0.05)
    assert np.delete(off, BOARD.cols - 1).max() < 0.01
    assert off.max() > MAX_UNSETTLED * SQUARE_PX


def test_a_fisheye_board_at_the_edge_of_the_image_settles() -> None:
    # a strongly distorted lens bends the grid by more than the slide tracking refuses: the
    # corners still settle back, and tracking keeps the board
    fisheye = CameraModel(640, 480, np.array([[231.7, 0.0, 322.3], [0.0, 231.9, 237.6],
                                              [0.0, 0.0, 1.0]]),
                          "equidistant", np.array([-0.040, 0.0012, -0.0008, 0.0001]))
    board = Board(7, 6, 0.015)
    rng = np.random.default_rng(4)
    pose = tilted_pose(fisheye, board, np.array([130.0, 110.0]), 0.12, tilt_rad=0.4, rng=rng)
    image = ideal_image(fisheye, pose, board)
    truth = fisheye.project(board.points_in_board() @ pose[:3, :3].T + pose[:3, 3])
    grid = truth.reshape(board.rows, board.cols, 2)
    bend = np.linalg.norm(grid[:, :-2] - 2 * grid[:, 1:-1] + grid[:, 2:], axis=2).max()
    assert bend > MAX_UNSETTLED * _min_spacing(truth, board)
    found = track_chessboard(image, truth, board)
    assert found is not None and found.accepted
    radius = max(2, min(11, math.ceil(_min_spacing(truth, board) * 0.5)))
    assert unsettled_px(image, found.corners_px, board, radius=radius).max() < 0.05


def test_a_frame_opencv_cannot_handle_is_rejected_with_its_reason() -> None:
    # a 1-pixel-wide image: OpenCV's detector raises; the frame is rejected, the run goes on
    image, _truth = render_board(BOARD, ORIGIN_PX, SQUARE_PX)
    found = detect_segment([np.zeros((480, 0), np.uint8), image], BOARD)
    assert found[0] is not None and not found[0].accepted
    assert found[0].reason.startswith("OpenCV failed: ")
    assert found[1] is not None and found[1].accepted

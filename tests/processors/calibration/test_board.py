"""Board sizes are counted in inner corners; corner order is OpenCV's (x fastest)."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.board import Board, make_board, parse_board_size
from processors.errors import ProcessorError


@pytest.mark.parametrize(("text", "expected"), [
    ("7x6", (7, 6)), ("8X6", (8, 6)), (" 9 x 7 ", (9, 7)), ("2x2", (2, 2)), ("12x11", (12, 11)),
])
def test_parse_size_reads_columns_by_rows(text: str, expected: tuple[int, int]) -> None:
    assert parse_board_size(text) == expected


@pytest.mark.parametrize("text", ["7", "7x", "x6", "7x6x5", "7.5x6", "7*6", "-7x6", "", "axb"])
def test_parse_size_rejects_what_is_not_a_size(text: str) -> None:
    with pytest.raises(ProcessorError, match="7x6"):
        parse_board_size(text)


@pytest.mark.parametrize("text", ["1x6", "7x1", "0x0"])
def test_parse_size_needs_two_corners_each_way(text: str) -> None:
    with pytest.raises(ProcessorError, match="at least 2x2"):
        parse_board_size(text)


def test_points_in_board_are_row_by_row_with_x_fastest() -> None:
    board = Board(4, 3, 0.05)
    points = board.points_in_board()
    assert points.shape == (12, 3) and points.dtype == np.float64
    # corner (col, row) sits at (col * square, row * square, 0), rows one after another
    expected = [[c * 0.05, r * 0.05, 0.0] for r in range(3) for c in range(4)]
    np.testing.assert_allclose(points, expected, atol=1e-15)
    np.testing.assert_array_equal(board.grid(), [[c, r] for r in range(3) for c in range(4)])
    assert board.pattern_size == (4, 3)
    assert board.corner_count == 12


def test_make_board_checks_its_inputs() -> None:
    board = make_board("7x6", 0.01)
    assert (board.cols, board.rows, board.square_m, board.pattern) == (7, 6, 0.01, "chessboard")
    with pytest.raises(ProcessorError, match="square size must be > 0"):
        make_board("7x6", 0.0)
    with pytest.raises(ProcessorError, match="square size must be > 0"):
        make_board("7x6", -0.01)
    with pytest.raises(ProcessorError, match="unsupported pattern 'hexagons'"):
        make_board("7x6", 0.01, "hexagons")
    with pytest.raises(ProcessorError, match="belong to the charuco pattern only"):
        make_board("7x6", 0.01, marker_m=0.005)


def test_charuco_counts_squares() -> None:
    board = make_board("12x9", 0.02, "charuco", marker_m=0.015)
    assert (board.cols, board.rows, board.dictionary) == (11, 8, "DICT_5X5_100")
    opencv = board.charuco()
    assert opencv.getChessboardSize() == (12, 9)
    # OpenCV's corners, moved so that the first inner corner is the origin
    corners = np.asarray(opencv.getChessboardCorners(), dtype=np.float64)
    np.testing.assert_allclose(board.points_in_board(), corners - corners[0], atol=1e-7)
    assert board.partial_views and not board.symmetric
    assert "12x9 squares ChArUco" in board.describe()


def test_charuco_legacy_layout_moves_the_markers_not_the_corners() -> None:
    today = make_board("6x4", 0.02, "charuco", marker_m=0.015, dictionary="DICT_4X4_50")
    legacy = make_board("6x4", 0.02, "charuco", marker_m=0.015, dictionary="DICT_4X4_50",
                        legacy_pattern=True)
    assert legacy.charuco().getLegacyPattern() and not today.charuco().getLegacyPattern()
    np.testing.assert_array_equal(legacy.points_in_board(), today.points_in_board())
    # 4 rows of squares (even): the same marker ids sit in other squares
    today_markers = np.asarray(today.charuco().getObjPoints())
    legacy_markers = np.asarray(legacy.charuco().getObjPoints())
    assert not np.allclose(today_markers, legacy_markers)
    assert "legacy layout" in legacy.describe() and "legacy" not in today.describe()
    with pytest.raises(ProcessorError, match="legacy layout belong to the charuco pattern"):
        make_board("7x6", 0.01, legacy_pattern=True)


def test_charuco_checks_markers_and_dictionary() -> None:
    with pytest.raises(ProcessorError, match="needs a marker size between 0 and the square"):
        make_board("6x5", 0.02, "charuco")
    with pytest.raises(ProcessorError, match="needs a marker size between 0 and the square"):
        make_board("6x5", 0.02, "charuco", marker_m=0.02)
    with pytest.raises(ProcessorError, match="unknown ArUco dictionary 'DICT_9X9_1'"):
        make_board("6x5", 0.02, "charuco", marker_m=0.015, dictionary="DICT_9X9_1")
    with pytest.raises(ProcessorError, match="needs 60 markers, DICT_4X4_50 has 50"):
        make_board("12x10", 0.02, "charuco", marker_m=0.015, dictionary="DICT_4X4_50")
    with pytest.raises(ProcessorError, match="3x3 squares"):
        make_board("2x5", 0.02, "charuco", marker_m=0.015)


def test_circle_grids_count_circles() -> None:
    symmetric = make_board("4x3", 0.02, "circles")
    np.testing.assert_allclose(symmetric.points_in_board()[:5, :2],
                               [[0, 0], [0.02, 0], [0.04, 0], [0.06, 0], [0, 0.02]])
    assert symmetric.symmetric
    # every other row half a step along: OpenCV's asymmetric grid
    asymmetric = make_board("4x3", 0.02, "acircles")
    np.testing.assert_allclose(asymmetric.points_in_board()[:6, :2],
                               [[0, 0], [0.04, 0], [0.08, 0], [0.12, 0], [0.02, 0.02],
                                [0.06, 0.02]])
    assert not asymmetric.symmetric and "asymmetric circle grid" in asymmetric.describe()

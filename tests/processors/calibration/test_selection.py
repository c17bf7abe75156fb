"""camera_calibration's view descriptors, and the farthest-point choice of views."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration.board import Board
from processors.calibration.selection import outside_corners, select_views, view_parameters

BOARD = Board(8, 6, 0.025)
W, H = 640, 480


def flat_board(center: tuple[float, float], spacing_px: float) -> np.ndarray:
    """Corners of a fronto-parallel board centred at ``center``, x fastest."""
    cols, rows = np.meshgrid(np.arange(BOARD.cols), np.arange(BOARD.rows))
    u = center[0] + (cols.ravel() - (BOARD.cols - 1) / 2) * spacing_px
    v = center[1] + (rows.ravel() - (BOARD.rows - 1) / 2) * spacing_px
    return np.column_stack([u, v])


def test_outside_corners_go_round_the_board() -> None:
    corners = flat_board((320, 240), 20)
    ul, ur, dr, dl = outside_corners(corners, BOARD)
    np.testing.assert_allclose(ul, corners[0])
    np.testing.assert_allclose(ur, corners[BOARD.cols - 1])
    np.testing.assert_allclose(dr, corners[-1])
    np.testing.assert_allclose(dl, corners[-BOARD.cols])


def test_a_centred_flat_board_sits_in_the_middle_without_skew() -> None:
    spacing = 30.0
    x, y, size, skew = view_parameters(flat_board((W / 2, H / 2), spacing), BOARD, (W, H))
    # size: square root of the outline's share of the image
    outline = (BOARD.cols - 1) * spacing * (BOARD.rows - 1) * spacing
    assert x == pytest.approx(0.5, abs=1e-9)
    assert y == pytest.approx(0.5, abs=1e-9)
    assert size == pytest.approx(math.sqrt(outline / (W * H)), rel=1e-9)
    assert skew == pytest.approx(0.0, abs=1e-9)


def test_descriptors_follow_position_size_and_shear() -> None:
    left = view_parameters(flat_board((150, 240), 20), BOARD, (W, H))
    right = view_parameters(flat_board((490, 240), 20), BOARD, (W, H))
    top = view_parameters(flat_board((320, 100), 20), BOARD, (W, H))
    big = view_parameters(flat_board((320, 240), 40), BOARD, (W, H))
    assert left[0] < 0.5 < right[0] and left[1] == pytest.approx(right[1])
    assert top[1] < 0.5
    assert big[2] == pytest.approx(2 * left[2])
    sheared = flat_board((320, 240), 20)
    sheared[:, 0] += 0.3 * (sheared[:, 1] - 240)  # rows slide sideways: corners not square
    assert view_parameters(sheared, BOARD, (W, H))[3] > 0.2


def test_identical_views_give_one() -> None:
    params = np.tile([0.4, 0.6, 0.3, 0.1], (20, 1))
    assert len(select_views(params, max_views=10)) == 1


def test_diverse_views_give_many_but_never_more_than_asked() -> None:
    params = np.random.default_rng(0).uniform(0, 1, (60, 4))
    everything = select_views(params, max_views=100, min_distance=0.02)
    assert len(everything) == 60  # random points in [0, 1]^4 are far more than 0.02 apart
    for cap in (1, 5, 17):
        chosen = select_views(params, max_views=cap, min_distance=0.02)
        assert len(chosen) == cap
        assert chosen == sorted(set(chosen))


def test_every_view_left_out_is_close_to_a_chosen_one() -> None:
    rng = np.random.default_rng(1)
    # five clusters of near-duplicates
    centres = rng.uniform(0, 1, (5, 4))
    params = np.repeat(centres, 8, axis=0) + rng.normal(0, 0.005, (40, 4))
    chosen = select_views(params, max_views=100, min_distance=0.2)
    assert len(chosen) == 5
    distance = np.abs(params[:, None] - params[chosen][None]).sum(axis=2).min(axis=1)
    assert distance.max() <= 0.2
    assert {int(np.argmin(np.abs(centres - params[i]).sum(axis=1))) for i in chosen} == set(
        range(5))  # one per cluster


def test_no_views() -> None:
    assert select_views(np.zeros((0, 4)), max_views=5) == []


def test_size_is_the_outline_area_of_a_perspective_view() -> None:
    """A board seen in perspective is a general quadrilateral: its area by the shoelace
    formula over the four outer corners."""
    flat = flat_board((320, 240), 1.0)
    # a homography that makes no two outline sides parallel
    h = np.array([[40.0, 6.0, 120.0], [-4.0, 36.0, 110.0], [0.04, 0.03, 1.0]])
    uvw = np.column_stack([flat - flat[0], np.ones(len(flat))]) @ h.T
    corners = uvw[:, :2] / uvw[:, 2:]
    outline = outside_corners(corners, BOARD)
    x, y = outline[:, 0], outline[:, 1]
    area = abs(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) / 2
    sides = np.roll(outline, -1, axis=0) - outline
    cosines = [abs(sides[i] @ sides[i + 2]) / np.linalg.norm(sides[i]) / np.linalg.norm(
        sides[i + 2]) for i in (0, 1)]
    assert max(cosines) < 0.999  # neither pair of opposite sides is parallel
    size = view_parameters(corners, BOARD, (W, H))[2]
    assert size == pytest.approx(math.sqrt(area / (W * H)), rel=1e-9)

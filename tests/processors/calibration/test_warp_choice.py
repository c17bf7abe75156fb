"""The board's warp chosen by cross-validation over whole views: chosen and recovered for a
bowed board, not for a flat one, also when every view's corners share an error."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration import warp_choice
from processors.calibration.board import Board
from processors.calibration.joint import BoardView, JointResult, calibrate_cameras
from processors.calibration.options import CalibrationOptions
from processors.calibration.warp import warp_shapes, warped
from processors.errors import ProcessorError
from replay.messages import F64

from . import synthetic as s

#: 27 x 21 cm, a printed board's size
BOARD = Board(10, 8, 0.03)
POINTS = BOARD.points_in_board()
IDS = np.arange(len(POINTS))
#: a bow of 1.5 mm along the board's x and -1 mm along its y
BOW_M = np.array([0.0015, -0.001])


def board_views(warp_m: F64, seed: int, *, count: int = 24, noise_px: float = 0.1,
                shared_px: float = 0.0) -> list[BoardView]:
    """``count`` views of the board bowed by ``warp_m``, Gaussian noise per corner, and with
    ``shared_px`` a shift and a stretch of that size every corner of a view shares."""
    model = s.true_model()
    rng = np.random.default_rng(seed)
    bowed = warped(POINTS, warp_m)
    out = []
    for instant, pose in enumerate(s.random_poses(rng, count, [model], board=BOARD)):
        corners = model.project(bowed @ pose[:3, :3].T + pose[:3, 3]) \
            + rng.normal(0.0, noise_px, (len(POINTS), 2))
        if shared_px:
            corners = corners + rng.normal(0.0, shared_px, 2) \
                + (corners - corners.mean(axis=0)) @ rng.normal(0.0, shared_px / 150.0, (2, 2))
        out.append(BoardView(0, instant, IDS, corners))
    return out


def calibrated(views: list[BoardView], board_warp: str = "auto") -> JointResult:
    return calibrate_cameras(POINTS, views, [(s.W, s.H)],
                             CalibrationOptions(board_warp=board_warp))


def test_the_shapes_bow_the_middle_and_hold_the_edges() -> None:
    shapes = warp_shapes(POINTS)
    assert shapes.min() == pytest.approx(0.0) and shapes.max() <= 1.0
    corner = np.argmin(np.sum(POINTS[:, :2], axis=1))
    assert np.allclose(shapes[corner], 0.0)
    middle_column = POINTS[:, 0] == POINTS[4, 0]  # x = 0.12 of 0 .. 0.27
    assert np.allclose(shapes[middle_column, 0], 1.0 - (0.12 / 0.135 - 1.0) ** 2)
    bowed = warped(POINTS, BOW_M)
    assert np.allclose(bowed[:, :2], POINTS[:, :2])
    assert bowed[:, 2].max() == pytest.approx(0.0015 * shapes[:, 0].max(), abs=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_a_bowed_board_is_chosen_and_its_warp_recovered(seed: int) -> None:
    result = calibrated(board_views(BOW_M, seed))
    choice = result.warp_choice
    assert choice is not None and choice.chosen, choice
    flat_px, warped_px = choice.held_out_rms_px
    assert warped_px < 0.8 * flat_px
    assert result.options[0].board_warp == "on"
    estimate = result.board_warp_m
    assert estimate is not None
    warp_m, std_m = estimate
    assert np.all(std_m > 0) and np.all(std_m < 2e-4)
    assert np.all(np.abs(warp_m - BOW_M) < 4 * std_m), (warp_m, std_m)
    assert result.rms_px < 0.15  # the bow is fitted away: noise of 0.1 px per coordinate


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "shared_px"), [(3, 0.0), (4, 0.0), (5, 0.3), (6, 0.3)])
def test_a_flat_board_stays_flat(seed: int, shared_px: float) -> None:
    views = board_views(np.zeros(2), seed, shared_px=shared_px)
    result = calibrated(views)
    choice = result.warp_choice
    assert choice is not None
    assert not choice.chosen, choice.describe()
    assert choice.views == len(views)
    assert result.board_warp_m is None and result.options[0].board_warp == "off"
    plain = calibrated(views, "off")
    np.testing.assert_array_equal(result.models[0].d, plain.models[0].d)


def test_off_holds_a_bowed_board_flat_without_cross_validating() -> None:
    views = board_views(BOW_M, 1)
    result = calibrated(views, "off")
    assert result.warp_choice is None and result.board_warp_m is None
    assert result.rms_px > 0.3  # the bow stays in the residuals
    on = calibrated(views, "on")
    assert on.warp_choice is None and on.board_warp_m is not None
    np.testing.assert_allclose(on.board_warp_m[0], BOW_M, atol=1e-4)


def test_too_few_views_hold_the_board_flat() -> None:
    choice = calibrated(board_views(BOW_M, 1, count=8)).warp_choice
    assert choice is not None and not choice.chosen and choice.why_not is not None
    assert "8 views" in choice.describe()


def test_an_unknown_mode_is_refused() -> None:
    with pytest.raises(ProcessorError, match="board warp"):
        CalibrationOptions(board_warp="maybe")


def test_the_views_of_one_board_pose_count_once_their_corners_pooled() -> None:
    from processors.calibration.warp_choice import _per_pose

    # views 0 and 1: one pose seen by two cameras (40 and 10 corners); view 2 another pose
    errors = np.array([[1.0, 3.0, 2.0], [0.5, 1.0, 2.5]])
    flat, warped = _per_pose(errors, np.array([7, 7, 9]), np.array([40, 10, 30]))
    assert flat == pytest.approx([(40 * 1.0 + 10 * 3.0) / 50, 2.0])
    assert warped == pytest.approx([(40 * 0.5 + 10 * 1.0) / 50, 2.5])


def test_the_poses_compared_are_an_even_sample_of_a_long_log(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Past :data:`~processors.calibration.warp_choice.WARP_POSES` board poses the folds are
    those of an even sample (the solve itself keeps every view): a bow is still chosen."""
    monkeypatch.setattr(warp_choice, "WARP_POSES", 20)
    result = calibrated(board_views(BOW_M, 1, count=40))
    choice = result.warp_choice
    assert choice is not None and choice.views == 20 and choice.chosen, choice
    assert len(result.used_views(0)) == 40

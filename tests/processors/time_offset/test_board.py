"""The offset between two cameras' stamps from a waved board both see (synthetic views)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.time_offset import NotObservableError, estimate_board_offset

from .synthetic import POINTS, SECOND_FROM_FIRST, tracks


@pytest.mark.parametrize("offset_ms", [0.0, 17.0, 33.0, -10.0])
def test_the_offset_and_the_rig_come_back_within_their_sigma(offset_ms: float) -> None:
    first, second = tracks(3, offset_ms)
    estimate = estimate_board_offset(first, second, points_in_board=POINTS)
    error_ms = estimate.offset_ms - offset_ms
    assert abs(error_ms) < 0.05
    assert abs(error_ms) < 5 * estimate.std_ms
    assert 0 < estimate.std_ms < 0.05
    assert estimate.method == "board"
    assert estimate.frames > 0.9 * estimate.frames_fitted > 250  # both cameras' frames
    assert estimate.second_from_first is not None
    np.testing.assert_allclose(estimate.second_from_first[:3, 3], SECOND_FROM_FIRST[:3, 3],
                               atol=2e-4)
    cosine = (np.trace(estimate.second_from_first[:3, :3]) - 1) / 2
    assert math.degrees(math.acos(min(cosine, 1.0))) < 0.05


def test_exposures_apart_stamped_as_one_instant() -> None:
    """The second camera exposes 15 ms after the first and its driver stamps 15 ms early:
    both stamp the same instants, the offset is -15 ms (sub-frame, between exposures)."""
    first, second = tracks(4, -15.0, phase_s=0.015)
    np.testing.assert_array_equal(first.stamps_ns, second.stamps_ns)
    estimate = estimate_board_offset(first, second, points_in_board=POINTS)
    assert abs(estimate.offset_ms + 15.0) < 0.05


def test_a_given_rig_leaves_only_the_offset() -> None:
    first, second = tracks(5, 7.0)
    estimate = estimate_board_offset(first, second, points_in_board=POINTS,
                                     second_from_first=SECOND_FROM_FIRST)
    assert abs(estimate.offset_ms - 7.0) < 0.05
    np.testing.assert_array_equal(estimate.second_from_first, SECOND_FROM_FIRST)


def test_a_board_numbered_from_its_other_end_in_one_camera() -> None:
    first, second = tracks(6, 12.0, turned=True)
    with pytest.raises(NotObservableError):  # the numberings disagree: no rig fits
        estimate_board_offset(first, second, points_in_board=POINTS)
    estimate = estimate_board_offset(first, second, points_in_board=POINTS, half_turn=True)
    assert abs(estimate.offset_ms - 12.0) < 0.05


def test_a_held_board_does_not_show_the_offset() -> None:
    """Held 0.5 s per pose and jumping between poses: no frame moves smoothly."""
    first, second = tracks(7, 17.0, held=True)
    with pytest.raises(NotObservableError, match=r"hardly moves.*held one does not"):
        estimate_board_offset(first, second, points_in_board=POINTS)


def test_cameras_that_never_see_the_board_together() -> None:
    first, second = tracks(8, 0.0, frames=60, start_s=(0.0, 10.0))
    with pytest.raises(NotObservableError, match="never see the board at the same time"):
        estimate_board_offset(first, second, points_in_board=POINTS)


def test_an_offset_beyond_the_search_is_not_found() -> None:
    first, second = tracks(9, 400.0, frames=120)
    with pytest.raises(NotObservableError):
        estimate_board_offset(first, second, points_in_board=POINTS, search_s=0.1)

"""Held boards: consecutive frames of one pose average into one view."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.holds import Seen, frame_scatter_px, holds

IDS = np.arange(4)


def seen(corners: np.ndarray, ids: np.ndarray = IDS) -> Seen:
    return Seen(ids, corners)


def test_consecutive_frames_of_one_pose_average() -> None:
    rng = np.random.default_rng(0)
    pose_a, pose_b = rng.uniform(0, 600, (4, 2)), rng.uniform(0, 600, (4, 2))
    noise = rng.normal(0, 0.01, (7, 4, 2))
    instants = [{0: seen(pose_a + noise[i])} for i in range(4)] + \
        [{0: seen(pose_b + noise[i])} for i in range(4, 7)]
    groups = holds(instants)
    assert [g.members for g in groups] == [[0, 1, 2, 3], [4, 5, 6]]
    np.testing.assert_allclose(groups[0].mean[0].corners_px, pose_a + noise[:4].mean(axis=0))
    scatter = frame_scatter_px(instants, groups)
    assert scatter == pytest.approx(0.01, rel=0.35)


def test_a_moving_board_makes_no_holds() -> None:
    instants = [{0: seen(np.full((4, 2), 100.0) + i)} for i in range(5)]
    groups = holds(instants)
    assert [g.members for g in groups] == [[i] for i in range(5)]
    assert frame_scatter_px(instants, groups) is None


def test_every_camera_must_hold_still() -> None:
    still = np.full((4, 2), 50.0)
    instants = [{0: seen(still), 1: seen(still)}, {0: seen(still), 1: seen(still + 1.0)},
                {0: seen(still)}, {0: seen(still, np.array([0, 1, 2, 5]))}]
    assert [g.members for g in holds(instants)] == [[0], [1], [2], [3]]

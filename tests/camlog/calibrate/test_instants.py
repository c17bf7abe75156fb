"""From frames to views: held poses averaged, stereo pairs shared, repeated frames once."""

from __future__ import annotations

import numpy as np

from camlog.calibrate.instants import rig_views
from camlog.calibrate.views import CameraSource, CameraViews, Frame, board_speeds
from processors.calibration.board import Board
from processors.calibration.detect import Detection

BOARD = Board(3, 2, 0.01)
GRID = np.array([[100.0 + 20 * c, 100.0 + 20 * r] for r in range(2) for c in range(3)])


def camera(corners: list[np.ndarray | None], *, duplicates: list[bool] | None = None,
           name: str = "/cam") -> CameraViews:
    dup = duplicates or [False] * len(corners)
    detections = [Detection(c, True) if c is not None else None for c in corners]
    speeds = board_speeds(detections, dup)
    frames = tuple(Frame(i, 1000 * i, dup[i], detections[i], speed_px=speeds[i])
                   for i in range(len(corners)))
    return CameraViews(CameraSource(name, f"{name}/image_raw", None), frames, (640, 480), None)


def test_a_held_board_is_one_view_of_its_frames_averaged() -> None:
    rng = np.random.default_rng(0)
    held = [GRID + rng.normal(0, 0.01, GRID.shape) for _ in range(4)]
    moving = [GRID + 5.0 * (i + 1) for i in range(3)]
    rig = rig_views([camera(held + moving)], BOARD, approximate_s=None, stereo_note=False)
    assert rig.frames_of == [[0, 1, 2, 3], [4], [5], [6]]
    np.testing.assert_allclose(rig.views[0].corners_px, np.mean(held, axis=0))
    assert rig.views[0].speed_px == 0.0
    # a moving board's view carries its speed: 5 px per frame along each axis
    assert rig.views[2].speed_px == np.hypot(5.0, 5.0)
    assert rig.frame_scatter_px is not None and 0.005 < rig.frame_scatter_px < 0.02


def test_a_repeated_frame_counts_once_and_stereo_pairs_share_an_instant() -> None:
    left = camera([GRID, GRID, GRID + 40.0], duplicates=[False, True, False], name="/l")
    right = camera([GRID - 30.0, GRID - 30.0, GRID + 10.0], duplicates=[False, True, False],
                   name="/r")
    rig = rig_views([left, right], BOARD, approximate_s=None, stereo_note=True)
    assert [v.camera for v in rig.views] == [0, 1, 0, 1]
    assert rig.frames_of == [[0], [0], [2], [2]]
    assert rig.pairs == [(0, 1), (2, 3)]
    assert rig.views[0].instant == rig.views[1].instant != rig.views[2].instant

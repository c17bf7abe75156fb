"""From frames to views: held poses averaged, stereo pairs shared, repeated frames once."""

from __future__ import annotations

import numpy as np
import pytest

from camlog.calibrate.instants import rig_views
from camlog.calibrate.views import CameraSource, CameraViews, DetectedFrame, board_speeds
from camlog.errors import CalibrationError
from processors.calibration.board import Board
from processors.calibration.detect import Detection

BOARD = Board(3, 2, 0.01)
GRID = np.array([[100.0 + 20 * c, 100.0 + 20 * r] for r in range(2) for c in range(3)])


def camera(corners: list[np.ndarray | None], *, duplicates: list[bool] | None = None,
           name: str = "/cam", period_ns: int = 1000, offset_ns: int = 0) -> CameraViews:
    dup = duplicates or [False] * len(corners)
    detections = [Detection(c, True) if c is not None else None for c in corners]
    speeds = board_speeds(detections, dup)
    frames = tuple(DetectedFrame(i, offset_ns + period_ns * i, dup[i], detections[i],
                         speed_px=speeds[i])
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


def test_offset_snapshots_pair_within_the_slop() -> None:
    # a photo pair a second, the right camera 3 ms late: every pose differs from the last,
    # yet each pair shows one pose (the board is not observed moving between photos)
    poses = [GRID + 30.0 * i for i in range(5)]
    left = camera(poses, name="/l", period_ns=1_000_000_000)
    right = camera([p - 20.0 for p in poses], name="/r", period_ns=1_000_000_000,
                   offset_ns=3_000_000)
    rig = rig_views([left, right], BOARD, approximate_s=0.02, stereo_note=True)
    assert len(rig.pairs) == 5
    assert [rig.frames_of[lv] + rig.frames_of[rv] for lv, rv in rig.pairs] == \
        [[i, i] for i in range(5)]


def test_offset_video_of_a_moving_board_does_not_pair() -> None:
    # 30 Hz video, the board moving 5 px a frame: 7 ms apart it is at another pose
    poses = [GRID + 5.0 * i for i in range(6)]
    left = camera(poses, name="/l", period_ns=33_333_333)
    right = camera(poses, name="/r", period_ns=33_333_333, offset_ns=7_000_000)
    with pytest.raises(CalibrationError, match="never see the board at the same instant "
                                               "with the board still"):
        rig_views([left, right], BOARD, approximate_s=0.02, stereo_note=True)


def test_offset_frames_either_side_of_a_pose_change_do_not_pair() -> None:
    # 30 Hz video of poses held 0.3 s (repeated frames: each pose's first frame is as far
    # from the last pose's as a snapshot), the right camera 7 ms late; the board jumps to
    # its next pose between a left frame and its right partner, and the right camera does
    # not see pose 1: the last left frame of pose 1 and the first right frame of pose 2
    # are 7 ms apart but show two poses
    period, phase, hold = 33_333_333, 7_000_000, 9
    left_pose = [i // hold for i in range(4 * hold)]
    right_pose = [(i + 1) // hold for i in range(4 * hold)]
    repeats = [[i > 0 and pose[i] == pose[i - 1] for i in range(len(pose))]
               for pose in (left_pose, right_pose)]
    left = camera([GRID + 40.0 * p for p in left_pose], duplicates=repeats[0], name="/l",
                  period_ns=period)
    right = camera([None if p == 1 else GRID - 20.0 + 40.0 * p for p in right_pose],
                   duplicates=repeats[1], name="/r", period_ns=period, offset_ns=phase)
    rig = rig_views([left, right], BOARD, approximate_s=0.02, stereo_note=True)
    poses = [({left_pose[f] for f in rig.frames_of[lv]},
              {right_pose[f] for f in rig.frames_of[rv]}) for lv, rv in rig.pairs]
    assert poses == [({p}, {p}) for p in (0, 2, 3)]


def test_three_cameras_share_instants_through_a_chain() -> None:
    # camera 0 and camera 2 never shoot at the same time; camera 1 shares with both
    first = camera([GRID, GRID + 40.0, None, None], name="/a")
    second = camera([GRID - 30.0, GRID + 10.0, GRID + 20.0, GRID + 60.0], name="/b")
    third = camera([None, None, GRID - 20.0, GRID + 30.0], name="/c")
    rig = rig_views([first, second, third], BOARD, approximate_s=None, stereo_note=True)
    by_instant: dict[int, list[int]] = {}
    for view in rig.views:
        by_instant.setdefault(view.instant, []).append(view.camera)
    assert sorted(by_instant.values()) == [[0, 1], [0, 1], [1, 2], [1, 2]]
    assert rig.pairs == []  # stereo pairs belong to two cameras


def test_a_camera_that_shares_no_instant_is_one_error() -> None:
    first = camera([GRID, GRID + 40.0], name="/a")
    second = camera([GRID - 30.0, GRID + 10.0], name="/b")
    alone = camera([GRID, GRID + 5.0], name="/c", offset_ns=500)
    with pytest.raises(CalibrationError, match=r"^/c/image_raw never sees the board at the "
                                               r"same instant as /a, /b, directly or through"):
        rig_views([first, second, alone], BOARD, approximate_s=None, stereo_note=True)


def test_three_offset_snapshots_share_one_instant_within_the_slop() -> None:
    # a photo a second from each of three cameras, 2 and 4 ms apart: one pose per second
    poses = [GRID + 30.0 * i for i in range(4)]
    cameras = [camera([p + 10.0 * c for p in poses], name=f"/c{c}", period_ns=1_000_000_000,
                      offset_ns=2_000_000 * c) for c in range(3)]
    rig = rig_views(cameras, BOARD, approximate_s=0.01, stereo_note=True)
    by_instant: dict[int, list[int]] = {}
    for view, frames in zip(rig.views, rig.frames_of, strict=True):
        by_instant.setdefault(view.instant, []).append(frames[0])
    assert sorted(by_instant.values()) == [[i, i, i] for i in range(4)]

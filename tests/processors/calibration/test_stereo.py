"""Stereo rig from a joint calibration: rectification and figures of merit of a synthetic rig
with a 0.02 m baseline along x."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration import prior
from processors.calibration.board import Board
from processors.calibration.holds import Seen
from processors.calibration.joint import BoardView, JointResult, calibrate_cameras
from processors.calibration.options import CalibrationOptions
from processors.calibration.stereo import (
    RectifiedPair,
    StereoResult,
    epipolar_errors,
    orient_right_views,
    square_size,
    stereo_result,
    turned,
)
from processors.errors import ProcessorError
from replay.camera import CameraModel

from .synthetic import BOARD, H, W, disc_views, pose, project, random_poses, views

BASELINE_M = 0.02
NOISE_PX = 0.05
LEFT = CameraModel(W, H, np.array([[800.0, 0, 322.0], [0, 801.0, 238.0], [0, 0, 1]]),
                   "plumb_bob", np.array([-0.1, 0.02, 0.0, 0.0, 0.0]))
RIGHT = CameraModel(W, H, np.array([[805.0, 0, 316.0], [0, 804.0, 243.0], [0, 0, 1]]),
                    "plumb_bob", np.array([-0.12, 0.03, 0.0, 0.0, 0.0]))
#: the right camera sits 0.02 m along the left camera's +x, turned by 0.5° about y
RIGHT_FROM_LEFT = np.linalg.inv(pose(np.array([0.0, math.radians(0.5), 0.0]),
                                     np.array([BASELINE_M, 0.0, 0.0])))


@pytest.fixture(scope="module")
def rig() -> tuple[list[np.ndarray], list[np.ndarray]]:
    left_from_board = random_poses(np.random.default_rng(3), 25, [LEFT, RIGHT],
                                   camera_from_reference=[np.eye(4), RIGHT_FROM_LEFT])
    left = views(LEFT, left_from_board, NOISE_PX, seed=1)
    right = views(RIGHT, [RIGHT_FROM_LEFT @ p for p in left_from_board], NOISE_PX, seed=2)
    return left, right


ALL = np.arange(BOARD.corner_count)


def pairs(count: int) -> list[tuple[int, int]]:
    """The joint views of ``count`` views per camera: (left view, right view) at each pose."""
    return [(i, count + i) for i in range(count)]


def solve(left: list[np.ndarray], right: list[np.ndarray]) -> tuple[JointResult, StereoResult]:
    """Both cameras and the rig jointly, then the stereo figures of the joint views."""
    views = [BoardView(0, i, ALL, c) for i, c in enumerate(left)] + \
        [BoardView(1, i, ALL, c) for i, c in enumerate(right)]
    joint = calibrate_cameras(BOARD.points_in_board(), views, [(W, H)] * 2,
                              CalibrationOptions(tangential="zero"))
    return joint, stereo_result(joint, pairs(len(left)), points_in_board=BOARD.points_in_board(),
                                square_m=BOARD.square_m)


@pytest.fixture(scope="module")
def solved(rig: tuple[list[np.ndarray], list[np.ndarray]]) -> tuple[JointResult, StereoResult]:
    return solve(*rig)


@pytest.fixture(scope="module")
def result(solved: tuple[JointResult, StereoResult]) -> StereoResult:
    return solved[1]


def test_recovers_the_rig(result: StereoResult) -> None:
    assert result.baseline_m == pytest.approx(BASELINE_M, rel=0.002)
    np.testing.assert_allclose(result.right_from_left[:3, 3], RIGHT_FROM_LEFT[:3, 3],
                               atol=0.002 * BASELINE_M)
    assert result.rotation_deg == pytest.approx(0.5, abs=0.02)
    # the joint covariance gives the baseline's and the rotation's uncertainty
    assert abs(result.baseline_m - BASELINE_M) < 3 * result.baseline_std_m
    assert 0 < result.rotation_std_deg < 0.02
    # RMS over both cameras' 2-D residuals: about sigma * sqrt(2)
    assert result.rms_px == pytest.approx(NOISE_PX * math.sqrt(2), rel=0.15)


def test_rectification_aligns_rows(result: StereoResult,
                                   rig: tuple[list[np.ndarray], list[np.ndarray]]) -> None:
    assert result.epipolar_rms_px < 0.1
    assert len(result.view_epipolar_px) == len(rig[0])
    # P2 = [fx' 0 cx' -fx' B; 0 fy' cy' 0; 0 0 1 0]: the right camera sits at +B
    fx = result.p2[0, 0]
    assert result.p2[0, 3] < 0
    assert result.p2[0, 3] == pytest.approx(-fx * BASELINE_M, rel=0.002)
    assert result.p1[0, 3] == 0.0
    np.testing.assert_allclose(result.p1[:, :3], result.p2[:, :3])
    for r in (result.r1, result.r2):
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-9)
    # rectified corners of a pair share their rows, and disparity is positive (left - right)
    left, right = rig
    xl = LEFT.rectify_points(left[0], result.r1, result.p1)
    xr = RIGHT.rectify_points(right[0], result.r2, result.p2)
    assert np.abs(xl[:, 1] - xr[:, 1]).max() < 0.5
    assert (xl[:, 0] - xr[:, 0] > 0).all()


def test_square_size_from_triangulation(result: StereoResult) -> None:
    assert result.square_m == pytest.approx(BOARD.square_m, rel=0.01)


def test_epipolar_errors_grow_when_the_rig_is_wrong(
    solved: tuple[JointResult, StereoResult], rig: tuple[list[np.ndarray], list[np.ndarray]]
) -> None:
    left, right = rig
    joint, result = solved
    models = {"left_model": joint.models[0], "right_model": joint.models[1]}
    good = epipolar_errors(left, right, **models, r1=result.r1, p1=result.p1, r2=result.r2,
                           p2=result.p2)
    assert np.sqrt(np.mean(np.square(good))) == pytest.approx(result.epipolar_rms_px, rel=0.05)
    # turn the right rectification by 0.5° about the baseline: rows slip by about f * 0.0087
    tilt = pose(np.array([math.radians(0.5), 0.0, 0.0]), np.zeros(3))[:3, :3]
    bad = epipolar_errors(left, right, **models, r1=result.r1, p1=result.p1,
                          r2=tilt @ result.r2, p2=result.p2)
    slip = result.p2[1, 1] * math.radians(0.5)
    assert np.median(bad) > 0.5 * slip > 10 * np.median(good)


def test_no_joint_view(rig: tuple[list[np.ndarray], list[np.ndarray]]) -> None:
    joint, _result = solve(*rig)
    with pytest.raises(ProcessorError, match="no joint stereo view"):
        stereo_result(joint, [], points_in_board=BOARD.points_in_board(),
                      square_m=BOARD.square_m)


def test_a_pair_from_two_board_poses_is_rejected(
    result: StereoResult, rig: tuple[list[np.ndarray], list[np.ndarray]]
) -> None:
    """Two frames paired across a move of the board (approximate pairing) show different
    poses: that joint view leaves the rig, not simultaneous, and the rig is the one the good
    views give; the right view stays in the right camera."""
    left, right = rig
    mixed = list(right)
    mixed[4] = right[5]
    joint, out = solve(left, mixed)
    mixed_pair = pairs(len(left))[4]
    assert mixed_pair in out.rejected
    assert out.rejected[mixed_pair].startswith("not simultaneous: the board moved")
    assert mixed_pair not in out.pairs
    assert out.baseline_m == pytest.approx(result.baseline_m, abs=3 * result.baseline_std_m)
    assert out.epipolar_rms_px < 2 * result.epipolar_rms_px
    assert not result.rejected and result.pairs == pairs(len(left))
    assert not joint.rejected and list(joint.split) == [mixed_pair[1]]


def test_no_joint_view_left_says_the_pairs_were_not_simultaneous(
        rig: tuple[list[np.ndarray], list[np.ndarray]]) -> None:
    left, right = rig
    mixed = list(right)
    mixed[4] = right[5]
    joint, _out = solve(left, mixed)
    with pytest.raises(ProcessorError, match=r"no joint stereo view: every pair left the rig "
                       r"as not simultaneous: the board moved [0-9.]+ mm .*--time-offset auto"):
        stereo_result(joint, [pairs(len(left))[4]], points_in_board=BOARD.points_in_board(),
                      square_m=BOARD.square_m)


def test_right_views_numbered_from_the_other_end_are_turned_back(
    rig: tuple[list[np.ndarray], list[np.ndarray]]
) -> None:
    left, right = rig
    every = np.arange(BOARD.corner_count)
    # a view cut by the image border shows some of the corners: every third one here
    part = every[every % 7 < 5]
    seen = [Seen(part, c[part]) if i % 2 else Seen(every, c) for i, c in enumerate(right)]
    flipped = [turned(s, BOARD.corner_count) if i % 3 == 0 else s for i, s in enumerate(seen)]
    assert not np.array_equal(flipped[3].point_ids, seen[3].point_ids)
    oriented = orient_right_views(BOARD.points_in_board(),
                                  [Seen(every, c) for c in left], flipped, left_model=LEFT,
                                  right_model=RIGHT)
    for a, b in zip(oriented, seen, strict=True):
        np.testing.assert_array_equal(a.point_ids, b.point_ids)
        np.testing.assert_array_equal(a.corners_px, b.corners_px)


def test_a_circle_grid_is_measured_at_the_circles_centres(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Noise-free detections of a circle grid are the centroids of its discs' images, which
    the two cameras see differently: taken for the circles' centres, rows of a rectified pair
    disagree and the triangulated spacing shrinks; moved by the disc shift at the solution,
    both figures are exact (without the distortion prior, whose pull is 1e-4 px)."""
    monkeypatch.setattr(prior, "PRIOR_SHARE", 0.0)
    board, diameter_m = Board(5, 4, 0.05, "circles"), 0.04
    points = board.points_in_board()
    left_from_board = random_poses(np.random.default_rng(3), 12, [LEFT, RIGHT], board=board,
                                   max_tilt_rad=1.0,
                                   camera_from_reference=[np.eye(4), RIGHT_FROM_LEFT])
    right_from_board = [RIGHT_FROM_LEFT @ p for p in left_from_board]
    left = disc_views(LEFT, left_from_board, board, diameter_m / 2)
    right = disc_views(RIGHT, right_from_board, board, diameter_m / 2)
    assert max(np.abs(c - project(LEFT, p, board)).max()
               for c, p in zip(left, left_from_board, strict=True)) > 0.5
    every = np.arange(board.corner_count)
    joint = calibrate_cameras(points, [BoardView(0, i, every, c) for i, c in enumerate(left)]
                              + [BoardView(1, i, every, c) for i, c in enumerate(right)],
                              [(W, H)] * 2, CalibrationOptions(tangential="zero"),
                              disc_diameter_m=diameter_m)
    result = stereo_result(joint, [(i, len(left) + i) for i in range(len(left))],
                           points_in_board=points, square_m=board.square_m)
    rig = {"left_model": joint.models[0], "right_model": joint.models[1], "r1": result.r1,
           "p1": result.p1, "r2": result.r2, "p2": result.p2}
    as_centres = epipolar_errors(left, right, **rig)
    assert math.sqrt(np.mean(np.square(as_centres))) > 5e-3 and result.epipolar_rms_px < 1e-6
    spacing = square_size(left, right, [every] * len(left), RectifiedPair(**rig),
                          points_in_board=points, square_m=board.square_m)
    assert abs(spacing / board.square_m - 1) > 1e-4
    assert abs(result.square_m / board.square_m - 1) < 1e-8

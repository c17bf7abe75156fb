"""Stereo extrinsics and rectification of a synthetic rig with a 0.02 m baseline along x."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration.stereo import (
    StereoResult,
    calibrate_stereo,
    epipolar_errors,
    orient_right_views,
    rectified_points,
)
from processors.errors import ProcessorError
from replay.camera import CameraModel

from .synthetic import BOARD, H, W, pose, random_poses, views

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


@pytest.fixture(scope="module")
def result(rig: tuple[list[np.ndarray], list[np.ndarray]]) -> StereoResult:
    left, right = rig
    return calibrate_stereo(BOARD.points_in_board(), left, right, left_model=LEFT,
                            right_model=RIGHT, square_m=BOARD.square_m)


def test_recovers_the_rig(result: StereoResult) -> None:
    assert result.baseline_m == pytest.approx(BASELINE_M, rel=0.002)
    np.testing.assert_allclose(result.right_from_left[:3, 3], RIGHT_FROM_LEFT[:3, 3],
                               atol=0.002 * BASELINE_M)
    assert result.rotation_deg == pytest.approx(0.5, abs=0.02)
    # the per-view spread overstates the joint estimate's scatter (about 10x here), so
    # only check it is not an understatement
    assert abs(result.baseline_m - BASELINE_M) < 3 * result.baseline_std_m
    # stereo RMS over both cameras' 2-D residuals: about sigma * sqrt(2)
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
    xl = rectified_points(left[0], LEFT, result.r1, result.p1)
    xr = rectified_points(right[0], RIGHT, result.r2, result.p2)
    assert np.abs(xl[:, 1] - xr[:, 1]).max() < 0.5
    assert (xl[:, 0] - xr[:, 0] > 0).all()


def test_square_size_from_triangulation(result: StereoResult) -> None:
    assert result.square_m == pytest.approx(BOARD.square_m, rel=0.01)


def test_epipolar_errors_grow_when_the_rig_is_wrong(
    result: StereoResult, rig: tuple[list[np.ndarray], list[np.ndarray]]
) -> None:
    left, right = rig
    good = epipolar_errors(left, right, left_model=LEFT, right_model=RIGHT, r1=result.r1,
                           p1=result.p1, r2=result.r2, p2=result.p2)
    assert np.sqrt(np.mean(np.square(good))) == pytest.approx(result.epipolar_rms_px, rel=0.05)
    # turn the right rectification by 0.5° about the baseline: rows slip by about f * 0.0087
    tilt = pose(np.array([math.radians(0.5), 0.0, 0.0]), np.zeros(3))[:3, :3]
    bad = epipolar_errors(left, right, left_model=LEFT, right_model=RIGHT, r1=result.r1,
                          p1=result.p1, r2=tilt @ result.r2, p2=result.p2)
    slip = result.p2[1, 1] * math.radians(0.5)
    assert np.median(bad) > 0.5 * slip > 10 * np.median(good)


def test_too_few_joint_views(rig: tuple[list[np.ndarray], list[np.ndarray]]) -> None:
    left, right = rig
    with pytest.raises(ProcessorError, match="too few joint stereo views"):
        calibrate_stereo(BOARD.points_in_board(), left[:4], right[:4], left_model=LEFT,
                         right_model=RIGHT, square_m=BOARD.square_m)


def test_a_pair_from_two_board_poses_is_rejected(
    result: StereoResult, rig: tuple[list[np.ndarray], list[np.ndarray]]
) -> None:
    """Two frames paired across a move of the board (approximate pairing) show different
    poses: that joint view is left out and the rig is the one the good views give."""
    left, right = rig
    mixed = list(right)
    mixed[4] = right[5]
    out = calibrate_stereo(BOARD.points_in_board(), left, mixed, left_model=LEFT,
                           right_model=RIGHT, square_m=BOARD.square_m)
    assert set(out.rejected) == {4} and "one pose" in out.rejected[4]
    assert out.view_ids == [i for i in range(len(left)) if i != 4]
    assert len(out.view_epipolar_px) == len(left) - 1
    assert out.baseline_m == pytest.approx(result.baseline_m, abs=2 * result.baseline_std_m)
    assert out.epipolar_rms_px < 2 * result.epipolar_rms_px
    assert not result.rejected and result.view_ids == list(range(len(left)))


def test_right_views_numbered_from_the_other_end_are_turned_back(
    rig: tuple[list[np.ndarray], list[np.ndarray]]
) -> None:
    left, right = rig
    flipped = [c[::-1].copy() if i % 3 == 0 else c for i, c in enumerate(right)]
    oriented = orient_right_views(BOARD.points_in_board(), left, flipped, left_model=LEFT,
                                  right_model=RIGHT)
    for a, b in zip(oriented, right, strict=True):
        np.testing.assert_array_equal(a, b)

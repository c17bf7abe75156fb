"""Corners measured on the board plane: on a strongly distorted lens they lose cornerSubPix's
bias, and whatever small error the guiding model has does not bring it back."""

from __future__ import annotations

import dataclasses

import numpy as np

from benchmarks.ideal_board import ideal_image, refinement_error_px, tilted_pose
from processors.calibration.board import Board
from processors.calibration.corners import refine_on_board, remeasures
from replay.camera import CameraModel

BOARD = Board(7, 6, 0.015)
#: the mono_fisheye scenario's lens: 176 degrees across
FISHEYE = CameraModel(640, 480, np.array([[231.7, 0.0, 322.3], [0.0, 231.9, 237.6],
                                          [0.0, 0.0, 1.0]]),
                      "equidistant", np.array([-0.040, 0.0012, -0.0008, 0.0001]))


def _near_the_corner() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A noise-free image of the board in the fisheye's top left corner, its pose and the
    true pixels of its corners."""
    pose = tilted_pose(FISHEYE, BOARD, np.array([120.0, 100.0]), 0.12, tilt_rad=0.5,
                       rng=np.random.default_rng(1))
    points = BOARD.points_in_board()
    true_px = FISHEYE.project(points @ pose[:3, :3].T + pose[:3, 3])
    return ideal_image(FISHEYE, pose, BOARD), pose, true_px


def _inwards(error_px: np.ndarray, at_px: np.ndarray) -> float:
    """The mean component of the errors towards the principal point (px)."""
    towards = np.array([FISHEYE.cx, FISHEYE.cy]) - at_px
    towards /= np.linalg.norm(towards, axis=1, keepdims=True)
    return float(np.mean(np.sum(error_px * towards, axis=1)))


def test_board_plane_corners_lose_the_bias_of_corner_subpix_on_a_fisheye() -> None:
    image, pose, true_px = _near_the_corner()
    plain = refinement_error_px(FISHEYE, pose, BOARD, image=image)
    assert plain is not None
    # a first calibration's model: principal point 0.3 px and fy 0.05 % off
    k = FISHEYE.k.copy()
    k[0, 2] += 0.3
    k[1, 1] *= 1.0005
    refined_px, ok = refine_on_board(image, dataclasses.replace(FISHEYE, k=k), pose,
                                     BOARD.points_in_board(), BOARD.square_m)
    assert ok.all()
    bias_before = _inwards(plain, true_px)
    bias_after = _inwards(refined_px - true_px, true_px)
    assert bias_before < -0.05  # cornerSubPix: outwards, on every corner alike
    assert abs(bias_after) < 0.2 * abs(bias_before)
    rms_before = np.sqrt(np.mean(np.sum(plain ** 2, axis=1)))
    rms_after = np.sqrt(np.mean(np.sum((refined_px - true_px) ** 2, axis=1)))
    assert rms_after < 0.7 * rms_before


def test_a_corner_whose_patch_leaves_the_image_is_not_measured() -> None:
    image, pose, _ = _near_the_corner()
    points = BOARD.points_in_board()
    # four squares beyond the board's last corner (the one nearest the image's top left)
    beyond = points[-1:] + np.array([4 * BOARD.square_m, 4 * BOARD.square_m, 0.0])
    beyond_px = FISHEYE.project(beyond @ pose[:3, :3].T + pose[:3, 3])[0]
    assert min(beyond_px) < 8  # nearer the border than half a patch
    _, ok = refine_on_board(image, FISHEYE, pose, np.concatenate([points, beyond]),
                            BOARD.square_m)
    assert ok[:-1].all()
    assert not ok[-1]


def test_only_fisheye_corners_are_measured_again() -> None:
    assert remeasures("equidistant")
    assert not remeasures("plumb_bob")
    assert not remeasures("rational_polynomial")

"""Corners measured on the board plane: on a strongly distorted lens they lose cornerSubPix's
bias, and whatever small error the guiding model has does not bring it back."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from benchmarks.ideal_board import ideal_image, refinement_error_px, tilted_pose
from processors.calibration.board import Board
from processors.calibration.corners import cross_corners, edge_band_m, refine_on_board, remeasures
from replay.camera import CameraModel

BOARD = Board(7, 6, 0.015)
#: the mono_fisheye scenario's lens: 176 degrees across
FISHEYE = CameraModel(640, 480, np.array([[231.7, 0.0, 322.3], [0.0, 231.9, 237.6],
                                          [0.0, 0.0, 1.0]]),
                      "equidistant", np.array([-0.040, 0.0012, -0.0008, 0.0001]))
#: the mono_charuco scenario's board (squares 7 x 5 inner corners) and lens
CHARUCO = Board(7, 5, 0.011, pattern="charuco", marker_m=0.008)
RATIONAL = CameraModel(640, 480, np.array([[512.3, 0.0, 318.2], [0.0, 513.1, 242.6],
                                           [0.0, 0.0, 1.0]]), "rational_polynomial",
                       np.array([-0.32, 0.11, 0.0004, -0.0003, -0.018, 0.02, 0.01, -0.004]))


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


@pytest.mark.slow
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


@pytest.mark.slow
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


def test_fisheye_chessboard_corners_and_every_charuco_corner_are_measured_again() -> None:
    assert remeasures(BOARD, "equidistant")
    assert not remeasures(BOARD, "plumb_bob")
    assert not remeasures(BOARD, "rational_polynomial")
    assert remeasures(CHARUCO, "rational_polynomial")
    assert remeasures(CHARUCO, "plumb_bob")
    assert not remeasures(Board(4, 11, 0.01, pattern="acircles"), "equidistant")
    assert edge_band_m(BOARD) is None
    assert edge_band_m(CHARUCO) == pytest.approx(0.00075)


def _saddle(corner: np.ndarray, *, marker: float, noise: float, rng: np.random.Generator,
            side: int = 61, square: float = 40.0) -> np.ndarray:
    """A fronto-parallel ``side`` x ``side`` patch of a chessboard corner at ``corner`` (x, y
    samples), squares ``square`` samples wide, a dark marker ``marker`` samples wide in the
    middle of each bright square, area-sampled (32 x 32 per sample), blurred by 1 sample."""
    sub = (np.arange(32) + 0.5) / 32 - 0.5
    ys, xs = np.mgrid[0:side, 0:side].astype(np.float64)
    a = (xs[..., None, None] + sub[None, None, None, :] - corner[0]) / square
    b = (ys[..., None, None] + sub[None, None, :, None] - corner[1]) / square
    dark = (np.floor(a) + np.floor(b)) % 2 == 0
    if marker:
        half = marker / (2 * square)
        dark |= (np.abs(a - np.floor(a) - 0.5) < half) & (np.abs(b - np.floor(b) - 0.5) < half)
    image = cv2.GaussianBlur(np.where(dark, 30.0, 220.0).mean(axis=(2, 3)), (0, 0), 1.0)
    return (image + rng.normal(0.0, noise, image.shape)).astype(np.float32)


@pytest.mark.slow
def test_cross_corners_use_the_edges_beyond_the_markers() -> None:
    """Around a ChArUco corner (markers 29/40 of a square), the two edges alone locate the
    corner with less noise than cornerSubPix in the small window that stays clear of the
    markers, and without their pull."""
    rng = np.random.default_rng(0)
    found_cross, found_small = [], []
    for _ in range(40):
        corner = 30.0 + rng.uniform(-0.5, 0.5, 2)
        patch = _saddle(corner, marker=29.0, noise=3.0, rng=rng)
        found_cross.append(cross_corners(patch[None], 18, np.array([11.0 / 4]))[0] - corner)
        start = np.array([[[30.0, 30.0]]], np.float32)
        small = cv2.cornerSubPix(patch, start, (4, 4), (-1, -1),
                                 (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 1e-3))
        found_small.append(small.reshape(2) - corner)
    rms_cross = float(np.sqrt(np.mean(np.sum(np.square(found_cross), axis=1))))
    rms_small = float(np.sqrt(np.mean(np.sum(np.square(found_small), axis=1))))
    assert rms_cross < 0.05
    assert rms_cross < 0.75 * rms_small
    assert np.abs(np.mean(found_cross, axis=0)).max() < 0.015


@pytest.mark.slow
def test_charuco_corners_on_the_board_plane_are_not_pulled_by_the_markers() -> None:
    """On the mono_charuco lens, noise-free: cornerSubPix on the board plane with a
    chessboard's window is pulled by the markers; the edge bands are not."""
    pose = tilted_pose(RATIONAL, CHARUCO, np.array([500.0, 380.0]), 0.2, tilt_rad=0.7,
                       rng=np.random.default_rng(2))
    points = CHARUCO.points_in_board()
    true_px = RATIONAL.project(points @ pose[:3, :3].T + pose[:3, 3])
    image = ideal_image(RATIONAL, pose, CHARUCO, supersample=8, marker_m=CHARUCO.marker_m)
    errors = {}
    for band in (None, edge_band_m(CHARUCO)):
        refined, ok = refine_on_board(image, RATIONAL, pose, points, CHARUCO.square_m,
                                      band_m=band)
        assert ok.sum() >= 0.9 * len(points)
        errors[band] = refined[ok] - true_px[ok]
    pulled, banded = errors[None], errors[edge_band_m(CHARUCO)]
    assert np.linalg.norm(banded.mean(axis=0)) < 0.5 * np.linalg.norm(pulled.mean(axis=0))
    assert np.sqrt(np.mean(np.sum(banded ** 2, axis=1))) \
        < np.sqrt(np.mean(np.sum(pulled ** 2, axis=1)))

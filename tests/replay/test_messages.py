"""Typed records: entry checks, equality, array conversion."""

from __future__ import annotations

import numpy as np
import pytest

from replay import (
    IMAGE_ENCODINGS,
    CameraInfo,
    EncodingError,
    Image,
    PointStamped,
    PoseStamped,
)

from .samples import random_pixels


@pytest.mark.parametrize("encoding", sorted(IMAGE_ENCODINGS))
def test_image_accepts_its_encoding_and_reports_size(encoding: str) -> None:
    pixels = random_pixels(encoding, height=4, width=6)  # even: nv21 shares chroma by 2x2
    image = Image(7, "cam", encoding, pixels)
    assert (image.width, image.height) == (6, 4)


@pytest.mark.parametrize(
    ("encoding", "pixels"),
    [
        ("rgb8", np.zeros((4, 4), np.uint8)),  # missing channel axis
        ("rgb8", np.zeros((4, 4, 4), np.uint8)),  # wrong channel count
        ("mono8", np.zeros((4, 4), np.uint16)),  # wrong dtype
        ("mono16", np.zeros((4, 4, 1), np.uint16)),  # one channel must be 2-D
    ],
)
def test_image_rejects_pixels_that_do_not_match(encoding: str, pixels: np.ndarray) -> None:
    with pytest.raises(EncodingError, match=encoding):
        Image(0, "cam", encoding, pixels)


def test_image_rejects_unknown_encoding_and_lists_supported() -> None:
    with pytest.raises(EncodingError, match=r"'yuv411'.*supported: .*rgb8"):
        Image(0, "cam", "yuv411", np.zeros((2, 2), np.uint8))


def test_image_equality_compares_pixels_and_metadata() -> None:
    pixels = random_pixels("rgb8")
    image = Image(1, "cam", "rgb8", pixels)
    assert image == Image(1, "cam", "rgb8", pixels.copy())
    changed = pixels.copy()
    changed[0, 0, 0] ^= 1
    assert image != Image(1, "cam", "rgb8", changed)
    assert image != Image(2, "cam", "rgb8", pixels)
    assert image != Image(1, "other", "rgb8", pixels)
    assert image != Image(1, "cam", "bgr8", pixels)
    mono = random_pixels("mono8")
    assert Image(1, "cam", "mono8", mono) != Image(1, "cam", "8UC1", mono)


def test_camera_info_defaults_and_array_conversion() -> None:
    info = CameraInfo(5, "cam", 640, 480, "plumb_bob", d=[0.1, 0.2, 0, 0, 0], k=np.eye(3))
    assert info.d.dtype == np.float64 and info.d.shape == (5,)
    assert np.array_equal(info.r, np.eye(3))
    assert info.p.shape == (3, 4) and not info.p.any()
    assert info == CameraInfo(5, "cam", 640, 480, "plumb_bob", d=np.array([0.1, 0.2, 0, 0, 0]),
                              k=np.eye(3).tolist())
    assert info != CameraInfo(5, "cam", 640, 480, "plumb_bob", d=[0.1, 0.2, 0, 0, 0],
                              k=2 * np.eye(3))


def test_camera_info_rejects_wrong_matrix_shape() -> None:
    with pytest.raises(ValueError, match=r"CameraInfo.k must have shape \(3, 3\)"):
        CameraInfo(0, "cam", 640, 480, "plumb_bob", d=[], k=np.eye(4))


def test_pose_and_point_convert_to_float64_and_compare_by_value() -> None:
    pose = PoseStamped(3, "world", [1, 2, 3], [0, 0, 0, 1])
    assert pose.position_m.dtype == np.float64
    assert pose == PoseStamped(3, "world", np.array([1.0, 2.0, 3.0]), np.array([0, 0, 0, 1.0]))
    assert pose != PoseStamped(3, "world", [1, 2, 3.5], [0, 0, 0, 1])
    point = PointStamped(4, "world", [1, 2, 3])
    assert point.point.dtype == np.float64
    assert point == PointStamped(4, "world", [1.0, 2.0, 3.0])
    assert point != PointStamped(4, "map", [1.0, 2.0, 3.0])

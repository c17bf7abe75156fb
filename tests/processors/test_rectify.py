"""Rectification: dots placed where a distorted camera sees them land where the ideal one does."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from processors.errors import ConfigError, FrameError
from processors.rectify import Rectifier
from replay import CameraInfo, Image
from replay.camera import CameraModel
from replay.frames import Frame, decode_frame

W, H = 160, 120
K = np.array([[140.0, 0, 81.0], [0, 138.0, 58.5], [0, 0, 1]])
D = np.array([-0.35, 0.12, 0.001, -0.002, 0.0])


def frame_of(*fields: Any) -> Frame:
    """The frame of an Image message built from ``fields``."""
    return decode_frame(Image(*fields))


def blobs(uv: np.ndarray, sigma: float = 1.2) -> np.ndarray:
    """mono8 image with a Gaussian dot at each sub-pixel position ``(N, 2)``."""
    ys, xs = np.mgrid[0:H, 0:W]
    img = np.zeros((H, W))
    for u, v in uv:
        img += np.exp(-((xs - u) ** 2 + (ys - v) ** 2) / (2 * sigma**2))
    return np.clip(img * 250, 0, 255).astype(np.uint8)


def dot_centres(img: np.ndarray, near: np.ndarray, radius: int = 5) -> np.ndarray:
    out = []
    ys, xs = np.mgrid[0:H, 0:W]
    for u, v in near:
        window = (np.abs(xs - u) <= radius) & (np.abs(ys - v) <= radius)
        weight = img.astype(np.float64) * window
        out.append([(weight * xs).sum() / weight.sum(), (weight * ys).sum() / weight.sum()])
    return np.array(out)


def test_distorted_dots_move_to_their_ideal_positions() -> None:
    info = CameraInfo(0, "cam", W, H, "plumb_bob", D, K, np.eye(3),
                      np.hstack([K, np.zeros((3, 1))]))
    model = CameraModel.from_camera_info(info)
    ideal_uv = np.array([[20.0, 15.0], [140.0, 20.0], [81.0, 58.5], [25.0, 100.0],
                         [135.5, 104.0], [60.3, 40.7]])
    xy = (ideal_uv - K[:2, 2]) / np.diag(K)[:2]
    raw_uv = model.distort_normalized(xy)
    assert np.max(np.linalg.norm(raw_uv - ideal_uv, axis=1)) > 4  # distortion matters here
    (topic, out), = Rectifier(camera_info=info)(frame_of(3, "cam", "mono8", blobs(raw_uv)))
    assert topic == "image_rect" and isinstance(out, Image)
    assert (out.encoding, out.stamp_ns, out.pixels.shape) == ("mono8", 3, (H, W))
    found = dot_centres(out.pixels, ideal_uv)
    np.testing.assert_allclose(found, ideal_uv, atol=0.15)


def test_colour_images_keep_their_encoding() -> None:
    info = CameraInfo(0, "cam", W, H, "plumb_bob", np.zeros(5), K)  # P all zero: use K
    rgb = np.random.default_rng(0).integers(0, 256, (H, W, 3), dtype=np.uint8)
    (_, out), = Rectifier(camera_info=info)(frame_of(0, "", "rgb8", rgb))
    assert isinstance(out, Image) and out.encoding == "rgb8"
    np.testing.assert_array_equal(out.pixels, rgb)  # no distortion, same camera: identity


def test_wrong_size_and_models_are_rejected() -> None:
    info = CameraInfo(0, "cam", W, H, "plumb_bob", D, K)
    with pytest.raises(FrameError, match="160x120"):
        Rectifier(camera_info=info)(frame_of(0, "", "mono8", np.zeros((H, W + 2), np.uint8)))
    with pytest.raises(ConfigError, match="kannala_brandt8"):
        Rectifier(camera_info=CameraInfo(0, "", W, H, "kannala_brandt8", np.zeros(8), K))


def test_equidistant_dots_move_to_their_pinhole_positions() -> None:
    """A fisheye model (ROS ``equidistant``) rectifies through OpenCV's fisheye maps."""
    k_fisheye = np.array([[70.0, 0, 80.5], [0, 70.0, 59.0], [0, 0, 1]])
    d_fisheye = np.array([0.03, -0.01, 0.002, 0.0])
    new_k = np.array([[60.0, 0, 79.5], [0, 60.0, 59.5], [0, 0, 1]])
    info = CameraInfo(0, "cam", W, H, "equidistant", d_fisheye, k_fisheye, np.eye(3),
                      np.hstack([new_k, np.zeros((3, 1))]))
    model = CameraModel.from_camera_info(info)
    ideal_uv = np.array([[20.0, 15.0], [140.0, 20.0], [79.5, 59.5], [25.0, 100.0]])
    rays = np.column_stack([ideal_uv, np.ones(len(ideal_uv))]) @ np.linalg.inv(new_k).T
    raw_uv = model.project(rays)
    assert np.max(np.linalg.norm(raw_uv - ideal_uv, axis=1)) > 4
    (_, out), = Rectifier(camera_info=info)(frame_of(0, "cam", "mono8", blobs(raw_uv)))
    assert isinstance(out, Image)
    np.testing.assert_allclose(dot_centres(out.pixels, ideal_uv), ideal_uv, atol=0.2)

"""Undistortion: dots placed where a distorted camera sees them land where K projects them,
whatever the calibration's rectification (R, P) says."""

from __future__ import annotations

import numpy as np
import pytest

from processors.errors import FrameError, OptionValueError
from processors.rectify import Rectifier
from processors.undistort import Undistort
from replay import CameraInfo, Image
from replay.camera import CameraModel
from replay.frames import decode_frame
from replay.geometry import rotation_about
from tests.processors.test_rectify import D, H, K, W, blobs, dot_centres


def stereo_info() -> CameraInfo:
    """A left camera of a rectified pair: R turns it by 2 degrees, P has another fx."""
    p = np.hstack([K, np.zeros((3, 1))])
    p[0, 0] = p[1, 1] = 120.0
    turn = rotation_about(np.array([0.0, 1.0, 0.0]), 0.035)
    return CameraInfo(0, "cam", W, H, "plumb_bob", D, K, turn, p)


def test_distorted_dots_move_to_where_k_projects_them() -> None:
    info = stereo_info()
    model = CameraModel.from_camera_info(info)
    ideal_uv = np.array([[20.0, 15.0], [140.0, 20.0], [81.0, 58.5], [25.0, 100.0],
                         [135.5, 104.0], [60.3, 40.7]])
    raw_uv = model.distort_normalized((ideal_uv - K[:2, 2]) / np.diag(K)[:2])
    assert np.max(np.linalg.norm(raw_uv - ideal_uv, axis=1)) > 4  # distortion matters here
    raw = decode_frame(Image(5, "cam", "mono8", blobs(raw_uv)))
    ((name, out),) = Undistort(camera_info=info)(raw)
    assert name == "image_undistorted" and isinstance(out, Image)
    assert (out.encoding, out.stamp_ns, out.frame_id, out.pixels.shape) == ("mono8", 5, "cam",
                                                                          (H, W))
    np.testing.assert_allclose(dot_centres(out.pixels, ideal_uv), ideal_uv, atol=0.15)
    # rectification with the same file puts them elsewhere (R and P's fx)
    ((_, rect),) = Rectifier(camera_info=info)(raw)
    assert isinstance(rect, Image) and not np.array_equal(rect.pixels, out.pixels)


def test_no_distortion_is_the_identity() -> None:
    info = CameraInfo(0, "cam", W, H, "plumb_bob", np.zeros(5), K)
    rgb = np.random.default_rng(1).integers(0, 256, (H, W, 3), dtype=np.uint8)
    ((_, out),) = Undistort(camera_info=info)(decode_frame(Image(0, "", "rgb8", rgb)))
    assert isinstance(out, Image) and out.encoding == "rgb8"
    np.testing.assert_array_equal(out.pixels, rgb)


def test_wrong_size_and_models_are_rejected() -> None:
    with pytest.raises(FrameError, match="160x120"):
        frame = decode_frame(Image(0, "", "mono8", np.zeros((H, 9), np.uint8)))
        Undistort(camera_info=stereo_info())(frame)
    with pytest.raises(OptionValueError) as err:
        Undistort(camera_info=CameraInfo(0, "", W, H, "kannala_brandt8", np.zeros(8), K))
    assert (err.value.processor, err.value.options) == ("undistort", ("camera_info",))

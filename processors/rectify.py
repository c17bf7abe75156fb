"""Rectification (``image_proc``'s ``image_rect``) with maps computed once per camera model."""

from __future__ import annotations

import cv2
import numpy as np

from replay.camera import DISTORTION_MODELS
from replay.messages import CameraInfo, Image

from .base import Output
from .errors import ConfigError, FrameError

IMAGE_RECT = "/image_converter/image_rect"


class Rectifier:
    """Undistort and rectify with ``K``, ``D``, ``R`` and ``P`` of a camera model.

    Output pixel ``(u, v)`` of the rectified camera ``P[:, :3]`` samples the raw image
    where ``R`` and the distorted model ``K, D`` put it (bilinear), as image_proc does.
    The output keeps the input encoding and size.
    """

    name = "rectify"

    def __init__(self, *, camera_info: CameraInfo) -> None:
        info = camera_info
        model = info.distortion_model or "plumb_bob"
        if model not in DISTORTION_MODELS:
            raise ConfigError(
                f"cannot rectify distortion model {model!r} (use {' or '.join(DISTORTION_MODELS)})"
            )
        if info.binning_x > 1 or info.binning_y > 1 or any(info.roi[:4]):
            raise ConfigError("rectifying binned or ROI camera models is not supported")
        if info.width <= 0 or info.height <= 0:
            raise ConfigError(f"camera model has no image size ({info.width}x{info.height})")
        new_k = info.p[:, :3] if np.any(info.p[:, :3]) else info.k
        self.width, self.height = info.width, info.height
        # fixed-point maps: remap is faster and they are computed once
        self.map1, self.map2 = cv2.initUndistortRectifyMap(
            info.k, info.d, info.r, new_k, (info.width, info.height), cv2.CV_16SC2
        )

    def outputs(self) -> dict[str, str]:
        """Output topic -> message kind."""
        return {IMAGE_RECT: "sensor_msgs/msg/Image"}

    def __call__(self, image: Image) -> list[Output]:
        if (image.width, image.height) != (self.width, self.height):
            raise FrameError(
                f"image is {image.width}x{image.height} but the calibration is for "
                f"{self.width}x{self.height}"
            )
        pixels: np.ndarray = image.pixels
        rect = cv2.remap(pixels, self.map1, self.map2, cv2.INTER_LINEAR)
        return [(IMAGE_RECT, Image(image.stamp_ns, image.frame_id, image.encoding, rect))]

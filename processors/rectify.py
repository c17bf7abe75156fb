"""Rectification (``image_proc``'s ``image_rect``) with maps computed once per camera model."""

from __future__ import annotations

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.frames import Frame, encode_image
from replay.lens_models import LENS_MODELS, canonical_name
from replay.messages import F64, CameraInfo

from .base import Output
from .errors import FrameError, OptionValueError


class Remap:
    """Resample images of one camera model through fixed maps: output pixel ``(u, v)`` of
    the camera ``new_k`` (turned by ``rotation``) samples the raw image where the distorted
    model ``K, D`` puts its ray (bilinear), as image_proc does. Outputs keep the input
    encoding and size. ``processor`` and ``output`` name the errors and the output."""

    def __init__(self, info: CameraInfo, *, rotation: F64, new_k: F64, processor: str,
                 output: str) -> None:
        model = canonical_name(info.distortion_model)
        problem = None
        if model not in LENS_MODELS:
            problem = (f"cannot resample distortion model {model!r} (use "
                       f"{', '.join(LENS_MODELS)})")
        elif info.binning_x > 1 or info.binning_y > 1 or any(info.roi[:4]):
            problem = "binned or ROI camera models are not supported"
        elif info.width <= 0 or info.height <= 0:
            problem = f"the camera model has no image size ({info.width}x{info.height})"
        if problem is not None:
            raise OptionValueError(processor, ("camera_info",), problem)
        self.output = output
        self.width, self.height = info.width, info.height
        # fixed-point maps: remap is faster and they are computed once (OpenCV's fisheye
        # maps for an equidistant lens)
        self.map1, self.map2 = CameraModel.from_camera_info(info).rectify_maps(
            rotation, new_k, cv2.CV_16SC2)

    def __call__(self, frame: Frame) -> list[Output]:
        """The resampled image (same colour order and bit depth) under this remap's output
        name."""
        if (frame.width, frame.height) != (self.width, self.height):
            raise FrameError(
                f"image is {frame.width}x{frame.height} but the calibration is for "
                f"{self.width}x{self.height}"
            )
        out = cv2.remap(frame.pixels, self.map1, self.map2, cv2.INTER_LINEAR)
        return [(self.output, encode_image(frame.with_pixels(out)))]


class Rectifier(Remap):
    """Undistort and rectify with ``K``, ``D``, ``R`` and ``P`` of a camera model (the
    rectified camera is ``P[:, :3]``, or ``K`` when P is empty)."""

    def __init__(self, *, camera_info: CameraInfo) -> None:
        info = camera_info
        new_k = info.p[:, :3] if np.any(info.p[:, :3]) else info.k
        super().__init__(info, rotation=info.r, new_k=new_k, processor="rectify",
                         output="image_rect")

"""A distorted camera as rerun can show it: pinhole views remapped from its raw images.

rerun's ``Pinhole`` has no lens distortion. A camera whose camera_info is not a pinhole
already gets the views :func:`replay.pinhole_views.pinhole_views` chooses (``undistorted``,
``wide`` for a fisheye that sees further, ``rectified`` for a camera of a rectified stereo
pair), each a ``Pinhole`` entity under the camera whose image is the raw image remapped to it.
:class:`Lens` holds one camera model's views and their ``cv2.remap`` maps, made once per
model; :meth:`Lens.remap` runs on the export's worker threads (OpenCV releases the GIL).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.frames import Color, Frame, decode_frame
from replay.messages import F64, CameraInfo, CompressedImage
from replay.pinhole_views import PinholeView, pinhole_views

from .columns import ImageRow
from .images import COLOR_MODELS, rerun_image

__all__ = ["VIEW_PLANE_DEPTHS", "Lens", "views_of"]

#: how far each view's image plane is drawn, relative to the camera's frustum depth (the
#: wide view behind the undistorted one, so that both show)
VIEW_PLANE_DEPTHS = {"undistorted": 1.0, "rectified": 1.0, "wide": 1.6}


def views_of(info: CameraInfo, scale: float) -> list[PinholeView]:
    """The pinhole views of ``info`` (a camera that is a pinhole already gets one view of
    its own ``K``, so that a camera shown through views stays so when its model changes)."""
    views = pinhole_views(info, scale=scale)
    if views:
        return views
    width, height = max(1, round(info.width * scale)), max(1, round(info.height * scale))
    sx, sy = width / info.width, height / info.height
    k = np.array([[info.k[0, 0] * sx, info.k[0, 1] * sx, sx * (info.k[0, 2] + 0.5) - 0.5],
                  [0.0, info.k[1, 1] * sy, sy * (info.k[1, 2] + 0.5) - 0.5],
                  [0.0, 0.0, 1.0]])
    return [PinholeView("undistorted", k, width, height, np.eye(3), 1.0)]


@dataclass(frozen=True)
class Lens:
    """One camera model (``info``) shown through pinhole views, with their remap maps."""

    info: CameraInfo
    model: CameraModel
    views: list[PinholeView]
    maps: list[tuple[np.ndarray, np.ndarray]]

    @classmethod
    def of(cls, info: CameraInfo, views: list[PinholeView]) -> Lens:
        """The lens of ``info`` shown through ``views`` (their maps are built here)."""
        model = CameraModel.from_camera_info(info)
        return cls(info, model, views, [view.maps(model) for view in views])

    def remap(self, source: Frame | CompressedImage, index: int, *,
              jpeg_quality: int | None = None, draw_order: float | None = None) -> Any:
        """The image of view ``index`` made from a raw frame (or a compressed image, decoded
        here): a row of pixels, a JPEG when ``jpeg_quality`` is given, a depth image with its
        metre scale (sampled at the nearest pixel: depths do not blend)."""
        frame = source if isinstance(source, Frame) else decode_frame(source)
        map1, map2 = self.maps[index]
        depth = frame.color is Color.DEPTH
        pixels = cv2.remap(frame.pixels, map1, map2,
                           cv2.INTER_NEAREST if depth else cv2.INTER_LINEAR,
                           borderMode=cv2.BORDER_CONSTANT)
        if depth or (jpeg_quality is not None and pixels.dtype == np.uint8):
            return rerun_image(frame.with_pixels(pixels), jpeg_quality=jpeg_quality,
                               draw_order=draw_order)
        return ImageRow(pixels, COLOR_MODELS[frame.color], draw_order)

    def remap_field(self, field_raw: F64, index: int) -> F64:
        """A value per raw pixel ``(H, W)`` seen through view ``index`` (NaN outside the
        raw image)."""
        map1, map2 = self.maps[index]
        return np.asarray(cv2.remap(field_raw.astype(np.float32), map1, map2, cv2.INTER_LINEAR,
                                    borderMode=cv2.BORDER_CONSTANT, borderValue=float("nan")),
                          dtype=np.float64)

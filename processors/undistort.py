"""Undistortion to the same camera matrix: the image an ideal pinhole camera ``K`` would see.

Unlike :class:`processors.rectify.Rectifier` it ignores ``R`` and ``P`` (a stereo pair's
rectification): each output pixel ``(u, v)`` shows the ray ``K^-1 (u, v, 1)``, sampled in
the raw image where the distorted model ``K, D`` puts that ray (bilinear), as
``cv2.undistort`` does.
"""

from __future__ import annotations

import numpy as np

from replay.messages import CameraInfo

from .rectify import Remap


class Undistort(Remap):
    """Remove lens distortion, keeping ``K``, the input encoding and size."""

    def __init__(self, *, camera_info: CameraInfo) -> None:
        super().__init__(camera_info, rotation=np.eye(3), new_k=camera_info.k,
                         processor="undistort", output="image_undistorted")

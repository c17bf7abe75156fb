"""Red pixels and their centroid (the chapter's ``find_red_pixels`` node).

A pixel is red when ``R > ratio * (G + B)`` in integer arithmetic. The node publishes the
black/white mask with a blue square at the centroid, the centroid in pixels and the count.
"""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt

from replay.frames import Frame
from replay.messages import Image, PointStamped

from .base import Output
from .errors import ConfigError, OptionValueError

U8 = npt.NDArray[np.uint8]

#: output names (declared in the registry)
OUTPUT_VIDEO, CENTROID, COUNT = "output_video", "red_centroid", "red_count"
#: the centroid marker is a filled square of (2 * HALF_BOX + 1) pixels, as in the chapter
HALF_BOX = 5
BLUE_RGB = (0, 0, 255)


def red_mask(rgb: U8, ratio: int = 10) -> U8:
    """``(H, W)`` uint8 mask, 255 where ``R > ratio * (G + B)`` of an ``(H, W, 3)`` RGB image.

    Computed with saturating uint8 arithmetic, which is exact here: once ``G + B`` or
    ``ratio * (G + B)`` saturates at 255 the true product is >= 255 >= R, so both sides say
    "not red".

    >>> red_mask(np.array([[[255, 10, 15], [255, 10, 16]]], np.uint8)).tolist()
    [[255, 0]]
    """
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise ConfigError(f"red_mask needs (H, W, 3) uint8, got {rgb.dtype}{list(rgb.shape)}")
    if ratio < 0:
        raise ConfigError(f"red ratio must be >= 0, got {ratio}")
    r, g, b = cv2.split(rgb)
    bound = cv2.convertScaleAbs(cv2.add(g, b), alpha=float(ratio))  # saturating
    return np.asarray(cv2.compare(r, bound, cv2.CMP_GT), dtype=np.uint8)


def mask_centroid(mask: U8) -> tuple[float, float, int]:
    """``(u, v, count)`` of the nonzero pixels of an ``(H, W)`` mask; u, v are NaN if none.

    ``u`` is the mean column and ``v`` the mean row (pixel centres at integer coordinates).
    """
    moments = cv2.moments(mask, binaryImage=True)
    count = round(moments["m00"])
    if count == 0:
        return float("nan"), float("nan"), 0
    return moments["m10"] / count, moments["m01"] / count, count


def draw_marker(mask: U8, u: float, v: float) -> U8:
    """``(H, W, 3)`` RGB copy of a mask with a blue square centred on pixel ``(u, v)``."""
    out = np.asarray(cv2.cvtColor(mask, cv2.COLOR_GRAY2RGB), dtype=np.uint8)
    if np.isfinite(u) and np.isfinite(v):
        col, row = round(u), round(v)
        out[max(row - HALF_BOX, 0): row + HALF_BOX + 1,
            max(col - HALF_BOX, 0): col + HALF_BOX + 1] = BLUE_RGB
    return out


class RedPixels:
    """``find_red_pixels``: mask video, centroid (x = u, y = v pixels) and count (x = count).

    Nothing goes to the centroid topic when no pixel is red; the count is always published.
    """

    def __init__(self, *, ratio: int = 10) -> None:
        if ratio < 0:
            raise OptionValueError("red_pixels", ("ratio",), f"must be >= 0, got {ratio}")
        self.ratio = ratio

    def __call__(self, frame: Frame) -> list[Output]:
        mask = red_mask(frame.rgb8(), self.ratio)
        u, v, count = mask_centroid(mask)
        stamp, frame_id = frame.stamp_ns, frame.frame_id
        out: list[Output] = [
            (OUTPUT_VIDEO, Image(stamp, frame_id, "rgb8", draw_marker(mask, u, v))),
        ]
        if count:
            out.append((CENTROID, PointStamped(stamp, frame_id, np.array([u, v, 0.0]))))
        out.append((COUNT, PointStamped(stamp, frame_id, np.array([float(count), 0.0, 0.0]))))
        return out

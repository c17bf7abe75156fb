"""A decoded camera frame: pixels as numpy with their colour order, depth unit and stamp."""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import StrEnum

import numpy as np
import numpy.typing as npt

from ..arrays import Pixels, PixelShape

__all__ = ["Color", "Frame", "Pixels"]

U8 = npt.NDArray[np.uint8]


class Color(StrEnum):
    """What the channels of a frame's pixels mean, in order."""

    RGB = "rgb"
    BGR = "bgr"
    RGBA = "rgba"
    BGRA = "bgra"
    MONO = "mono"
    DEPTH = "depth"  # one channel of distances, ``depth_unit_m`` metres per value


#: colour -> (channels, OpenCV conversion to RGB, to BGR, to grey), each the name of its ``cv2``
#: constant (OpenCV is imported on the first conversion, not by opening a log); None: no
#: conversion
_CONVERSIONS: dict[Color, tuple[int, str | None, str | None, str | None]] = {
    Color.RGB: (3, None, "COLOR_RGB2BGR", "COLOR_RGB2GRAY"),
    Color.BGR: (3, "COLOR_BGR2RGB", None, "COLOR_BGR2GRAY"),
    Color.RGBA: (4, "COLOR_RGBA2RGB", "COLOR_RGBA2BGR", "COLOR_RGBA2GRAY"),
    Color.BGRA: (4, "COLOR_BGRA2RGB", "COLOR_BGRA2BGR", "COLOR_BGRA2GRAY"),
    Color.MONO: (1, "COLOR_GRAY2RGB", "COLOR_GRAY2BGR", None),
    Color.DEPTH: (1, "COLOR_GRAY2RGB", "COLOR_GRAY2BGR", None),
}


@dataclass(frozen=True, slots=True, eq=False)
class Frame(PixelShape):
    """One camera image decoded from any message kind and encoding.

    ``pixels`` is ``(H, W)`` for ``MONO`` and ``DEPTH``, ``(H, W, C)`` otherwise, channels in
    ``color`` order; uint8 or uint16 (float32 for float depth). ``source`` names what the
    frame was decoded from (``rgb8``, ``jpeg``, ``bayer_rggb8``...). A depth frame's
    values times ``depth_unit_m`` are metres (0 and non-finite values: no measurement).
    """

    stamp_ns: int
    frame_id: str
    pixels: Pixels
    color: Color
    source: str = ""
    depth_unit_m: float | None = None

    def __post_init__(self) -> None:
        channels = _CONVERSIONS[self.color][0]
        px = self.pixels
        ok = px.ndim == 2 if channels == 1 else px.ndim == 3 and px.shape[2] == channels
        if not ok:
            raise ValueError(f"{self.color} frame needs {channels} channel(s), got pixels "
                             f"{px.dtype}{list(px.shape)}")
        if (self.color is Color.DEPTH) != (self.depth_unit_m is not None):
            raise ValueError("a depth frame, and only a depth frame, has a depth unit")

    def with_pixels(self, pixels: Pixels) -> Frame:
        """The same frame (stamp, colour order, unit) holding other pixels, e.g. rectified."""
        return replace(self, pixels=pixels)

    def rgb8(self) -> U8:
        """``(H, W, 3)`` uint8 RGB; the pixels themselves when they already are."""
        return self._convert(1)

    def bgr8(self) -> U8:
        """``(H, W, 3)`` uint8 BGR (what OpenCV draws on and encodes)."""
        return self._convert(2)

    def mono8(self) -> U8:
        """``(H, W)`` uint8 grey."""
        return self._convert(3)

    def to8(self) -> U8:
        """The pixels in their own colour order with 8-bit channels (16-bit: top byte;
        depth: scaled so the farthest measured value is 255)."""
        px = self.pixels
        if px.dtype == np.uint8:
            return px
        if self.color is Color.DEPTH:
            values = np.nan_to_num(px.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0)
            top = float(values.max(initial=0.0))
            scaled = values * (255.0 / top) if top > 0 else values
            return np.clip(scaled, 0, 255).astype(np.uint8)
        if px.dtype == np.uint16:
            return (px >> 8).astype(np.uint8)
        if px.dtype == np.int16:
            return (px.astype(np.int32) + 32768 >> 8).astype(np.uint8)
        return np.clip(px, 0, 255).astype(np.uint8)

    def _convert(self, which: int) -> U8:
        code = _CONVERSIONS[self.color][which]
        px = self.to8()
        if code is None or isinstance(code, int):
            return px
        import cv2

        return np.asarray(cv2.cvtColor(px, getattr(cv2, code)), dtype=np.uint8)

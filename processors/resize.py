"""Resizing to a size in pixels or by a scale (image_proc's ``resize``).

Pixel centres stay at integer coordinates: output pixel ``x'`` covers input
``(x' + 0.5) * W / W' - 0.5``, OpenCV's convention. Shrinking averages the covered input
pixels (``INTER_AREA``, no aliasing); enlarging interpolates bilinearly.
"""

from __future__ import annotations

import math

import cv2

from replay.frames import Frame, encode_image

from .base import Output
from .errors import OptionValueError

#: the largest side an output may have (a typo such as 64000x480 fails at once)
MAX_SIDE = 16384


def parse_size(text: str) -> tuple[int, int] | float:
    """``"WxH"`` -> ``(W, H)`` pixels, or ``"0.5"`` -> a scale; ValueError otherwise.

    >>> parse_size("320x240"), parse_size("0.5")
    ((320, 240), 0.5)
    """
    width, sep, height = text.lower().partition("x")
    try:
        if sep:
            size = int(width), int(height)
            if min(size) < 1 or max(size) > MAX_SIDE:
                raise ValueError
            return size
        scale = float(text)
    except ValueError:
        raise ValueError(f"expected WxH (1..{MAX_SIDE} pixels each) or a scale, got {text!r}"
                         ) from None
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"a scale must be > 0, got {text!r}")
    return scale


class Resize:
    """Resize every frame to ``size`` (``"WxH"``) or by a scale (``"0.5"``); the output
    keeps the frame's colour order and bit depth."""

    def __init__(self, *, size: str) -> None:
        try:
            self.size = parse_size(size)
        except ValueError as err:
            raise OptionValueError("resize", ("size",), str(err)) from None

    def output_size(self, width: int, height: int) -> tuple[int, int]:
        """(W', H') of the output for a ``width`` x ``height`` input."""
        if isinstance(self.size, tuple):
            return self.size
        return max(1, round(width * self.size)), max(1, round(height * self.size))

    def __call__(self, frame: Frame) -> list[Output]:
        """The resized frame (same colour order and bit depth)."""
        width, height = self.output_size(frame.width, frame.height)
        if max(width, height) > MAX_SIDE:
            raise OptionValueError("resize", ("size",), f"{frame.width}x{frame.height} "
                                   f"scaled is {width}x{height}, above {MAX_SIDE} pixels")
        shrink = width * height < frame.width * frame.height
        resized = cv2.resize(frame.pixels, (width, height),
                             interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
        return [("image_resized", encode_image(frame.with_pixels(resized)))]

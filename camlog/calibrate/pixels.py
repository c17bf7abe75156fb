"""The pixels calibration needs from an image message: grey for detection, BGR for drawing."""

from __future__ import annotations

import cv2
import numpy as np

from replay.codec import decode_compressed, to_bgr_or_mono, to_mono8
from replay.errors import ReplayError
from replay.messages import CompressedImage, Image

from ..errors import InputError

__all__ = ["as_image", "bgr", "mono8"]


def as_image(message: object, *, where: str) -> Image:
    """A raw image of an ``Image`` or ``CompressedImage`` message; ``where`` names the topic."""
    if isinstance(message, CompressedImage):
        try:
            return decode_compressed(message)
        except ReplayError as err:
            raise InputError(f"{where}: {err}") from None
    if not isinstance(message, Image):
        raise InputError(f"{where} does not hold images")
    return message


def mono8(image: Image) -> np.ndarray:
    """``(H, W)`` uint8 grey levels."""
    return to_mono8(image)


def bgr(image: Image) -> np.ndarray:
    """``(H, W, 3)`` uint8 BGR for drawing (16-bit images keep their high byte)."""
    array = to_bgr_or_mono(image)
    if array.ndim == 2:
        if array.dtype != np.uint8:
            array = (array >> 8).astype(np.uint8)
        return cv2.cvtColor(array, cv2.COLOR_GRAY2BGR)
    return array

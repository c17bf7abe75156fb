"""The camera frame of an image message, for calibration (errors name the topic)."""

from __future__ import annotations

from replay.errors import ReplayError
from replay.frames import Frame, decode_frame
from replay.messages import CompressedImage, Image

from ..errors import InputError

__all__ = ["as_frame"]


def as_frame(message: object, *, where: str) -> Frame:
    """The frame of an image message in any encoding (grey for detection: ``mono8()``,
    BGR for drawing: ``bgr8()``); ``where`` names the topic."""
    if not isinstance(message, Image | CompressedImage):
        raise InputError(f"{where} does not hold images")
    try:
        return decode_frame(message)
    except ReplayError as err:
        raise InputError(f"{where}: {err}") from None

"""The camera frames of image messages, for calibration (errors name the topic)."""

from __future__ import annotations

from replay.errors import ReplayError
from replay.frames import Frame, FrameStream
from replay.messages import CompressedImage, CompressedVideo, Image

from ..errors import InputError

__all__ = ["TopicFrames"]


class TopicFrames:
    """Decodes the image messages of a log's topics, each topic in log order (a video
    picture needs the ones before it), to frames (grey for detection: ``mono8()``, BGR for
    drawing: ``bgr8()``)."""

    def __init__(self) -> None:
        self._streams: dict[str, FrameStream] = {}

    def __call__(self, message: object, *, topic: str, where: str) -> Frame | None:
        """The frame of ``topic``'s next message in any encoding, still or video; None for
        a video picture before the stream's first keyframe. ``where`` names the topic."""
        if not isinstance(message, Image | CompressedImage | CompressedVideo):
            raise InputError(f"{where} does not hold images")
        try:
            return self._streams.setdefault(topic, FrameStream()).decode(message)
        except ReplayError as err:
            raise InputError(f"{where}: {err}") from None

"""Canny edges of the grayscale image (the chapter's ``find_features`` node)."""

from __future__ import annotations

import cv2

from replay.frames import Frame
from replay.messages import Image

from .base import Output
from .errors import OptionValueError


class Edges:
    """Grayscale, then ``cv2.Canny(gray, low, high)``; publishes a mono8 edge image (255 on
    edges). Thresholds are on the 8-bit gradient magnitude (L1 norm, OpenCV's default)."""

    def __init__(self, *, low: float = 50.0, high: float = 150.0) -> None:
        if not 0 <= low <= high:
            raise OptionValueError("edges", ("low", "high"),
                                   f"Canny thresholds need 0 <= low <= high, got {low}, {high}")
        self.low, self.high = low, high

    def __call__(self, frame: Frame) -> list[Output]:
        edges = cv2.Canny(frame.mono8(), self.low, self.high)
        return [("edges", Image(frame.stamp_ns, frame.frame_id, "mono8", edges))]

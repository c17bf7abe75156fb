"""What ``camlog view`` and ``camlog play`` draw, and how: the options a user sets."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["UNDISTORTED_SCALE", "LoggerOptions"]

#: the pinhole views' width and height, relative to the raw images': a quarter of their
#: pixels, which costs view about a quarter of what a second image as large would (each
#: image, remapped or not, costs rerun as much as its pixels; see the benchmarks page)
UNDISTORTED_SCALE = 0.5


@dataclass(frozen=True)
class LoggerOptions:
    """What to draw and how: ``every`` keeps every N-th image of a camera; ``jpeg_quality``
    stores raw 8-bit images as JPEG; residual arrows are drawn ``residual_scale`` times long;
    a camera whose lens is not a pinhole gets pinhole views ``undistorted_scale`` times its
    raw images' width and height (None: none, its raw images under a pinhole of its K)."""

    every: int = 1
    jpeg_quality: int | None = None
    residual_scale: float = 50.0
    ground_truth: bool = True
    undistorted_scale: float | None = UNDISTORTED_SCALE

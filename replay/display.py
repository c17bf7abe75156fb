"""How processor outputs are displayed: the vocabulary programs that add topics declare.

A program that adds topics to a log (``camlog process``) declares each output with a
:class:`Display` and records it in the log (:class:`replay.records.ProcessedOutputs` on
:data:`replay.topics.PROCESSED`), so that ``camlog view`` knows, for any topic name, which
image it was computed from and how to draw it. Pure data: importing this module loads no
numerical or viewer library.
"""

from __future__ import annotations

from enum import Enum

__all__ = ["Display"]


class Display(Enum):
    """How one output topic is shown (what its message holds, and where it goes)."""

    IMAGE = "image"  # an image (any encoding), in its own 2D view
    RECTIFIED = "rectified"  # a rectified image: its own 2D view with guide rows
    MASK = "mask"  # mono8 (nonzero) or rgb8 mask (white, blue marker) over the camera image
    EDGES = "edges"  # mono8 edge image (above 127) over the camera image
    POINT_2D = "point_2d"  # PointStamped x = u, y = v in pixels, on the camera image
    SCALAR = "scalar"  # PointStamped x as a time series
    POINT_SERIES = "point_series"  # PointStamped x, y, z as time series

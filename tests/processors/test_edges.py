"""Canny edges of synthetic images."""

from __future__ import annotations

import numpy as np
import pytest

from processors.edges import Edges
from processors.errors import ConfigError
from replay import Frame, Image
from replay.frames import decode_frame


def square_image(level: int) -> Frame:
    rgb = np.full((60, 80, 3), 100, np.uint8)
    rgb[20:40, 30:60] = level
    return decode_frame(Image(7, "cam", "rgb8", rgb))


def test_edges_trace_the_square_outline() -> None:
    (topic, out), = Edges()(square_image(250))
    assert topic == "edges" and isinstance(out, Image)
    assert (out.encoding, out.stamp_ns, out.frame_id, out.pixels.shape) == ("mono8", 7, "cam",
                                                                          (60, 80))
    rows, cols = np.nonzero(out.pixels)
    assert set(np.unique(out.pixels)) == {0, 255}
    # every edge pixel is on the step between rows 19|20, 39|40 or cols 29|30, 59|60
    near_row = np.minimum(np.abs(rows - 19.5), np.abs(rows - 39.5)) <= 0.5
    near_col = np.minimum(np.abs(cols - 29.5), np.abs(cols - 59.5)) <= 0.5
    assert np.all(near_row | near_col)
    edges = out.pixels > 0
    assert edges[20:40, 29:31].any(axis=1).all() and edges[20:40, 59:61].any(axis=1).all()
    assert edges[19:21, 30:60].any(axis=0).all() and edges[39:41, 30:60].any(axis=0).all()


def test_weak_steps_are_below_the_thresholds() -> None:
    (_, out), = Edges()(square_image(103))
    assert isinstance(out, Image) and not out.pixels.any()
    (_, out), = Edges(low=1, high=5)(square_image(103))
    assert isinstance(out, Image) and out.pixels.any()


def test_mono16_input_is_scaled_to_8_bit() -> None:
    px = np.full((30, 30), 1000, np.uint16)
    px[10:20, 10:20] = 60000
    (_, out), = Edges()(decode_frame(Image(0, "", "mono16", px)))
    assert isinstance(out, Image) and out.pixels[10:20, 9:11].any()


def test_thresholds_are_checked() -> None:
    with pytest.raises(ConfigError):
        Edges(low=200, high=100)
    with pytest.raises(ConfigError):
        Edges(low=-1)

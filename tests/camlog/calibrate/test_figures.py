"""The calibration figures: sizes, and the uncertainty map's colours and colour bar."""

from __future__ import annotations

import cv2
import numpy as np

from camlog.calibrate.figures import uncertainty_figure
from processors.calibration.uncertainty import grid


def viridis(value: int) -> np.ndarray:
    return np.asarray(cv2.applyColorMap(np.array([[value]], np.uint8), cv2.COLORMAP_VIRIDIS)[0, 0])


def test_uncertainty_figure_colours_the_map_and_its_bar_by_value() -> None:
    size = (160, 120)
    pixels = grid(size, 16)
    # grows to the right: the largest value on the right edge, the smallest on the left
    sigma = 0.01 + 0.1 * pixels[..., 0] / (size[0] - 1)
    img = uncertainty_figure(size, pixels, sigma, "test")
    w, h = size
    margin = (img.shape[0] - h) // 2
    assert img.shape[1] >= w + 90 and img.shape[0] >= h
    bar = [x for x in range(img.shape[1]) if np.array_equal(img[margin, x], viridis(255))
           and np.array_equal(img[margin + h - 1, x], viridis(0))]
    assert len(bar) == 16  # the colour bar: the largest value at its top, the smallest below
    column = img[margin:margin + h, bar[0]].astype(int)
    brightness = column.sum(axis=1)
    assert brightness[0] > brightness[-1]
    # away from the contour lines (white), the colour is the value's
    top = float(sigma.max())
    for u in (8, w // 3, w - 8):
        expected = viridis(round(255 * (0.01 + 0.1 * u / (w - 1)) / top))
        found = img[margin + 5, margin + u].astype(int)
        assert np.abs(found - expected).max() <= 6, (u, found, expected)

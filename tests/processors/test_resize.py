"""Resizing: pixel centres stay at integer coordinates; shrinking averages, never aliases."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

import processors.resize
from processors.errors import OptionValueError
from processors.resize import Resize
from replay import Image
from replay.frames import decode_frame

W, H = 64, 48


def dot(u: float, v: float, width: int = W, height: int = H, sigma: float = 2.0) -> np.ndarray:
    """mono16 image of a Gaussian dot centred on pixel coordinates ``(u, v)``."""
    ys, xs = np.mgrid[0:height, 0:width]
    return (60000 * np.exp(-((xs - u) ** 2 + (ys - v) ** 2) / (2 * sigma**2))).astype(np.uint16)


def centroid(pixels: np.ndarray) -> np.ndarray:
    ys, xs = np.mgrid[0:pixels.shape[0], 0:pixels.shape[1]]
    weight = pixels.astype(np.float64)
    return np.array([(weight * xs).sum(), (weight * ys).sum()]) / weight.sum()


@pytest.mark.parametrize(("size", "scale"), [("32x24", 0.5), ("0.5", 0.5), ("128x96", 2.0),
                                             ("2", 2.0)])
def test_the_dot_stays_on_the_same_ray(size: str, scale: float) -> None:
    u, v = 30.3, 21.7
    ((name, out),) = Resize(size=size)(decode_frame(Image(9, "cam", "mono16", dot(u, v))))
    assert name == "image_resized" and isinstance(out, Image)
    assert (out.encoding, out.stamp_ns, out.frame_id) == ("mono16", 9, "cam")
    assert out.pixels.shape == (round(H * scale), round(W * scale))
    # pixel centres at integer coordinates: x' = (x + 0.5) * scale - 0.5
    expected = (np.array([u, v]) + 0.5) * scale - 0.5
    np.testing.assert_allclose(centroid(out.pixels), expected, atol=0.03)


def test_shrinking_averages_instead_of_aliasing() -> None:
    stripes = np.zeros((H, W, 3), np.uint8)
    stripes[:, ::2] = 255  # one-pixel columns: a point sample would keep only one colour
    ((_, out),) = Resize(size="0.5")(decode_frame(Image(0, "", "rgb8", stripes)))
    assert isinstance(out, Image) and out.pixels.shape == (H // 2, W // 2, 3)
    assert np.all(np.abs(out.pixels.astype(int) - 128) <= 1)


@pytest.mark.parametrize("size", ["0", "-1", "nan", "x", "10x", "0x10", "99999x10", "big"])
def test_bad_sizes_name_the_option(size: str) -> None:
    with pytest.raises(OptionValueError) as err:
        Resize(size=size)
    assert (err.value.processor, err.value.options) == ("resize", ("size",))
    assert "--" not in str(err.value)


def test_a_huge_scale_fails_per_frame() -> None:
    with pytest.raises(OptionValueError, match="above"):
        Resize(size="1000")(decode_frame(Image(0, "", "mono8", np.zeros((H, W), np.uint8))))


def test_docstring_examples() -> None:
    result = doctest.testmod(processors.resize)
    assert result.attempted > 0 and result.failed == 0

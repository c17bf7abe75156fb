"""Red mask, centroid and the find_red_pixels outputs on synthetic arrays."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from processors.errors import ConfigError
from processors.red_pixels import (
    BLUE_RGB,
    CENTROID,
    COUNT,
    HALF_BOX,
    OUTPUT_VIDEO,
    RedPixels,
    mask_centroid,
    red_mask,
)
from replay import Image, PointStamped
from replay.frames import decode_frame


def reference_mask(rgb: np.ndarray, ratio: int) -> np.ndarray:
    """The chapter's rule in wide integers."""
    r, g, b = (rgb[..., c].astype(np.int64) for c in range(3))
    return r > ratio * (g + b)


@pytest.mark.parametrize("ratio", [0, 1, 3, 10, 40, 300])
def test_mask_matches_the_rule_in_wide_integers(ratio: int) -> None:
    rng = np.random.default_rng(ratio)
    noise = rng.integers(0, 256, (64, 80, 3), dtype=np.uint8)
    reddish = noise.copy()  # many pixels near the decision boundary
    reddish[..., 1:] = rng.integers(0, 20, (64, 80, 2), dtype=np.uint8)
    for rgb in (noise, reddish):
        mask = red_mask(rgb, ratio)
        assert mask.dtype == np.uint8 and set(np.unique(mask)) <= {0, 255}
        np.testing.assert_array_equal(mask == 255, reference_mask(rgb, ratio))


def test_boundary_values() -> None:
    rgb = np.array([[[201, 10, 10], [200, 10, 10], [255, 13, 13], [255, 12, 13], [255, 0, 0],
                     [0, 0, 0]]], np.uint8)
    assert (red_mask(rgb, 10) == 255).tolist() == [[True, False, False, True, True, False]]
    assert (red_mask(rgb, 9) == 255).tolist() == [[True, True, True, True, True, False]]


def test_centroid_of_a_rectangle_is_its_centre() -> None:
    mask = np.zeros((48, 64), np.uint8)
    mask[10:21, 5:9] = 255  # rows 10..20, cols 5..8
    u, v, count = mask_centroid(mask)
    assert (u, v, count) == (6.5, 15.0, 44)
    u, v, count = mask_centroid(np.zeros((4, 4), np.uint8))
    assert count == 0 and np.isnan(u) and np.isnan(v)


def test_outputs_mask_video_centroid_and_count() -> None:
    rgb = np.full((60, 80, 3), (120, 130, 140), np.uint8)
    rgb[20:31, 40:61] = (250, 3, 2)  # centre (50, 25)
    image = Image(123, "cam", "rgb8", rgb)
    outputs = dict(RedPixels()(decode_frame(image)))
    assert set(outputs) == {OUTPUT_VIDEO, CENTROID, COUNT}
    centroid, count, video = outputs[CENTROID], outputs[COUNT], outputs[OUTPUT_VIDEO]
    assert isinstance(centroid, PointStamped) and isinstance(count, PointStamped)
    assert centroid.point.tolist() == [50.0, 25.0, 0.0] and count.point[0] == 11 * 21
    assert (centroid.stamp_ns, centroid.frame_id) == (123, "cam") == (video.stamp_ns,
                                                                       video.frame_id)
    assert isinstance(video, Image) and video.encoding == "rgb8"
    px = video.pixels
    blue = np.all(px == BLUE_RGB, axis=2)
    rows, cols = np.nonzero(blue)
    assert (rows.min(), rows.max(), cols.min(), cols.max()) == (
        25 - HALF_BOX, 25 + HALF_BOX, 50 - HALF_BOX, 50 + HALF_BOX)
    white = np.all(px == 255, axis=2)
    expected_white = np.zeros((60, 80), bool)
    expected_white[20:31, 40:61] = True
    np.testing.assert_array_equal(white, expected_white & ~blue)
    assert np.all(px[~white & ~blue] == 0)


def test_no_red_publishes_count_zero_and_no_centroid() -> None:
    image = Image(5, "cam", "rgb8", np.full((8, 8, 3), 90, np.uint8))
    outputs = RedPixels()(decode_frame(image))
    assert [t for t, _ in outputs] == [OUTPUT_VIDEO, COUNT]
    count = outputs[1][1]
    assert isinstance(count, PointStamped) and count.point[0] == 0


@pytest.mark.parametrize("encoding", ["bgr8", "rgba8", "bgra8"])
def test_every_colour_encoding_gives_the_same_mask(encoding: str) -> None:
    rgb = np.zeros((10, 12, 3), np.uint8)
    rgb[2:5, 3:9] = (200, 5, 5)
    convert = {"bgr8": cv2.COLOR_RGB2BGR, "rgba8": cv2.COLOR_RGB2RGBA,
               "bgra8": cv2.COLOR_RGB2BGRA}[encoding]
    image = Image(0, "", encoding, cv2.cvtColor(rgb, convert))
    reference = dict(RedPixels()(decode_frame(Image(0, "", "rgb8", rgb))))
    outputs = dict(RedPixels()(decode_frame(image)))
    assert outputs[CENTROID] == reference[CENTROID]
    assert outputs[OUTPUT_VIDEO] == reference[OUTPUT_VIDEO]


def test_bad_options_and_arrays() -> None:
    with pytest.raises(ConfigError):
        RedPixels(ratio=-1)
    with pytest.raises(ConfigError):
        red_mask(np.zeros((4, 4), np.uint8))

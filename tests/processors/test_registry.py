"""The processor registry and the shared interface; docstring examples run."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

import processors.red_pixels
import processors.resync
from processors import PROCESSORS, ConfigError, make_processor
from replay import IMAGE_ENCODINGS, CameraInfo, Image
from replay.codec import msgtype_of

K = np.array([[50.0, 0, 15.5], [0, 50.0, 11.5], [0, 0, 1]])
OPTIONS = {"rectify": {"camera_info": CameraInfo(0, "", 32, 24, "plumb_bob", np.zeros(5), K)}}


@pytest.mark.parametrize("name", sorted(PROCESSORS))
def test_every_processor_honours_the_interface(name: str) -> None:
    processor = make_processor(name, **OPTIONS.get(name, {}))
    assert processor.name == name
    rgb = np.zeros((24, 32, 3), np.uint8)
    rgb[5:10, 5:10] = (255, 0, 0)
    outputs = processor(Image(42, "cam", "rgb8", rgb))
    declared = processor.outputs()
    assert outputs
    for topic, message in outputs:
        assert declared[topic] == msgtype_of(message)
        assert (message.stamp_ns, message.frame_id) == (42, "cam")  # type: ignore[union-attr]


@pytest.mark.parametrize("encoding", sorted(IMAGE_ENCODINGS))
@pytest.mark.parametrize("name", sorted(PROCESSORS))
def test_every_encoding_the_log_layer_supports(name: str, encoding: str) -> None:
    dtype, channels = IMAGE_ENCODINGS[encoding]
    shape = (24, 32) if channels == 1 else (24, 32, channels)
    pixels = np.random.default_rng(0).integers(0, np.iinfo(dtype).max, shape).astype(dtype)
    outputs = make_processor(name, **OPTIONS.get(name, {}))(Image(1, "", encoding, pixels))
    images = [m for _, m in outputs if isinstance(m, Image)]
    assert images and all(m.pixels.shape[:2] == (24, 32) for m in images)


def test_unknown_processor() -> None:
    with pytest.raises(ConfigError, match="red_pixels"):
        make_processor("blur")


@pytest.mark.parametrize("module", [processors.red_pixels, processors.resync])
def test_docstring_examples(module: object) -> None:
    result = doctest.testmod(module)  # type: ignore[arg-type]
    assert result.attempted > 0 and result.failed == 0

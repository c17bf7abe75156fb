"""Image buffer layouts: numbers only, the same as the frame decoders' table."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from replay.buffer_layout import LAYOUTS, check_buffer
from replay.errors import EncodingError, UnsupportedEncodingError
from replay.frames.raw import RAW_ENCODINGS


def test_every_raw_encoding_has_its_layout_and_no_other() -> None:
    assert set(LAYOUTS) == set(RAW_ENCODINGS)
    for name, layout in LAYOUTS.items():
        raw = RAW_ENCODINGS[name]
        assert layout.pixel_bytes == raw.dtype.itemsize * raw.channels, name
        assert np.dtype(layout.value) == raw.dtype, name


@pytest.mark.parametrize(("encoding", "width", "height", "step", "rows"), [
    ("rgb8", 4, 3, 12, 3),
    ("rgb8", 4, 3, 16, 3),  # padded rows
    ("mono16", 5, 2, 10, 2),
    ("nv21", 4, 4, 4, 6),  # chroma rows below the luma rows
    ("nv24", 4, 2, 4, 6),
])
def test_a_buffer_that_holds_the_image_gives_its_rows(encoding: str, width: int, height: int,
                                                      step: int, rows: int) -> None:
    assert check_buffer(encoding, width=width, height=height, step=step,
                        size=step * rows) == rows
    assert rows == height * LAYOUTS[encoding].rows


def test_a_short_buffer_or_step_is_an_encoding_error() -> None:
    with pytest.raises(EncodingError, match="too small"):
        check_buffer("rgb8", width=4, height=3, step=12, size=35)
    with pytest.raises(EncodingError, match="too small"):
        check_buffer("rgb8", width=4, height=3, step=11, size=100)
    with pytest.raises(EncodingError, match="even height"):
        check_buffer("nv21", width=4, height=3, step=4, size=100)
    with pytest.raises(EncodingError, match="unpadded rows"):
        check_buffer("nv24", width=4, height=2, step=8, size=100)


def test_an_unknown_encoding_names_the_supported_ones() -> None:
    with pytest.raises(UnsupportedEncodingError, match=r"'yuv411' \(supported: 16SC1, "):
        check_buffer("yuv411", width=2, height=2, step=4, size=8)
    assert LAYOUTS["nv21"].rows == Fraction(3, 2)

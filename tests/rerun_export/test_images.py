"""Compressed stills handed to rerun as they are: only whole JPEG and PNG files (OpenCV's)."""

from __future__ import annotations

import doctest

import cv2
import pytest

import rerun_export.images
from rerun_export.images import complete, media_type
from tests.encodings import scene_rgb


@pytest.mark.parametrize("ext", [".jpg", ".png"])
def test_whole_files_are_complete_cut_ones_are_not(ext: str) -> None:
    ok, buf = cv2.imencode(ext, scene_rgb())
    assert ok
    data = buf.tobytes()
    kind = media_type(data)
    assert kind == ("image/jpeg" if ext == ".jpg" else "image/png")
    assert complete(data, kind)
    assert complete(data + bytes(4), kind) == (ext == ".jpg")  # JPEG padding is allowed
    for cut in (len(data) // 2, len(data) - 1):
        assert not complete(data[:cut], kind)


def test_doctests() -> None:
    assert doctest.testmod(rerun_export.images).failed == 0

"""camera_calibration's ost.txt: sections in its order, matrices that read back as written."""

from __future__ import annotations

import re

import numpy as np
import pytest

from replay import CameraInfo
from replay.calibration_ini import cameras_from_ost, ost_text
from replay.calibration_yaml import CalibrationFileError

MATRICES = {"camera matrix": (3, 3), "rectification": (3, 3), "projection": (3, 4)}


def camera(fx: float, tx: float = 0.0) -> CameraInfo:
    k = np.array([[fx, 0.0, 321.25], [0.0, fx + 1.5, 239.125], [0.0, 0.0, 1.0]])
    r = np.array([[0.999998, 0.001, -0.0015], [-0.001, 0.999999, 0.0002],
                  [0.0015, -0.0002, 0.999998]])
    p = np.array([[fx, 0.0, 320.0, tx], [0.0, fx, 240.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    return CameraInfo(0, "cam", 640, 480, "plumb_bob",
                      np.array([-0.2125, 0.05, 0.001, -0.0005, 0.0]), k, r, p)


def parse(text: str) -> dict[str, dict[str, object]]:
    """Section name -> {key: value lines}; a key is a line followed by its values."""
    sections: dict[str, dict[str, object]] = {}
    current: dict[str, object] = {}
    blocks = [b.strip().splitlines() for b in text.split("\n\n") if b.strip()]
    for lines in blocks:
        if lines[0].startswith("#"):
            continue
        if lines[0].startswith("["):
            current = sections.setdefault(lines[0][1:-1], {})
            continue
        name, rows = lines[0], lines[1:]
        values = np.array([[float(v) for v in row.split()] for row in rows])
        current[name] = values
    return sections


def assert_camera(section: dict[str, object], info: CameraInfo) -> None:
    assert list(section) == ["camera matrix", "distortion", "rectification", "projection"]
    for name, attribute in (("camera matrix", "k"), ("rectification", "r"),
                            ("projection", "p")):
        values = section[name]
        assert isinstance(values, np.ndarray) and values.shape == MATRICES[name]
        np.testing.assert_allclose(values, getattr(info, attribute), atol=5e-7)
    distortion = section["distortion"]
    assert isinstance(distortion, np.ndarray) and distortion.shape == (1, 5)
    np.testing.assert_allclose(distortion[0], info.d, atol=5e-7)


def test_mono_layout() -> None:
    info = camera(1034.473)
    text = ost_text(info)
    assert text.startswith("# oST version 5.0 parameters\n")
    sections = parse(text)
    assert list(sections) == ["image", "narrow_stereo"]
    np.testing.assert_array_equal(sections["image"]["width"], [[640]])
    np.testing.assert_array_equal(sections["image"]["height"], [[480]])
    assert_camera(sections["narrow_stereo"], info)


def test_stereo_layout() -> None:
    left, right = camera(1034.5), camera(1035.25, tx=-20.705)
    sections = parse(ost_text(left=left, right=right))
    assert list(sections) == ["image", "narrow_stereo/left", "narrow_stereo/right"]
    assert_camera(sections["narrow_stereo/left"], left)
    assert_camera(sections["narrow_stereo/right"], right)
    projection = sections["narrow_stereo/right"]["projection"]
    assert isinstance(projection, np.ndarray) and projection[0, 3] == -20.705


def test_needs_a_camera_or_a_pair() -> None:
    with pytest.raises(ValueError, match="mono camera or a left and right"):
        ost_text()
    with pytest.raises(ValueError, match="both left and right"):
        ost_text(left=camera(1000.0))


def test_reads_back_what_it_writes() -> None:
    left, right = camera(1034.5), camera(1035.25, tx=-20.705)
    for text, expected in ((ost_text(left), [("narrow_stereo", left)]),
                           (ost_text(left=left, right=right),
                            [("narrow_stereo/left", left), ("narrow_stereo/right", right)])):
        got = cameras_from_ost(text)
        assert [name for name, _ in got] == [name for name, _ in expected]
        for (_, info), (_, truth) in zip(got, expected, strict=True):
            assert (info.width, info.height, info.distortion_model) == (640, 480, "plumb_bob")
            for name in ("k", "d", "r", "p"):
                np.testing.assert_allclose(getattr(info, name), getattr(truth, name), atol=5e-7)


@pytest.mark.parametrize(("text", "words"), [
    ("", "no camera section"),
    ("width\n640\n", "before the first [section]"),
    ("[image]\n\nwidth\n640\n", "[image]: expected width and height"),
    ("[image]\n\nwidth\n640\n\nheight\n480\n\n[cam]\n\ncamera matrix\n1 0 0\n",
     "[cam]: missing distortion, rectification, projection"),
    (ost_text(camera(800.0)).replace("0.001000 -0.001500", "x y"),
     "[narrow_stereo] rectification: expected rows of numbers"),
    (ost_text(camera(800.0)).replace("\n0.000000 0.000000 1.000000 0.000000", ""),
     "[narrow_stereo] projection: expected 3x4 values, got 8"),
])
def test_a_malformed_file_says_what_is_wrong(text: str, words: str) -> None:
    with pytest.raises(CalibrationFileError, match=re.escape(words)):
        cameras_from_ost(text)

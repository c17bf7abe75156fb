"""The circle diameter a calibration models: given, or the median the views measured."""

from __future__ import annotations

import numpy as np
import pytest

from camlog.calibrate.circles import circle_size
from camlog.calibrate.views import CameraSource, CameraViews, DetectedFrame
from camlog.errors import CalibrationError
from processors.calibration.board import Board
from processors.calibration.detect import Detection

CIRCLES = Board(4, 11, 0.01, "acircles")
CORNERS = np.zeros((CIRCLES.corner_count, 2))


def camera(diameters: list[float | None], *, accepted: bool = True) -> CameraViews:
    frames = tuple(DetectedFrame(i, 1000 * i, False, Detection(CORNERS, accepted, diameter_m=d))
                   for i, d in enumerate(diameters))
    return CameraViews(CameraSource("/cam", "/cam/image_raw", None), frames, (640, 480), None)


def test_measured_is_the_median_over_the_views() -> None:
    size = circle_size([camera([0.0101, 0.0099, 0.0100, None, 0.0180])], CIRCLES, None)
    assert size is not None and size.measured
    assert size.diameter_m == pytest.approx(0.01005)
    assert "measured from the images" in size.describe() and size.warning() is None


def test_given_wins_and_a_disagreement_is_a_warning() -> None:
    size = circle_size([camera([0.0100, 0.0100])], CIRCLES, 0.008)
    assert size is not None and not size.measured and size.diameter_m == 0.008
    assert size.measured_m == pytest.approx(0.01)
    assert "given; the images show 0.01000 m" in size.describe()
    warning = size.warning()
    assert warning is not None and "0.01000 m across" in warning
    close = circle_size([camera([0.0100])], CIRCLES, 0.0101)
    assert close is not None and close.warning() is None


def test_rejected_views_do_not_count_and_none_measured_is_an_error() -> None:
    with pytest.raises(CalibrationError, match="give it with --diameter"):
        circle_size([camera([0.01, 0.01], accepted=False)], CIRCLES, None)
    given = circle_size([camera([None])], CIRCLES, 0.01)
    assert given is not None and given.measured_m is None and given.warning() is None


def test_circles_that_would_overlap_are_an_error() -> None:
    with pytest.raises(CalibrationError, match="would overlap"):
        circle_size([camera([0.015, 0.015])], CIRCLES, None)


def test_other_boards_have_no_circles() -> None:
    assert circle_size([camera([None])], Board(7, 6, 0.01), None) is None

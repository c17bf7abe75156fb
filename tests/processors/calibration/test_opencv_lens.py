"""OpenCV's functions per lens model: each family rectifies a pair and gives a camera matrix."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.opencv_lens import FISHEYE, OPENCV_LENSES, PINHOLE, opencv_lens
from processors.calibration.stereo import rectify
from processors.errors import ProcessorError
from replay.camera import CameraModel

from .synthetic import K_TRUE, H, W

#: a lens of each model that bends the image edges a little
_D = {"plumb_bob": [-0.05, 0.01, 0.0, 0.0, 0.0],
      "rational_polynomial": [-0.05, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
      "equidistant": [0.01, -0.002, 0.0, 0.0]}


def test_aliases_and_families() -> None:
    assert opencv_lens("fisheye") is FISHEYE is OPENCV_LENSES["equidistant"]
    assert opencv_lens("") is PINHOLE  # camera_info_manager's empty model


@pytest.mark.parametrize("name", list(OPENCV_LENSES))
def test_every_family_rectifies_a_pair_of_its_cameras(name: str) -> None:
    model = CameraModel(W, H, K_TRUE, name, np.array(_D[name]))
    right_from_left = np.eye(4)
    right_from_left[:3, 3] = [-0.1, 0.0, 0.0]  # a column of a pose matrix, as the solver's
    r1, r2, p1, p2 = rectify(model, model, right_from_left)
    assert p2[0, 3] == pytest.approx(-p2[0, 0] * 0.1, rel=1e-9)
    points_in_left = np.column_stack([np.linspace(-0.3, 0.3, 9), np.linspace(0.2, -0.2, 9),
                                      np.full(9, 1.5)])
    left_px = model.project(points_in_left)
    right_px = model.project(points_in_left + right_from_left[:3, 3])
    left_rows = model.rectify_points(left_px, r1, p1)[:, 1]
    right_rows = model.rectify_points(right_px, r2, p2)[:, 1]
    assert np.abs(left_rows - right_rows).max() < 1e-6
    new_k = opencv_lens(name).new_camera_matrix(model)
    assert new_k.shape == (3, 3) and new_k[0, 0] > 0 and new_k[2, 2] == 1


def test_a_fisheye_and_a_pinhole_are_not_rectified_together() -> None:
    fisheye = CameraModel(W, H, K_TRUE, "equidistant", np.array(_D["equidistant"]))
    pinhole = CameraModel(W, H, K_TRUE)
    with pytest.raises(ProcessorError, match="rectifying a fisheye camera with a pinhole camera"):
        rectify(fisheye, pinhole, np.eye(4))

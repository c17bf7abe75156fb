"""The lens-model table: every entry is consistent with the code that uses it."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.lens import INTRINSIC_NAMES, intrinsics_of, project
from processors.calibration.options import CalibrationOptions
from replay.camera import CameraModel
from replay.format_names import CAMERA_MODELS
from replay.lens_models import LENS_MODELS, MODEL_ALIASES, lens_model


@pytest.mark.parametrize("name", list(LENS_MODELS))
def test_every_model_is_one_consistent_entry(name: str) -> None:
    lens = LENS_MODELS[name]
    assert CAMERA_MODELS[name] == len(lens.coefficients)
    assert INTRINSIC_NAMES[name] == ("fx", "fy", "cx", "cy", *lens.coefficients)
    assert 0 < lens.default_radial <= lens.max_radial == len(lens.radial_names)
    assert ({"p1", "p2"} <= set(lens.coefficients)) == lens.tangential
    options = CalibrationOptions(model=name)
    assert options.radial_count == lens.default_radial
    assert options.has_tangential == lens.tangential
    with pytest.raises(Exception, match="radial coefficients"):
        CalibrationOptions(model=name, k_coefficients=lens.max_radial + 1)
    # the solver's projection and OpenCV's (through CameraModel) agree
    rng = np.random.default_rng(0)
    d = rng.normal(0, 0.01, len(lens.coefficients))
    model = CameraModel(640, 480, np.array([[500.0, 0, 320], [0, 510, 240], [0, 0, 1]]), name, d)
    assert model.is_fisheye == lens.fisheye and model.lens is lens
    points = np.column_stack([rng.uniform(-0.3, 0.3, (20, 2)), np.ones(20)])
    uv, _d_point, _d_intrinsics = project(name, intrinsics_of(model), points)
    np.testing.assert_allclose(uv, model.project(points), atol=1e-6)


def test_aliases_and_unknown_names() -> None:
    for alias, name in MODEL_ALIASES.items():
        assert lens_model(alias) is LENS_MODELS[name]
    assert lens_model("").name == "plumb_bob"  # camera_info_manager's empty model
    with pytest.raises(KeyError, match=r"unknown lens model 'kannala'.*plumb_bob.*fisheye"):
        lens_model("kannala")

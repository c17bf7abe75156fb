"""The lens-model table: every entry is consistent with the code that uses it, and every model
projects and unprojects, goes through a calibration YAML file and calibrates."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.lens import DISTORTIONS, INTRINSIC_NAMES, intrinsics_of, project
from processors.calibration.mono import calibrate_mono, mono_camera_info
from processors.calibration.opencv_lens import OPENCV_LENSES
from processors.calibration.options import CalibrationOptions
from replay.calibration_yaml import calibration_from_yaml, calibration_to_yaml
from replay.camera import CameraModel
from replay.lens_models import LENS_MODELS, MODEL_ALIASES, lens_model
from replay.projections import PROJECTIONS
from tests.processors.calibration.synthetic import BOARD, K_TRUE, H, W, random_poses, views

#: a lens of each model that bends the image edges by a few pixels
_COEFFICIENTS = {"k1": -0.05, "k2": 0.01, "p1": 4e-4, "p2": -3e-4}


def _model(name: str) -> CameraModel:
    d = [_COEFFICIENTS.get(c, 0.0) for c in LENS_MODELS[name].coefficients]
    return CameraModel(W, H, K_TRUE, name, np.array(d))


def test_every_table_holds_every_model() -> None:
    assert list(PROJECTIONS) == list(DISTORTIONS) == list(OPENCV_LENSES) == list(LENS_MODELS)


@pytest.mark.parametrize("name", list(LENS_MODELS))
def test_every_model_is_one_consistent_entry(name: str) -> None:
    lens = LENS_MODELS[name]
    assert INTRINSIC_NAMES[name] == ("fx", "fy", "cx", "cy", *lens.coefficients)
    assert 0 < lens.default_radial <= lens.max_radial == len(lens.radial_names)
    assert ({"p1", "p2"} <= set(lens.coefficients)) == lens.tangential
    options = CalibrationOptions(model=name)
    assert options.radial_count == lens.default_radial
    assert options.has_tangential == lens.tangential
    assert set(options.free) <= set(lens.intrinsic_names)
    with pytest.raises(Exception, match="radial coefficients"):
        CalibrationOptions(model=name, k_coefficients=lens.max_radial + 1)
    # the solver's projection and OpenCV's (through CameraModel) agree
    rng = np.random.default_rng(0)
    d = rng.normal(0, 0.01, len(lens.coefficients))
    model = CameraModel(640, 480, np.array([[500.0, 0, 320], [0, 510, 240], [0, 0, 1]]), name, d)
    assert model.is_fisheye == lens.fisheye and model.lens is lens
    assert model.projection is PROJECTIONS[name]
    points = np.column_stack([rng.uniform(-0.3, 0.3, (20, 2)), np.ones(20)])
    uv, _d_point, _d_intrinsics = project(name, intrinsics_of(model), points)
    np.testing.assert_allclose(uv, model.project(points), atol=1e-6)


@pytest.mark.parametrize("name", list(LENS_MODELS))
def test_every_model_unprojects_what_it_projects(name: str) -> None:
    model = _model(name)
    rng = np.random.default_rng(1)
    points = np.column_stack([rng.uniform(-0.35, 0.35, (50, 2)), rng.uniform(0.5, 2.0, 50)])
    pixels = model.project(points)
    np.testing.assert_allclose(model.pixel_rays(pixels),
                               points / np.linalg.norm(points, axis=1, keepdims=True), atol=1e-9)
    np.testing.assert_allclose(model.undistort_pixels(pixels), points[:, :2] / points[:, 2:],
                               atol=1e-9)
    np.testing.assert_allclose(model.distort_normalized(points[:, :2] / points[:, 2:]), pixels,
                               atol=1e-9)


@pytest.mark.parametrize("name", list(LENS_MODELS))
def test_every_model_calibrates_and_round_trips_its_yaml(name: str) -> None:
    truth = _model(name)
    poses = random_poses(np.random.default_rng(2), 12, [truth])
    result = calibrate_mono(BOARD.points_in_board(), views(truth, poses, 0.02, seed=3),
                            (W, H), CalibrationOptions(model=name))
    assert result.models[0].distortion_model == name
    np.testing.assert_allclose(result.models[0].k, truth.k, rtol=2e-3, atol=0.5)
    info = mono_camera_info(result.models[0], "camera")
    back = calibration_from_yaml(calibration_to_yaml(info, camera_name="camera")).camera_info
    assert back.distortion_model == name
    for ours, read in ((info.k, back.k), (info.d, back.d), (info.r, back.r), (info.p, back.p)):
        np.testing.assert_array_equal(read, ours)
    assert np.isfinite(info.p).all() and info.p[0, 0] > 0
    read_model = CameraModel.from_camera_info(back)
    points = BOARD.points_in_board() + np.array([0.0, 0.0, 0.5])
    np.testing.assert_array_equal(read_model.project(points), result.models[0].project(points))


def test_aliases_and_unknown_names() -> None:
    for alias, name in MODEL_ALIASES.items():
        assert lens_model(alias) is LENS_MODELS[name]
        assert CalibrationOptions(model=alias).distortion_model == name
    assert lens_model("").name == "plumb_bob"  # camera_info_manager's empty model
    with pytest.raises(KeyError, match=r"unknown lens model 'kannala'.*plumb_bob.*fisheye"):
        lens_model("kannala")
    with pytest.raises(Exception, match=r"unknown lens model 'kannala'.*plumb_bob.*fisheye"):
        CalibrationOptions(model="kannala")

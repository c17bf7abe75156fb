"""The solver's projection agrees with OpenCV's, and its derivatives with finite differences."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from processors.calibration import rotation
from processors.calibration.lens import INTRINSIC_NAMES, intrinsics_of, model_of, project
from replay.camera import CameraModel

W, H = 640, 480
MODELS = {
    "plumb_bob": CameraModel(W, H, np.array([[800.0, 0, 326], [0, 806, 233], [0, 0, 1]]),
                             "plumb_bob", np.array([-0.2, 0.05, 0.0008, -0.0005, 0.01])),
    "rational_polynomial": CameraModel(
        W, H, np.array([[500.0, 0, 318], [0, 502, 241], [0, 0, 1]]), "rational_polynomial",
        np.array([0.4, -0.1, 0.001, 0.0005, 0.02, 0.7, -0.05, 0.03])),
    "equidistant": CameraModel(W, H, np.array([[190.0, 0, 321], [0, 191, 238], [0, 0, 1]]),
                               "equidistant", np.array([0.03, -0.01, 0.004, -0.001])),
}


def points_in_view(name: str, count: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    half_angle = math.radians(80 if name == "equidistant" else 25)
    theta = rng.uniform(0, half_angle, count)
    phi = rng.uniform(-math.pi, math.pi, count)
    rays = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                            np.cos(theta)])
    return rays * rng.uniform(0.2, 3.0, (count, 1))


@pytest.mark.parametrize("name", list(MODELS))
def test_projection_matches_the_camera_model(name: str) -> None:
    model = MODELS[name]
    points = points_in_view(name, 300, 0)
    uv, _, _ = project(name, intrinsics_of(model), points)
    np.testing.assert_allclose(uv, model.project(points), atol=1e-8)
    assert len(intrinsics_of(model)) == len(INTRINSIC_NAMES[name])
    rebuilt = model_of(name, intrinsics_of(model), (W, H))
    np.testing.assert_array_equal(rebuilt.k, model.k)
    np.testing.assert_array_equal(rebuilt.d, model.d)


@pytest.mark.parametrize("name", list(MODELS))
def test_derivatives_match_finite_differences(name: str) -> None:
    intrinsics = intrinsics_of(MODELS[name])
    points = points_in_view(name, 50, 1)
    _, d_point, d_intrinsics = project(name, intrinsics, points)
    for j in range(3):
        step = np.zeros(3)
        step[j] = 1e-6
        numeric = (project(name, intrinsics, points + step)[0]
                   - project(name, intrinsics, points - step)[0]) / 2e-6
        np.testing.assert_allclose(d_point[:, :, j], numeric, rtol=1e-5, atol=1e-4)
    for j in range(len(intrinsics)):
        step = np.zeros(len(intrinsics))
        step[j] = 1e-7 * max(1.0, abs(intrinsics[j]))
        numeric = (project(name, intrinsics + step, points)[0]
                   - project(name, intrinsics - step, points)[0]) / (2 * step[j])
        np.testing.assert_allclose(d_intrinsics[:, :, j], numeric, rtol=1e-5, atol=1e-4)


def test_equidistant_on_the_optical_axis() -> None:
    intrinsics = intrinsics_of(MODELS["equidistant"])
    axis = np.array([[0.0, 0.0, 2.0], [1e-7, 0.0, 2.0]])
    uv, d_point, _ = project("equidistant", intrinsics, axis)
    assert np.isfinite(d_point).all()
    np.testing.assert_allclose(uv[0], intrinsics[2:4])
    np.testing.assert_allclose(d_point[0], d_point[1], rtol=1e-6, atol=1e-5)


def test_rotation_matrices_and_vectors_are_opencv_rodrigues() -> None:
    rng = np.random.default_rng(2)
    rvecs = np.vstack([rng.normal(0, 1.0, (20, 3)), [[0, 0, 0], [1e-10, 0, 0],
                                                      [0, math.pi - 1e-4, 0]]])
    ours = rotation.matrices(rvecs)
    for rvec, matrix in zip(rvecs, ours, strict=True):
        np.testing.assert_allclose(matrix, cv2.Rodrigues(rvec)[0], atol=1e-12)
    back = rotation.rotation_vectors(ours)
    np.testing.assert_allclose(rotation.matrices(back), ours, atol=1e-9)


def test_rigid_fit_recovers_a_transform_and_the_mean_of_rotations_is_one() -> None:
    rng = np.random.default_rng(3)
    points = rng.normal(0, 0.1, (12, 3))
    turn = rotation.matrices(rng.normal(0, 1.0, (1, 3)))[0]
    shift = rng.normal(0, 1.0, 3)
    fit = rotation.rigid_fit(points, points @ turn.T + shift)
    np.testing.assert_allclose(fit[:3, :3], turn, atol=1e-12)
    np.testing.assert_allclose(fit[:3, 3], shift, atol=1e-12)
    # a small turn either way about one axis averages to no turn at all
    either = rotation.matrices(np.array([[0.0, 0.0, 0.1], [0.0, 0.0, -0.1]]))
    np.testing.assert_allclose(rotation.nearest_rotation(either.sum(axis=0)), np.eye(3),
                               atol=1e-12)


@pytest.mark.parametrize("name", sorted(INTRINSIC_NAMES))
def test_a_point_in_the_camera_plane_has_no_projection_and_no_warning(name: str) -> None:
    """A poor starting pose can put board points at z = 0: their rows are not finite (the
    solver leaves such corners out) and numpy says nothing (pytest turns warnings into
    errors). The fisheye sees 90 degrees off its axis: only the lens centre itself has no
    projection there."""
    intrinsics = np.concatenate([[500.0, 500.0, 319.5, 239.5],
                                 np.full(len(INTRINSIC_NAMES[name]) - 4, 0.01)])
    points = np.array([[0.1, -0.05, 0.0], [0.0, 0.0, 0.0], [0.02, 0.01, 0.5]])
    uv, d_point, d_intrinsics = project(name, intrinsics, points)
    unprojected = 1 if name == "equidistant" else 2
    assert not np.isfinite(uv[2 - unprojected:2]).all(axis=1).any()
    assert np.isfinite(uv[2]).all() and np.isfinite(d_point[2]).all() \
        and np.isfinite(d_intrinsics[2]).all()

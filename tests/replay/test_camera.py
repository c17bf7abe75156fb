"""CameraModel's equidistant fisheye against OpenCV's cv2.fisheye, and past 90 degrees."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from replay.camera import CameraModel, rectify_maps, stereo_right_from_left
from replay.lens_models import LENS_MODELS, canonical_name
from replay.messages import F64, CameraInfo

K = np.array([[214.7, 0.0, 322.3], [0.0, 214.9, 237.6], [0.0, 0.0, 1.0]])
D = np.array([-0.0063, 0.0414, -0.0389, 0.0070])


def fisheye(d: F64 = D) -> CameraModel:
    return CameraModel(640, 480, K, "equidistant", d)


def rays_at(theta_rad: F64, phi_rad: F64) -> F64:
    """Unit rays (N, 3) at angle theta from the optical axis, azimuth phi."""
    return np.column_stack([np.sin(theta_rad) * np.cos(phi_rad),
                            np.sin(theta_rad) * np.sin(phi_rad), np.cos(theta_rad)])


def test_equidistant_is_a_fisheye_model_with_four_coefficients() -> None:
    assert len(LENS_MODELS["equidistant"].coefficients) == 4
    assert LENS_MODELS["equidistant"].fisheye
    model = fisheye()
    assert model.is_fisheye and not model.is_ideal
    assert not CameraModel(640, 480, K).is_fisheye
    with pytest.raises(ValueError, match="at most 4"):
        CameraModel(640, 480, K, "equidistant", np.zeros(5))
    info = model.camera_info(stamp_ns=1, frame_id="fisheye")
    assert info.distortion_model == "equidistant"
    np.testing.assert_array_equal(CameraModel.from_camera_info(info).d, D)


def test_projection_is_cv2_fisheye() -> None:
    rng = np.random.default_rng(0)
    points = rng.normal(size=(500, 3))
    points[:, 2] = np.abs(points[:, 2]) + 0.05  # in front: cv2.fisheye's domain
    expected, _ = cv2.fisheye.projectPoints(points.reshape(-1, 1, 3), np.zeros(3), np.zeros(3),
                                            K, D)
    np.testing.assert_allclose(fisheye().project(points), expected.reshape(-1, 2), atol=1e-9)


def test_undistort_pixels_is_cv2_fisheye() -> None:
    model = fisheye()
    theta = np.linspace(0.0, math.radians(80), 40)
    pixels = model.project(rays_at(theta, np.linspace(0, 6, 40)))
    expected = cv2.fisheye.undistortPoints(
        pixels.reshape(-1, 1, 2), K, D,
        criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14))
    np.testing.assert_allclose(model.undistort_pixels(pixels), expected.reshape(-1, 2),
                               atol=1e-9)


def test_rays_round_trip_beyond_90_degrees() -> None:
    """A ray 110 degrees off axis (behind the image plane) has a pixel and comes back."""
    model = fisheye()
    theta = np.linspace(0.0, math.radians(115), 60)
    phi = np.linspace(-3.0, 3.0, 60)
    rays = rays_at(theta, phi)
    pixels = model.project(rays)
    assert np.all(np.isfinite(pixels))
    # the distorted radius grows with theta along each azimuth: theta_d (1 + k1 theta^2 ...)
    t2 = theta**2
    theta_d = theta * (1 + t2 * (D[0] + t2 * (D[1] + t2 * (D[2] + t2 * D[3]))))
    expected = np.column_stack([K[0, 0] * theta_d * np.cos(phi) + K[0, 2],
                                K[1, 1] * theta_d * np.sin(phi) + K[1, 2]])
    np.testing.assert_allclose(pixels, expected, atol=1e-9)
    np.testing.assert_allclose(model.pixel_rays(pixels), rays, atol=1e-12)
    # no pinhole coordinates from 90 degrees on
    behind = model.undistort_pixels(pixels)[theta >= math.radians(90)]
    assert np.isnan(behind).all()


def test_pinhole_rays_are_unit_undistorted_directions() -> None:
    model = CameraModel(640, 480, K, "plumb_bob", np.array([-0.2, 0.05, 0.001, 0.0, 0.0]))
    pixels = np.array([[0.0, 0.0], [322.3, 237.6], [639.0, 479.0]])
    rays = model.pixel_rays(pixels)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0)
    np.testing.assert_allclose(model.project(rays), pixels, atol=1e-6)


def test_rectified_points_match_opencv() -> None:
    k = np.array([[800.0, 0.0, 326.0], [0.0, 806.0, 233.0], [0.0, 0.0, 1.0]])
    d = np.array([-0.2, 0.05, 0.0008, -0.0005, 0.01])
    model = CameraModel(640, 480, k, "plumb_bob", d)
    r = cv2.Rodrigues(np.array([0.01, -0.02, 0.005]))[0]
    p = np.array([[700.0, 0, 310, -14.0], [0, 700, 240, 0], [0, 0, 1, 0]])
    uv = np.random.default_rng(4).uniform([20, 20], [620, 460], (40, 2))
    expected = cv2.undistortPoints(uv.reshape(-1, 1, 2), k, d, R=r, P=p,
                                   criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS,
                                             100, 1e-14))
    np.testing.assert_allclose(model.rectify_points(uv, r, p), expected.reshape(-1, 2),
                               atol=1e-6)


@pytest.mark.parametrize("distortion_model", ["equidistant", "fisheye"])
def test_fisheye_rectification_maps_sample_where_the_lens_images_the_ray(
        distortion_model: str) -> None:
    new_k = np.array([[150.0, 0, 319.5], [0, 150.0, 239.5], [0, 0, 1]])
    r = cv2.Rodrigues(np.array([0.0, 0.1, 0.0]))[0]
    info = CameraInfo(0, "cam", 640, 480, distortion_model, D, K, r,
                      np.hstack([new_k, np.zeros((3, 1))]))
    map_x, map_y = rectify_maps(info, cv2.CV_32FC1)
    out_uv = np.array([[100, 50], [319, 239], [600, 400], [20, 460]])
    rays = np.column_stack([out_uv, np.ones(len(out_uv))]) @ np.linalg.inv(new_k).T @ r
    expected = fisheye().project(rays)
    sampled = np.column_stack([map_x[out_uv[:, 1], out_uv[:, 0]],
                               map_y[out_uv[:, 1], out_uv[:, 0]]])
    np.testing.assert_allclose(sampled, expected, atol=1e-3)


def test_model_names() -> None:
    assert canonical_name("fisheye") == "equidistant"
    assert canonical_name("") == "plumb_bob"
    info = CameraInfo(0, "", 640, 480, "fisheye", D, K)
    assert CameraModel.from_camera_info(info).distortion_model == "equidistant"
    with pytest.raises(ValueError, match="unknown distortion model"):
        CameraModel(640, 480, K, "kannala_brandt_8")


@pytest.mark.parametrize("translation", [[-0.12, 0.003, 0.002], [0.004, -0.09, -0.001]],
                         ids=["horizontal", "vertical"])
def test_a_pairs_camera_infos_give_back_the_rig(translation: list[float]) -> None:
    # the rectification OpenCV computes for a known rig, written as ROS's camera_infos
    k1 = np.array([[800.0, 0.0, 322.0], [0.0, 802.0, 241.0], [0.0, 0.0, 1.0]])
    k2 = np.array([[810.0, 0.0, 318.0], [0.0, 809.0, 236.0], [0.0, 0.0, 1.0]])
    d1, d2 = np.array([-0.2, 0.05, 0.001, 0.0, 0.0]), np.array([-0.18, 0.04, 0.0, 0.001, 0.0])
    rotation = cv2.Rodrigues(np.array([0.01, -0.035, 0.02]))[0]
    t = np.array(translation).reshape(3, 1)
    r1, r2, p1, p2, *_ = cv2.stereoRectify(k1, d1, k2, d2, (640, 480), rotation, t)
    left = CameraInfo(0, "l", 640, 480, "plumb_bob", d1, k1, r1, p1)
    right = CameraInfo(0, "r", 640, 480, "plumb_bob", d2, k2, r2, p2)
    got = stereo_right_from_left(left, right)
    assert got is not None
    np.testing.assert_allclose(got[:3, :3], rotation, atol=1e-9)
    np.testing.assert_allclose(got[:3, 3], t.ravel(), atol=1e-9)
    assert stereo_right_from_left(left, left) is None  # no baseline in P

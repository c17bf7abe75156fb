"""The pinhole views of a lens: which ones, what they hold, and maps that agree with the
lens model."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from replay.camera import CameraModel
from replay.messages import CameraInfo
from replay.pinhole_views import MAX_HALF_ANGLE_RAD, WIDE_HALF_ANGLE_RAD, pinhole_views

W, H = 320, 240
#: the scenarios' lenses at 320x240
HELDOUT = CameraInfo(0, "c", W, H, "plumb_bob", np.array([-0.21, 0.11, 0.0007, -0.0005, -0.03]),
                     np.array([[510.7, 0, 165.6], [0, 523.95, 113.85], [0, 0, 1]]))
CHARUCO = CameraInfo(0, "c", W, H, "rational_polynomial",
                     np.array([-0.32, 0.11, 0.0004, -0.0003, -0.018, 0.02, 0.01, -0.004]),
                     np.array([[256.15, 0, 158.85], [0, 256.55, 121.05], [0, 0, 1]]))
FISHEYE = CameraInfo(0, "c", W, H, "equidistant", np.array([-0.040, 0.0012, -0.0008, 0.0001]),
                     np.array([[115.85, 0, 160.9], [0, 115.95, 118.55], [0, 0, 1]]))


def _border(width: int, height: int, step: float = 0.5) -> np.ndarray:
    us, vs = np.arange(-0.5, width, step), np.arange(-0.5, height, step)
    return np.vstack([np.column_stack([us, np.full_like(us, -0.5)]),
                      np.column_stack([us, np.full_like(us, height - 0.5)]),
                      np.column_stack([np.full_like(vs, -0.5), vs]),
                      np.column_stack([np.full_like(vs, width - 0.5), vs])])


def _in_view(info: CameraInfo, uv_raw: np.ndarray, view_index: int = 0) -> np.ndarray:
    """Where raw pixels land in a view (through the lens's rays)."""
    view = pinhole_views(info)[view_index]
    rays = CameraModel.from_camera_info(info).pixel_rays(uv_raw) @ view.rotation.T
    uv = rays @ view.k.T
    return np.asarray(uv[:, :2] / uv[:, 2:])


def test_a_pinhole_camera_needs_no_view() -> None:
    ideal = CameraModel.ideal(W, H, 1.0).camera_info(stamp_ns=0, frame_id="c")
    assert pinhole_views(ideal) == []
    assert pinhole_views(CameraInfo(0, "c", W, H, "", np.zeros(5), ideal.k)) == []
    # an equidistant lens with no coefficients is still no pinhole
    (view,) = pinhole_views(CameraInfo(0, "c", W, H, "fisheye", np.zeros(4), ideal.k))
    assert view.name == "undistorted"


@pytest.mark.parametrize("info", [HELDOUT, CHARUCO], ids=["plumb_bob", "rational"])
def test_the_undistorted_view_holds_the_whole_raw_image(info: CameraInfo) -> None:
    (view,) = pinhole_views(info)
    assert (view.name, view.width, view.height, view.covered) == ("undistorted", W, H, 1.0)
    assert view.k[0, 0] / view.k[1, 1] == pytest.approx(info.k[0, 0] / info.k[1, 1])
    uv = _in_view(info, _border(W, H))
    margin = 1e-6
    assert uv[:, 0].min() >= -0.5 - margin and uv[:, 0].max() <= W - 0.5 + margin
    assert uv[:, 1].min() >= -0.5 - margin and uv[:, 1].max() <= H - 0.5 + margin
    # and no larger than it must be: the raw border touches two opposite edges
    touches_x = uv[:, 0].min() < -0.49 and uv[:, 0].max() > W - 0.51
    touches_y = uv[:, 1].min() < -0.49 and uv[:, 1].max() > H - 0.51
    assert touches_x or touches_y


def test_a_wide_fisheye_gets_a_wider_second_view_and_says_what_is_cut() -> None:
    undistorted, wide = pinhole_views(FISHEYE)
    assert (undistorted.name, wide.name) == ("undistorted", "wide")
    across, down = undistorted.fov_rad
    assert min(across, down) == pytest.approx(2 * MAX_HALF_ANGLE_RAD, abs=1e-9)
    assert min(wide.fov_rad) == pytest.approx(2 * WIDE_HALF_ANGLE_RAD, abs=1e-9)
    assert 0.5 < undistorted.covered < wide.covered < 1.0
    # the coverage is the share of raw pixels whose rays land in the view
    us, vs = np.meshgrid(np.arange(0, W, 2.0), np.arange(0, H, 2.0))
    uv_raw = np.column_stack([us.ravel(), vs.ravel()])
    for index, view in enumerate((undistorted, wide)):
        rays = CameraModel.from_camera_info(FISHEYE).pixel_rays(uv_raw)
        ahead = rays[:, 2] > 0
        uv = _in_view(FISHEYE, uv_raw[ahead], index)
        inside = (uv[:, 0] >= -0.5) & (uv[:, 0] <= W - 0.5) & (uv[:, 1] >= -0.5) \
            & (uv[:, 1] <= H - 0.5)
        assert inside.sum() / len(uv_raw) == pytest.approx(view.covered, abs=0.01)
    assert "undistorted 320x240" in undistorted.describe()
    assert f"{100 * wide.covered:.1f} % of the raw image" in wide.describe()


def test_a_rectified_stereo_camera_keeps_its_p_and_r() -> None:
    r = cv2.Rodrigues(np.array([0.01, -0.02, 0.005]))[0]
    p = np.array([[400.0, 0, 150.0, -8.0], [0, 400.0, 120.0, 0], [0, 0, 1, 0]])
    info = CameraInfo(0, "c", W, H, "plumb_bob", HELDOUT.d, HELDOUT.k, r, p)
    (view,) = pinhole_views(info)
    assert view.name == "rectified"
    np.testing.assert_array_equal(view.k, p[:, :3])
    np.testing.assert_array_equal(view.rotation, r)
    (half,) = pinhole_views(info, scale=0.5)
    assert (half.width, half.height) == (W // 2, H // 2)
    assert half.k[0, 0] == 200.0 and half.k[0, 2] == pytest.approx((150.0 + 0.5) / 2 - 0.5)


@pytest.mark.parametrize("info", [HELDOUT, CHARUCO, FISHEYE],
                         ids=["plumb_bob", "rational", "equidistant"])
def test_the_maps_sample_the_raw_image_where_the_lens_images_each_view_pixel(
        info: CameraInfo) -> None:
    model = CameraModel.from_camera_info(info)
    for view in pinhole_views(info):
        map_u, map_v = view.maps(model, cv2.CV_32FC1)
        assert map_u.shape == (view.height, view.width)
        us, vs = np.meshgrid(np.arange(0, view.width, 7), np.arange(0, view.height, 7))
        uv = np.column_stack([us.ravel(), vs.ravel()]).astype(np.float64)
        rays = np.column_stack([uv, np.ones(len(uv))]) @ np.linalg.inv(view.k).T
        rays = rays @ view.rotation  # into the lens's frame
        off_axis = np.arccos(rays[:, 2] / np.linalg.norm(rays, axis=1))
        keep = off_axis < math.radians(80)
        expected = model.project(rays[keep])
        sampled = np.column_stack([map_u[vs.ravel(), us.ravel()],
                                   map_v[vs.ravel(), us.ravel()]])[keep]
        np.testing.assert_allclose(sampled, expected, atol=2e-3)

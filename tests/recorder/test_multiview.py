"""plan_multiview_optics: a fisheye rendered as several pinhole views, warped exactly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from recorder.errors import ScenarioError
from recorder.multiview import (
    MultiViewOptics,
    plan_camera_optics,
    plan_multiview_optics,
    view_rotations,
)
from recorder.optics import Optics, View
from replay.camera import CameraModel
from replay.messages import F64

W, H = 96, 72


#: close to an equisolid lens (r = 2 f sin(theta / 2))
EQUISOLID = (-0.040, 0.0012, -0.0008, 0.0001)


def fisheye(f: float = 36.0, d: tuple[float, ...] = EQUISOLID) -> CameraModel:
    k = np.array([[f, 0, (W - 1) / 2 + 0.7], [0, f * 1.002, (H - 1) / 2 - 0.4], [0, 0, 1]])
    return CameraModel(W, H, k, "equidistant", np.array(d))


def view_of_row(optics: MultiViewOptics, atlas_y: F64) -> np.ndarray:
    """Index of the view each atlas row belongs to."""
    starts = np.array([v.atlas_row for v in optics.views])
    return np.asarray(np.searchsorted(starts, atlas_y, side="right") - 1)


def atlas_rays(optics: MultiViewOptics, atlas_x: F64, atlas_y: F64) -> F64:
    """Unit rays (N, 3) in the camera frame of atlas positions, through the views' pinholes."""
    index = view_of_row(optics, atlas_y)
    rays = np.empty((len(atlas_x), 3))
    for i, view in enumerate(optics.views):
        at = index == i
        local = np.column_stack([(atlas_x[at] - view.cx) / view.focal_px,
                                 (atlas_y[at] - view.atlas_row - view.cy) / view.focal_px,
                                 np.ones(int(at.sum()))])
        rays[at] = local @ view.camera_from_view.T
    return rays / np.linalg.norm(rays, axis=1, keepdims=True)


def pixel_centres() -> F64:
    grid_u, grid_v = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
    return np.column_stack([grid_u.ravel(), grid_v.ravel()])


@pytest.fixture(scope="module")
def optics() -> MultiViewOptics:
    return plan_multiview_optics(fisheye(), 2)


def test_fisheye_gets_multiview_optics_and_pinholes_keep_theirs() -> None:
    assert isinstance(plan_camera_optics(fisheye(), 2), MultiViewOptics)
    pinhole = CameraModel(W, H, np.array([[80.0, 0, 47.5], [0, 80.0, 35.5], [0, 0, 1]]))
    assert isinstance(plan_camera_optics(pinhole, 2), Optics)


def test_view_directions_are_the_cube_faces_edges_and_corners() -> None:
    rotations = view_rotations()
    assert len(rotations) == 26
    for r in rotations:
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
        assert np.linalg.det(r) == pytest.approx(1.0)
    axes = np.round(np.array([r[:, 2] for r in rotations]) * np.sqrt(3), 6)
    assert len({tuple(a) for a in axes}) == 26


def test_a_wide_fisheye_needs_views_beside_and_behind_the_camera(
    optics: MultiViewOptics,
) -> None:
    model = fisheye()
    edge = model.pixel_rays(np.array([[0.0, model.cy], [W - 1.0, model.cy], [0.0, 0.0]]))
    angles_deg = np.degrees(np.arccos(edge[:, 2]))
    assert angles_deg[:2].sum() > 160  # horizontal field of view
    assert angles_deg[2] > 110  # the image corners look behind the camera
    axes = np.array([v.camera_from_view[:, 2] for v in optics.views])
    assert (axes[:, 2] > 0.99).sum() == 1  # one view straight ahead
    assert (np.abs(axes[:, 2]) < 1e-9).sum() >= 4  # views at right angles to the axis
    assert (axes[:, 2] < 0).sum() >= 1  # and some looking backwards: rays past 90 degrees
    assert optics.output_size == (W, H) and optics.supersample == 2
    n = optics.samples_per_side
    assert optics.map_x.shape == optics.map_y.shape == (H * n, W * n)


def sample_errors(optics: MultiViewOptics, model: CameraModel) -> F64:
    """Distance (output px) from each sample's ray to its sub-pixel centre."""
    n = optics.samples_per_side
    offsets = (np.arange(n) + 0.5) / n - 0.5
    sub_u, sub_v = np.meshgrid((np.arange(W)[:, None] + offsets[None]).ravel(),
                               (np.arange(H)[:, None] + offsets[None]).ravel())
    rays = atlas_rays(optics, optics.map_x.ravel().astype(np.float64),
                      optics.map_y.ravel().astype(np.float64))
    sub_pixels = np.column_stack([sub_u.ravel(), sub_v.ravel()])
    return np.asarray(np.linalg.norm(model.project(rays) - sub_pixels, axis=1))


def test_samples_sit_on_their_exact_sub_pixel_rays(optics: MultiViewOptics) -> None:
    """Each pixel's samples come from the quadratic through its exact rays: even at 1.6
    degrees a pixel (this tiny lens; third-order terms shrink with the cube of that) they sit
    within 0.01 px of the exact sub-pixel rays."""
    errors = sample_errors(optics, fisheye())
    assert errors.max() < 0.01 and np.median(errors) < 5e-4


def test_views_are_dense_enough_and_samples_skip_no_render_pixel(
    optics: MultiViewOptics,
) -> None:
    n, s = optics.samples_per_side, optics.supersample
    x = optics.map_x.astype(np.float64).reshape(H, n, W, n)
    y = optics.map_y.astype(np.float64).reshape(H, n, W, n)
    view = view_of_row(optics, y.ravel()).reshape(y.shape)
    # neighbouring samples of one pixel are at most one render pixel apart
    step_u = np.hypot(np.diff(x, axis=3), np.diff(y, axis=3))
    step_v = np.hypot(np.diff(x, axis=1), np.diff(y, axis=1))
    assert max(step_u.max(), step_v.max()) <= 1.0 + 1e-4
    # neighbouring pixels in the same view are >= s render pixels apart
    cx, cy, cview = x.mean(axis=(1, 3)), y.mean(axis=(1, 3)), view[:, 0, :, 0]
    same_u = cview[:, 1:] == cview[:, :-1]
    gap_u = np.hypot(np.diff(cx, axis=1), np.diff(cy, axis=1))[same_u]
    same_v = cview[1:] == cview[:-1]
    gap_v = np.hypot(np.diff(cx, axis=0), np.diff(cy, axis=0))[same_v]
    assert min(gap_u.min(), gap_v.min()) >= s * 0.98


def test_every_sample_reads_inside_its_view(optics: MultiViewOptics) -> None:
    x = optics.map_x.astype(np.float64).ravel()
    y = optics.map_y.astype(np.float64).ravel()
    index = view_of_row(optics, y)
    for i, view in enumerate(optics.views):
        at = index == i
        assert at.any()
        local_y = y[at] - view.atlas_row
        # the bilinear sample's second pixel and a guard stay inside the view
        assert x[at].min() >= 1.0 and x[at].max() <= view.width - 2.0
        assert local_y.min() >= 1.0 and local_y.max() <= view.height - 2.0


def test_warp_is_the_mean_of_the_samples(optics: MultiViewOptics) -> None:
    """An atlas holding its own coordinates: bilinear sampling is exact on it, so each output
    pixel reads the mean position of its n x n samples."""
    rows = sum(v.height for v in optics.views)
    cols = max(v.width for v in optics.views)
    grid_x, grid_y = np.meshgrid(np.arange(cols, dtype=np.float32),
                                 np.arange(rows, dtype=np.float32))
    atlas = np.dstack([grid_x, grid_y, np.zeros_like(grid_x)])
    image = optics.apply(atlas)
    assert image.shape == (H, W, 3)
    n = optics.samples_per_side
    for channel, samples in enumerate((optics.map_x, optics.map_y)):
        mean = samples.astype(np.float64).reshape(H, n, W, n).mean(axis=(1, 3))
        np.testing.assert_allclose(image[..., channel], mean, atol=2e-3)
    flat = optics.apply(np.full((rows, cols, 3), 200, np.uint8))
    assert flat.dtype == np.uint8 and (flat == 200).all()


def test_views_fit_their_atlas_rows(optics: MultiViewOptics) -> None:
    row = 0
    for view in optics.views:
        assert isinstance(view, View)
        assert view.atlas_row == row
        row += view.height
        np.testing.assert_allclose(view.camera_from_view.T @ view.camera_from_view, np.eye(3),
                                   atol=1e-12)


def test_fisheye_past_180_degrees_all_around() -> None:
    """A 250-degree lens: every pixel's ray comes back, some from behind the camera."""
    model = fisheye(f=W / 2 / math.radians(125), d=(0.0, 0.0, 0.0, 0.0))
    optics = plan_multiview_optics(model, 1)
    corner = model.pixel_rays(np.array([[0.0, 0.0]]))
    assert corner[0, 2] < -0.5
    axes = np.array([v.camera_from_view[:, 2] for v in optics.views])
    assert axes[:, 2].min() < -0.9  # the view straight behind
    assert sample_errors(optics, model).max() < 0.01


def test_non_invertible_fisheye_is_rejected() -> None:
    # theta_d = theta (1 - 0.3 theta^2) peaks at theta = 1 / sqrt(0.9) rad, well inside
    with pytest.raises(ScenarioError, match="not invertible"):
        plan_multiview_optics(fisheye(d=(-0.3, 0.0, 0.0, 0.0)), 2)

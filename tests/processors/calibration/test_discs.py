"""The centroid of a projected disc: exact where a closed form exists, converged elsewhere,
and the shifts the solver applies are those centroids."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from processors.calibration import bundle
from processors.calibration.discs import centroid_shifts, disc_centroids
from processors.calibration.lens import intrinsics_of

from .synthetic import K_TRUE, true_model

RADIUS_M = 0.005


def discs(count: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotations ``(M, 3, 3)`` (camera from board), centres ``(M, 3)`` 0.15-0.3 m away and
    the board axes ``(M, 2, 3)`` of tilted discs across the view."""
    rng = np.random.default_rng(seed)
    rotations = np.stack([cv2.Rodrigues(rng.uniform(-0.8, 0.8, 3))[0] for _ in range(count)])
    depth = rng.uniform(0.15, 0.3, count)
    centres = np.column_stack([rng.uniform(-0.3, 0.3, (count, 2)) * depth[:, None], depth])
    return rotations, centres, np.swapaxes(rotations[:, :, :2], 1, 2)


def ellipse_centre(camera_from_plane: np.ndarray, radius_m: float) -> np.ndarray:
    """Centre (2,) of the ellipse a pinhole K_TRUE images a circle as: the circle's conic
    carried through the plane's homography ``K [r1 r2 t]``."""
    homography = K_TRUE @ camera_from_plane
    inverse = np.linalg.inv(homography)
    conic = inverse.T @ np.diag([1.0, 1.0, -radius_m ** 2]) @ inverse
    return np.asarray(-np.linalg.solve(conic[:2, :2], conic[:2, 2]))


def test_a_pinhole_images_the_centroid_at_the_ellipse_centre() -> None:
    rotations, centres, axes = discs(50, 0)
    intrinsics = intrinsics_of(true_model(d=np.zeros(5)))
    projected, centroid = disc_centroids("plumb_bob", intrinsics, centres, axes,
                                         radius_m=RADIUS_M)
    exact = np.array([ellipse_centre(np.column_stack([r[:, 0], r[:, 1], c]), RADIUS_M)
                      for r, c in zip(rotations, centres, strict=True)])
    assert np.abs(centroid - exact).max() < 1e-9
    # the centroid is not the projected centre: that is the bias being modelled
    assert np.linalg.norm(centroid - projected, axis=1).max() > 0.3


@pytest.mark.parametrize("samples", [12, 16])
def test_the_centroid_converges_through_distortion(samples: int) -> None:
    _rotations, centres, axes = discs(50, 1)
    intrinsics = intrinsics_of(true_model())
    _p, few = disc_centroids("plumb_bob", intrinsics, centres, axes, radius_m=RADIUS_M,
                             samples=samples)
    _p, many = disc_centroids("plumb_bob", intrinsics, centres, axes, radius_m=RADIUS_M,
                              samples=256)
    assert np.abs(few - many).max() < 1e-6


def test_shifts_are_the_centroids_of_each_seen_circle() -> None:
    rotations, centres, _axes = discs(3, 2)
    points = np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.0, 0.01, 0.0]])
    model = true_model()
    # the rig's reference camera looks at one board pose per view
    state = bundle.RigState([intrinsics_of(model)], np.eye(3)[None], np.zeros((1, 3)),
                            rotations, centres)
    setups = [bundle.CameraSetup("plumb_bob", (model.width, model.height), ("fx", "fy"))]
    mask = np.array([[True, True, False], [True, True, True], [False, True, True]])
    obs = bundle.Observations(np.zeros(3, np.int64), np.arange(3), np.zeros((3, 3, 2)), mask,
                              np.ones(3))
    layout = bundle.Layout.of(setups, state, corners=obs.corners(len(setups)))
    shifts = centroid_shifts(state, layout, obs, points, RADIUS_M)
    assert np.all(shifts[~mask] == 0.0)
    for view in range(3):
        in_camera = points @ rotations[view].T + centres[view]
        axes = np.repeat(rotations[view][:, :2].T[None], len(points), axis=0)
        projected, centroid = disc_centroids("plumb_bob", intrinsics_of(model), in_camera,
                                             axes, radius_m=RADIUS_M)
        seen = mask[view]
        assert np.allclose(shifts[view, seen], (centroid - projected)[seen], atol=1e-12)
        assert np.allclose(projected, model.project(in_camera), atol=1e-9)

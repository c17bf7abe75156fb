"""Processor and calibration outputs converted to drawable arrays."""

from __future__ import annotations

import numpy as np

from processors.red_pixels import draw_marker
from replay.camera import CameraModel
from replay.geometry import quat_xyzw_from_rotation, rotation_about
from replay.wire import serialize
from rerun_export.overlays import (
    CENTROID_MARKER,
    EDGE,
    MASK_PIXEL,
    edge_classes,
    mask_classes,
    project_target,
    stamp_free_key,
)


def test_mask_classes_of_the_red_pixels_output() -> None:
    mask = np.zeros((40, 60), np.uint8)
    mask[10:20, 30:45] = 255
    rgb = draw_marker(mask, 37.0, 15.0)  # blue 11x11 square over the red pixels' centre
    classes = mask_classes(rgb)
    assert classes[15, 37] == CENTROID_MARKER
    assert classes[10, 30] == MASK_PIXEL
    assert classes[0, 0] == 0
    assert int((classes == CENTROID_MARKER).sum()) == 11 * 11


def test_edge_classes() -> None:
    edges = np.array([[0, 255, 200, 100]], np.uint8)
    assert edge_classes(edges).tolist() == [[0, EDGE, EDGE, 0]]


def test_projection_matches_the_camera_model() -> None:
    model = CameraModel(640, 480, np.array([[500, 0, 320], [0, 510, 240], [0, 0, 1.0]]),
                        "plumb_bob", np.array([-0.2, 0.05, 0, 0, 0]))
    camera_from_target = rotation_about(np.array([0.0, 1, 0]), 0.3)
    position = np.array([0.01, -0.02, 0.3])
    points = np.array([[0, 0, 0], [0.05, 0.02, 0], [0, 0, -1.0]])  # the last lies behind
    uv = project_target(points, position_m=position, model=model,
                        orientation_xyzw=quat_xyzw_from_rotation(camera_from_target))
    in_camera = points[:2] @ camera_from_target.T + position
    np.testing.assert_allclose(uv, model.project(in_camera), atol=1e-9)


def test_stamp_free_key_ignores_only_the_stamp() -> None:
    info = CameraModel.ideal(64, 48, 0.6).camera_info(stamp_ns=1, frame_id="cam")
    later = CameraModel.ideal(64, 48, 0.6).camera_info(stamp_ns=10**18 + 7, frame_id="cam")
    other = CameraModel.ideal(64, 48, 0.7).camera_info(stamp_ns=1, frame_id="cam")
    for serialization in ("cdr", "ros1"):
        a, b, c = (serialize(m, serialization) for m in (info, later, other))
        assert a != b and stamp_free_key(a) == stamp_free_key(b)
        assert stamp_free_key(a) != stamp_free_key(c)

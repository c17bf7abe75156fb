"""A camera drifting away from its calibration: rendered turned, truth turned, info unchanged."""

from __future__ import annotations

import math
from collections.abc import Callable

import cv2
import numpy as np
import pytest

from recorder.drift import DriftSpec, world_from_camera_at
from recorder.errors import ScenarioError
from recorder.scenario import load_scenario
from replay.camera import CameraModel
from replay.geometry import invert, rotation_about
from replay.messages import F64

from .logs import Log, transform

LEFT, RIGHT = "/stereo_camera/left", "/stereo_camera/right"
DRIFT = {"camera": "right", "axis": "pitch", "degrees": 0.5, "start_s": 1.0}
SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)


@pytest.fixture(scope="module")
def drifted(recording: Callable[..., Log]) -> Log:
    """stereo_checkerboard, 2 s at 320x240, the right camera pitched 0.5° from 1 s on."""
    return recording("stereo_checkerboard", duration_s=2.0, width=320, height=240,
                     drifts=[DRIFT])


def _seconds(log: Log, stamp_ns: int) -> float:
    return (stamp_ns - log.images(LEFT)[0].stamp_ns) * 1e-9


def test_the_scenario_record_lists_the_drift(drifted: Log) -> None:
    (drift,) = drifted.scenario["drifts"]
    start_ns = drifted.images(LEFT)[0].stamp_ns
    assert drift == {"camera": "right", "namespace": RIGHT, "axis": "pitch", "degrees": 0.5,
                     "start_s": 1.0, "start_stamp_ns": start_ns + 1_000_000_000}


def test_camera_info_keeps_the_calibration(drifted: Log) -> None:
    infos = drifted.infos(RIGHT)
    assert all(np.array_equal(i.p, infos[0].p) and np.array_equal(i.r, infos[0].r)
               for i in infos)


def test_truth_turns_the_right_camera_about_its_x_axis_from_the_start_on(drifted: Log) -> None:
    turned = rotation_about(np.array([1.0, 0, 0]), math.radians(0.5))
    for left, right in zip(drifted.truths(LEFT, "checkerboard"),
                           drifted.truths(RIGHT, "checkerboard"), strict=True):
        right_from_left = transform(right) @ invert(transform(left))
        before = _seconds(drifted, right.stamp_ns) < 1.0
        expected = np.eye(3) if before else turned.T
        np.testing.assert_allclose(right_from_left[:3, :3], expected, atol=1e-9)
        np.testing.assert_allclose(right_from_left[:3, 3], expected @ [-0.02, 0, 0], atol=1e-9)


def _corner_errors(log: Log, namespace: str) -> F64:
    """Distance (px) from every detected corner to its true corner, over the frames after
    the drift that show the whole board."""
    (target,) = log.scenario["targets"]
    pattern = tuple(target["inner_corners"])
    corners = np.array(target["corners_in_target"])
    errors = []
    for image, info, pose in zip(log.images(namespace), log.infos(namespace),
                                 log.truths(namespace, "checkerboard"), strict=True):
        if _seconds(log, image.stamp_ns) < 1.0:
            continue
        gray = cv2.cvtColor(image.pixels, cv2.COLOR_RGB2GRAY)
        found, detected = cv2.findChessboardCorners(gray, pattern)
        if not found:
            continue
        detected = cv2.cornerSubPix(gray, detected, (5, 5), (-1, -1), SUBPIX_CRITERIA)
        camera_from_board = transform(pose)
        projected = CameraModel.from_camera_info(info).project(
            corners @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])
        distances = np.linalg.norm(detected.reshape(-1, 1, 2) - projected[None], axis=2)
        errors.append(distances.min(axis=1))
    assert len(errors) >= 5
    return np.concatenate(errors)


def test_the_turned_camera_sees_the_board_where_its_truth_says(drifted: Log) -> None:
    errors = _corner_errors(drifted, RIGHT)
    assert np.median(errors) < 0.15, f"median {np.median(errors):.3f} px"


def test_the_pixels_did_move(recording: Callable[..., Log], drifted: Log) -> None:
    """The same recording without the drift: the turned frames differ, the earlier match."""
    clean = recording("stereo_checkerboard", duration_s=2.0, width=320, height=240)
    for a, b in zip(clean.images(RIGHT), drifted.images(RIGHT), strict=True):
        same = np.array_equal(a.pixels, b.pixels)
        assert same == (_seconds(clean, a.stamp_ns) < 1.0)
    assert all(np.array_equal(a.pixels, b.pixels)
               for a, b in zip(clean.images(LEFT), drifted.images(LEFT), strict=True))


def test_drifts_of_one_camera_compose_in_the_order_they_start() -> None:
    (camera, _) = load_scenario("stereo_checkerboard").cameras
    drifts = [DriftSpec("left", "yaw", 2.0, 3.0), DriftSpec("left", "roll", 1.0, 1.0),
              DriftSpec("right", "pitch", 5.0, 0.0)]
    np.testing.assert_array_equal(world_from_camera_at(camera, drifts, 0.5),
                                  camera.world_from_camera)
    roll = rotation_about(np.array([0, 0, 1.0]), math.radians(1.0))
    yaw = rotation_about(np.array([0, 1.0, 0]), math.radians(2.0))
    turned = world_from_camera_at(camera, drifts, 3.0)
    np.testing.assert_allclose(turned[:3, :3], camera.world_from_camera[:3, :3] @ roll @ yaw)
    np.testing.assert_array_equal(turned[:3, 3], camera.world_from_camera[:3, 3])


@pytest.mark.parametrize(("drift", "message"), [
    ({"camera": "middle", "axis": "roll", "degrees": 1.0}, "no camera 'middle'"),
    ({"camera": "left", "axis": "tilt", "degrees": 1.0}, "must be one of roll, pitch, yaw"),
    ({"camera": "left", "axis": "roll", "degrees": 90.0}, "must be within"),
])
def test_a_bad_drift_is_refused_naming_the_key(drift: dict[str, object], message: str) -> None:
    with pytest.raises(ScenarioError, match=message):
        load_scenario("stereo_checkerboard", {"drifts": [drift]})
